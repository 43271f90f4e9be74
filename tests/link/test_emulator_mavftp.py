"""MAVLink FTP (read-only) served by the WIRIS emulator: the devguide's read sequence, bounded burst reads,
lost-ACK resends, errors, sessions that expire or are reclaimed; our client's mftp:// download over UDP, its
TerminateSession retried; pymavlink's burst client. (MAVSDK's mftp download: test_mavsdk_camera.py.)"""

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


@pytest.mark.parametrize("offset,packets", [(100, mavftp.ServerLimits().burst_packets), (len(BODY) - 300, 2)],
                         ids=["a-burst-of-the-middle", "the-last-burst"])
def test_burst_read_streams_a_burst(cam, offset, packets):
    g = Wire()
    (opened,) = _answers(cam, _req(g, 1, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))
    burst = _answers(cam, _req(g, 2, mavftp.OP_BURST_READ, session=opened.session, offset=offset))
    assert len(burst) == packets
    assert b"".join(p.data for p in burst) == BODY[offset:offset + packets * mavftp.DATA_MAX]
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
                emu.state.ftp.sessions.update({i: mavftp.Session(NAME, time.monotonic())   # all in use just now
                                               for i in range(mavftp.MAX_SESSIONS)})
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

    def _answer(self, req, now):
        out = super()._answer(req, now)
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
    cam.subscribe(lambda msg: [cam.send(r) for r in server.handle(msg, time.monotonic())], "FILE_TRANSFER_PROTOCOL", to_me=True)
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


# -- sessions that expire, a TerminateSession that is retried, bursts that are bounded ---------------------

class _Clock:
    """The camera's clock, moved by the test (no sleeps)."""

    def __init__(self) -> None:
        self.now = 0.0


class _ServedCamera:
    """A WIRIS camera state on a real UDP Link, its FTP server on the test's clock; `lose_terminates`
    TerminateSession requests are lost on the way in, as on a radio."""

    def __init__(self, clock: _Clock, lose_terminates: int = 0) -> None:
        self.state = new_wiris(CAM)
        self.clock = clock
        self.lose_terminates = lose_terminates
        self.terminates_heard = 0
        self.link = Link("udpin:127.0.0.1:0", system=1, component=100, mav_type=mavlink2.MAV_TYPE_CAMERA,
                         heartbeat_s=0.2)
        self.link.subscribe(self._serve, "FILE_TRANSFER_PROTOCOL", to_me=True)

    def _serve(self, msg) -> None:
        if mavftp.Packet.unpack(msg.payload).opcode == mavftp.OP_TERMINATE:
            self.terminates_heard += 1
            if self.lose_terminates > 0:
                self.lose_terminates -= 1
                return
        for reply in self.state.handle(msg, self.clock.now):
            self.link.send(reply)

    def __enter__(self) -> "_ServedCamera":
        return self

    def __exit__(self, *exc) -> None:
        self.link.close()


def _ask(link, pkt):
    """One FTP request over the link, and its answer."""
    with link.inbox("FILE_TRANSFER_PROTOCOL", src_component=100,
                    predicate=lambda m: mavftp.Packet.unpack(m.payload).seq == pkt.seq + 1) as box:
        link.send(link.mav.file_transfer_protocol_encode(0, 1, 100, pkt.pack()))
        got = box.get(5.0)
    assert got is not None
    return mavftp.Packet.unpack(got.payload)


def _open_and_walk_away(link, seq):
    """OpenFileRO as a client that then vanishes (its TerminateSession never arrives)."""
    return _ask(link, mavftp.Packet(seq, 0, mavftp.OP_OPEN_RO, len(NAME), 0, 0, 0, NAME.encode()))


