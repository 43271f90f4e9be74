"""MAVLink FTP (read-only) served by the WIRIS emulator: the devguide's read sequence, burst reads, lost-ACK
resends, errors; our client's mftp:// download over UDP. (MAVSDK's mftp download: test_mavsdk_camera.py.)"""

from __future__ import annotations

import dataclasses
import struct
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

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
        with pytest.raises(LinkError, match="cannot open the file") as err:
            mavftp.download(link, 1, 100, "missing.xml", timeout_s=0.3)
        assert err.value.hint.startswith("file not found")


@pytest.mark.parametrize("case", ["path-too-long", "no-sessions", "too-large"])
def test_download_refusals_say_what_to_do(case):
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
        if case == "path-too-long":
            with pytest.raises(LinkError, match="path too long") as err:
                mavftp.download(link, 1, 100, "d/" * 120 + NAME, timeout_s=0.3)
            assert err.value.where.startswith("mftp d/d/") and "239 bytes" in err.value.hint
        elif case == "no-sessions":
            with emu.lock:
                emu.state.ftp.sessions.update(dict.fromkeys(range(mavftp.MAX_SESSIONS), NAME))
            with pytest.raises(LinkError, match=f"FTP error {mavftp.ERR_NO_SESSIONS}") as err:
                mavftp.download(link, 1, 100, NAME, timeout_s=0.3)
            assert "retry" in err.value.hint
        else:
            with pytest.raises(LinkError, match=f"file is {len(BODY)} bytes; the limit is 1000") as err:
                mavftp.download(link, 1, 100, NAME, timeout_s=0.3, max_bytes=1000)
            assert "names the camera definition" in err.value.hint


def test_downloads_after_a_refused_one_get_their_own_answers():
    # A server takes a request repeating its last seq for a resend and replays its last answer: downloads
    # that all started at seq 1 got the "file not found" of a wrong path again for the right one.
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
        for _ in range(3):
            with pytest.raises(LinkError, match="cannot open the file"):
                mavftp.download(link, 1, 100, "missing.xml", timeout_s=0.3)
            assert mavftp.download(link, 1, 100, NAME, timeout_s=0.3) == BODY


def test_a_refused_download_closes_its_session():
    # the size refusal came before the try whose finally sends TerminateSession: each one kept a session
    # of the camera's four until none was left (hidden while every download began at seq 1: the server
    # replayed the first OpenFileRO's answer instead of opening another)
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
        for _ in range(mavftp.MAX_SESSIONS + 1):
            with pytest.raises(LinkError, match="the limit is 1000"):
                mavftp.download(link, 1, 100, NAME, timeout_s=0.3, max_bytes=1000)
        assert mavftp.download(link, 1, 100, NAME, timeout_s=0.3) == BODY
        deadline = time.monotonic() + 2
        while time.monotonic() < deadline:
            with emu.lock:
                if not emu.state.ftp.sessions:
                    break
            time.sleep(0.02)
        with emu.lock:
            assert emu.state.ftp.sessions == {}


class _FaultyServer(mavftp.FtpServer):
    """A camera's FTP server with one fault: a file shorter than it announces, reads answered at the wrong
    offset, or reads that fail."""

    def __init__(self, mav, fault):
        super().__init__({NAME: BODY}, mav)
        self.fault = fault

    def _answer(self, req):
        out = super()._answer(req)
        if req.opcode == mavftp.OP_OPEN_RO and self.fault == "short":
            return [dataclasses.replace(out[0], data=struct.pack("<I", len(BODY) + 10))]
        if req.opcode == mavftp.OP_READ and self.fault == "offset":
            return [dataclasses.replace(out[0], offset=out[0].offset + 1)]
        if req.opcode == mavftp.OP_READ and self.fault == "fail":
            return [self._nak(req, mavftp.ERR_FAIL)]
        return out


@pytest.mark.parametrize("fault,message", [
    ("short", f"got {len(BODY)} of {len(BODY) + 10} bytes"),
    ("offset", "the camera answered a read at the wrong offset"),
    ("fail", f"read failed (FTP error {mavftp.ERR_FAIL})"),
], ids=["short", "offset", "fail"])
def test_a_camera_whose_ftp_server_misbehaves_gets_a_hint(fault, message):
    cam = Link("udpin:127.0.0.1:0", system=1, component=100, mav_type=mavlink2.MAV_TYPE_CAMERA, heartbeat_s=0.2)
    server = _FaultyServer(cam.mav, fault)
    cam.subscribe(lambda msg: [cam.send(r) for r in server.handle(msg)], "FILE_TRANSFER_PROTOCOL", to_me=True)
    try:
        with Link(f"udpout:127.0.0.1:{cam.local_port}", heartbeat_s=0.2) as link:
            with pytest.raises(LinkError) as err:
                mavftp.download(link, 1, 100, NAME, timeout_s=0.5)
    finally:
        cam.close()
    assert err.value.message == message and err.value.where == f"mftp {NAME} on component 100"
    assert "firmware" in err.value.hint


@pytest.mark.parametrize("body,message,hint", [
    (b"<html><body>login</body></html>", "root element is <html>, not <mavlinkcamera>", "not a camera definition"),
    (b"\xfd7zXZ\x00 not really xz", "broken xz stream", ".xml.xz"),
    (b"<mavlinkcamera><definition", "", "broken definition"),
], ids=["html-page", "broken-xz", "unclosed"])
def test_a_definition_the_camera_serves_that_cannot_be_read_says_what_to_do(body, message, hint):
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
        with emu.lock:
            emu.state.ftp.files[NAME] = body
        cam = CameraClient(link, timeout_s=0.5)
        with pytest.raises(LinkError, match="the camera's definition cannot be read: ") as err:
            cam.definition(cam.information())
    assert message in err.value.message and "hint" not in err.value.message   # the hint travels as the hint
    assert err.value.where == f"mftp://{NAME}" and hint in err.value.hint
