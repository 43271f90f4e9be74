"""MAVLink FTP (read-only) served by the WIRIS emulator: the devguide's read sequence, burst reads, lost-ACK
resends, errors; our client's mftp:// download over UDP. (MAVSDK's mftp download: test_mavsdk_camera.py.)"""

from __future__ import annotations

import struct

import pytest

from cdf.catalogue import catalogue
from cdf.generate import definition_file_name, definition_xml
from emu_wire import Wire
from wiris_tools import mavftp
from wiris_tools.camera_client import CameraClient
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.emulate.wiris import new_wiris
from wiris_tools.errors import LinkError
from wiris_tools.link import Link

CAM = catalogue().get("wiris-pro")
NAME = definition_file_name(CAM)
BODY = definition_xml(CAM)


def _req(g, seq, opcode, *, session=0, offset=0, size=0, data=b"", target=100):
    pkt = mavftp.Packet(seq, session, opcode, size, 0, 0, offset, data)
    return g(g.mav.file_transfer_protocol_encode(0, 1, target, pkt.pack()))


def _answers(state, msg):
    return [mavftp.Packet.unpack(o.payload) for o in state.handle(msg, 0.0)]


@pytest.fixture
def cam():
    return new_wiris(CAM)


def test_read_sequence_and_eof(cam):
    g = Wire()
    for path in (NAME, "/" + NAME):
        (opened,) = _answers(cam, _req(g, 10, mavftp.OP_OPEN_RO, size=len(path), data=path.encode()))
        assert (opened.opcode, opened.req_opcode, opened.seq) == (mavftp.OP_ACK, mavftp.OP_OPEN_RO, 11)
        assert struct.unpack("<I", opened.data)[0] == len(BODY)
        got = bytearray()
        seq = 12
        while True:
            (r,) = _answers(cam, _req(g, seq, mavftp.OP_READ, session=opened.session, offset=len(got), size=239))
            seq += 2
            if r.opcode == mavftp.OP_NAK:
                assert r.data[0] == mavftp.ERR_EOF
                break
            got += r.data
        assert bytes(got) == BODY
        (t,) = _answers(cam, _req(g, seq, mavftp.OP_TERMINATE, session=opened.session))
        assert t.opcode == mavftp.OP_ACK


def test_burst_read_streams_the_rest(cam):
    g = Wire()
    (opened,) = _answers(cam, _req(g, 1, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))
    burst = _answers(cam, _req(g, 2, mavftp.OP_BURST_READ, session=opened.session, offset=100))
    assert b"".join(p.data for p in burst) == BODY[100:]
    assert [p.burst_complete for p in burst] == [0] * (len(burst) - 1) + [1]
    assert [p.seq for p in burst] == list(range(3, 3 + len(burst)))


def test_resent_request_gets_the_same_answer(cam):
    g = Wire()
    first = _answers(cam, _req(g, 5, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))
    again = _answers(cam, _req(g, 5, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))
    assert first == again and len(cam.ftp.sessions) == 1      # no second session for a lost ACK


@pytest.mark.parametrize("opcode,kw,error", [
    (mavftp.OP_OPEN_RO, {"size": 7, "data": b"/etc/pw"}, mavftp.ERR_FILE_NOT_FOUND),
    (mavftp.OP_READ, {"session": 3, "size": 10}, mavftp.ERR_INVALID_SESSION),
    (mavftp.OP_TERMINATE, {"session": 9}, mavftp.ERR_INVALID_SESSION),
    (7, {"size": 3, "data": b"abc"}, mavftp.ERR_UNKNOWN_COMMAND),            # WriteFile: read-only server
])
def test_errors(cam, opcode, kw, error):
    (r,) = _answers(cam, _req(Wire(), 1, opcode, **kw))
    assert r.opcode == mavftp.OP_NAK and r.data[0] == error


def test_sessions_run_out(cam):
    g = Wire()
    answers = [_answers(cam, _req(g, 2 * i, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))[0]
               for i in range(mavftp.MAX_SESSIONS + 1)]
    assert answers[-1].opcode == mavftp.OP_NAK and answers[-1].data[0] == mavftp.ERR_NO_SESSIONS
    _answers(cam, _req(g, 99, mavftp.OP_RESET))
    assert cam.ftp.sessions == {}


def test_ftp_to_another_component_is_ignored(cam):
    assert cam.handle(_req(Wire(), 1, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode(), target=101), 0) == []


def test_client_downloads_the_mftp_definition():
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
        cam = CameraClient(link, timeout_s=0.5)
        info = cam.information()
        assert info.definition_uri == f"mftp://{NAME}"
        loaded = cam.definition(info)
        assert loaded.data == BODY and loaded.report.valid
        with pytest.raises(LinkError, match="cannot open the file"):
            mavftp.download(link, 1, 100, "missing.xml", timeout_s=0.3)