def test_sessions_left_open_are_reclaimed_then_expire():
    limits = mavftp.ServerLimits()
    clock = _Clock()
    with _ServedCamera(clock) as cam, Link(f"udpout:127.0.0.1:{cam.link.local_port}", heartbeat_s=0.2) as link:
        opened = [_open_and_walk_away(link, 100 + 10 * i) for i in range(limits.max_sessions)]
        assert [p.opcode for p in opened] == [mavftp.OP_ACK] * limits.max_sessions
        clock.now = limits.reclaim_idle_s / 2          # the four may still be in use: refused, and says so
        with pytest.raises(LinkError, match=f"FTP error {mavftp.ERR_NO_SESSIONS}"):
            mavftp.download(link, 1, 100, NAME, timeout_s=0.5)
        clock.now = limits.reclaim_idle_s + 0.1        # now idle long enough: the oldest one is handed over
        newcomer = _open_and_walk_away(link, 500)
        assert newcomer.opcode == mavftp.OP_ACK and newcomer.session != opened[0].session
        # the first client's session id is not the newcomer's: its next read is refused, not served
        stale = _ask(link, mavftp.Packet(7, opened[0].session, mavftp.OP_READ, 239, 0, 0, 0, b""))
        assert stale.opcode == mavftp.OP_NAK and stale.data[0] == mavftp.ERR_INVALID_SESSION
        assert mavftp.download(link, 1, 100, NAME, timeout_s=0.5) == BODY     # reclaims the next oldest
        assert len(cam.state.ftp.sessions) == limits.max_sessions - 1
        clock.now += limits.expire_idle_s + 0.1         # and the rest expire on their own
        assert mavftp.download(link, 1, 100, NAME, timeout_s=0.5) == BODY
        assert cam.state.ftp.sessions == {}


def test_a_session_in_use_is_not_reclaimed():
    limits = mavftp.ServerLimits()
    cam, g = new_wiris(CAM), Wire()
    sessions = [_answers(cam, _req(g, 10 * i, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()))[0].session
                for i in range(limits.max_sessions)]
    now = limits.reclaim_idle_s + 1
    for i, s in enumerate(sessions[1:]):      # every session but the first is read from just now
        (r,) = cam.handle(_req(g, 100 + 2 * i, mavftp.OP_READ, session=s, size=239), now)
        assert mavftp.Packet.unpack(r.payload).opcode == mavftp.OP_ACK
    (opened,) = [mavftp.Packet.unpack(m.payload)
                 for m in cam.handle(_req(g, 200, mavftp.OP_OPEN_RO, size=len(NAME), data=NAME.encode()), now)]
    assert opened.opcode == mavftp.OP_ACK
    assert sessions[0] not in cam.ftp.sessions and set(sessions[1:]) <= set(cam.ftp.sessions)


@pytest.mark.parametrize("case", ["download", "refused-download"])
def test_a_lost_terminate_session_is_sent_again(case):
    clock = _Clock()
    with _ServedCamera(clock, lose_terminates=1) as cam, \
            Link(f"udpout:127.0.0.1:{cam.link.local_port}", heartbeat_s=0.2) as link:
        if case == "download":
            assert mavftp.download(link, 1, 100, NAME, timeout_s=0.3) == BODY
        else:
            with pytest.raises(LinkError, match="the limit is 1000"):
                mavftp.download(link, 1, 100, NAME, timeout_s=0.3, max_bytes=1000)
        assert cam.lose_terminates == 0 and cam.terminates_heard == 2
        assert cam.state.ftp.sessions == {}


def test_terminate_session_tries_are_bounded():
    clock = _Clock()
    with _ServedCamera(clock, lose_terminates=100) as cam, \
            Link(f"udpout:127.0.0.1:{cam.link.local_port}", heartbeat_s=0.2) as link:
        assert mavftp.download(link, 1, 100, NAME, timeout_s=0.2) == BODY   # the data is good: no error
        for _ in range(100):                       # the last try may still be on its way (a loaded machine)
            if cam.terminates_heard >= mavftp.TERMINATE_TRIES:
                break
            time.sleep(0.05)
        assert cam.terminates_heard == mavftp.TERMINATE_TRIES
        assert len(cam.state.ftp.sessions) == 1                            # left for the server's expiry


def _raw_exchange(sock, port, enc, parser, pkt, *, max_datagrams=1000):
    """Send one FTP request as one UDP datagram; the FTP answers that come back (until one with
    burst_complete, a NAK, or a quiet second) with the byte counts of both directions."""
    request = enc.file_transfer_protocol_encode(0, 1, 100, pkt.pack()).pack(enc)
    enc.seq = (enc.seq + 1) % 256
    sock.sendto(request, ("127.0.0.1", port))
    answers, answer_bytes = [], 0
    while len(answers) < max_datagrams:
        try:
            data = sock.recv(65535)
        except TimeoutError:
            break
        ftp = [m for m in parser.parse_buffer(data) or [] if m.get_type() == "FILE_TRANSFER_PROTOCOL"]
        if not ftp:
            continue                                   # the camera's heartbeats
        answer_bytes += len(data)
        answers += [mavftp.Packet.unpack(m.payload) for m in ftp]
        last = answers[-1]
        if pkt.opcode != mavftp.OP_BURST_READ or last.burst_complete or last.opcode == mavftp.OP_NAK:
            break
    return answers, len(request), answer_bytes


def test_a_burst_read_answers_a_bounded_burst_and_the_file_still_arrives():
    # One BurstReadFile datagram used to bring back the whole rest of the file at once: for this
    # definition, from offset 0, 126 datagrams (33394 bytes) for a request of 19 bytes, an amplification of
    # 1758. ArduPilot and PX4 send big bursts too, but paced to the link (see mavftp.ServerLimits).
    import socket

    limits = mavftp.ServerLimits()
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(1.0)
        enc = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
        parser = mavlink2.MAVLink(None)
        port = emu.link.local_port
        (opened,), _, _ = _raw_exchange(sock, port, enc, parser,
                                        mavftp.Packet(1, 0, mavftp.OP_OPEN_RO, len(NAME), 0, 0, 0, NAME.encode()))
        assert opened.opcode == mavftp.OP_ACK
        got, seq, ratios = bytearray(), 10, []
        for _ in range(len(BODY)):                     # bounded: each burst brings at least one byte
            burst, sent, received = _raw_exchange(sock, port, enc, parser, mavftp.Packet(
                seq, opened.session, mavftp.OP_BURST_READ, 0, 0, 0, len(got), b""))
            seq += len(burst) + 1
            assert burst and burst[0].opcode == mavftp.OP_ACK
            assert len(burst) <= limits.burst_packets and burst[-1].burst_complete == 1
            assert [p.offset for p in burst] == list(range(len(got), len(got) + DATA * len(burst), DATA))
            got += b"".join(p.data for p in burst)
            assert received <= limits.burst_packets * FRAME_MAX
            ratios.append(received / sent)
            if len(got) >= len(BODY):
                break
    assert bytes(got) == BODY
    worst = max(ratios)
    print(f"burst amplification: at most {worst:.0f}x ({len(ratios)} bursts for {len(BODY)} bytes)")
    assert worst < 150                                 # 8 datagrams of 266 bytes per 19-byte request: 112x


def test_pymavlink_mavftp_reads_the_definition_through_bounded_bursts():
    # A real burst client (pymavlink's MAVFTP, MAVProxy's ftp module) asks for the next burst where one ends
    from pymavlink import mavutil
    from pymavlink.mavftp import MAVFTP

    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu:
        bursts = []
        emu.link.subscribe(lambda m: bursts.append(m) if mavftp.Packet.unpack(m.payload).opcode
                           == mavftp.OP_BURST_READ else None, "FILE_TRANSFER_PROTOCOL")
        gcs = mavutil.mavlink_connection(f"udpout:127.0.0.1:{emu.link.local_port}", source_system=255,
                                         source_component=190)
        try:
            got = {}
            ftp = MAVFTP(gcs, 1, 100)
            ftp.cmd_get([NAME], callback=lambda fh: got.setdefault("data", fh.read() if fh else None))
            ret = ftp.process_ftp_reply("OpenFileRO", timeout=30)
        finally:
            gcs.close()
        assert ret.error_code == 0 and got.get("data") == BODY
        assert len(bursts) >= len(BODY) // (DATA * mavftp.ServerLimits().burst_packets)
        with emu.lock:
            assert emu.state.ftp.sessions == {}          # and it closed its session


DATA = mavftp.DATA_MAX
FRAME_MAX = 280          # the longest MAVLink 2 frame (255-byte payload, signed)
