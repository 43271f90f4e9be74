"""Link over real UDP sockets on 127.0.0.1: heartbeats, filters, MAVLink 1, the command protocol
(ACK matching, IN_PROGRESS, retries with confirmation, error results) and MAVLink 2 signing."""

from __future__ import annotations

import math
import socket
import threading
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from raw_peers import timed_call
from wiris_tools.errors import CommandRefused, LinkError, NoAnswer
from wiris_tools.link import Link, command_name
from wiris_tools.signing import key_from_text, load_signing_key


def pair(*, a_kwargs=None, b_kwargs=None):
    """A camera-like side bound to a free port and a GCS that sends to it."""
    a = Link("udpin:127.0.0.1:0", **({"system": 1, "component": 100, "mav_type": mavlink2.MAV_TYPE_CAMERA,
                                      "heartbeat_s": 0.2} | (a_kwargs or {})))
    b = Link(f"udpout:127.0.0.1:{a.local_port}", **({"heartbeat_s": 0.2} | (b_kwargs or {})))
    return a, b


@pytest.fixture
def links():
    a, b = pair()
    yield a, b
    b.close()
    a.close()


class Responder:
    """Answers COMMAND_LONG on link `a` with scripted results; records the confirmations seen."""

    def __init__(self, link: Link, script: list[list[tuple[int, int]]], from_component: int | None = None):
        self.link = link
        self.script = list(script)
        self.confirmations: list[int] = []
        self.params: list[tuple] = []
        self.sub = link.subscribe(self.on_cmd, "COMMAND_LONG", to_me=True)

    def on_cmd(self, msg):
        self.confirmations.append(msg.confirmation)
        self.params.append((msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7))
        answers = self.script.pop(0) if self.script else []
        for result, prog in answers:
            self.link.send(self.link.mav.command_ack_encode(msg.command, result, prog, 0,
                                                            msg.get_srcSystem(), msg.get_srcComponent()))


def test_heartbeats_carry_our_type_and_ids(links):
    a, b = links
    hb = b.wait_heartbeat(timeout=3, component=100)
    assert (hb.get_srcSystem(), hb.get_srcComponent(), hb.type) == (1, 100, mavlink2.MAV_TYPE_CAMERA)
    hb = a.wait_heartbeat(timeout=3, system=255)
    assert (hb.get_srcComponent(), hb.type) == (mavlink2.MAV_COMP_ID_MISSIONPLANNER, mavlink2.MAV_TYPE_GCS)


def test_inbox_filters_by_type_source_and_target(links):
    a, b = links
    b.wait_heartbeat(timeout=3)
    with a.inbox("COMMAND_LONG", src_system=255, to_me=True) as box:
        b.send(b.mav.command_long_encode(7, 100, 1, 0, 0, 0, 0, 0, 0, 0, 0))   # another system
        b.send(b.mav.command_long_encode(1, 101, 2, 0, 0, 0, 0, 0, 0, 0, 0))   # another component
        b.send(b.mav.param_request_list_encode(1, 100))                          # another type
        b.send(b.mav.command_long_encode(0, 0, 3, 0, 0, 0, 0, 0, 0, 0, 0))     # broadcast
        b.send(b.mav.command_long_encode(1, 100, 4, 0, 0, 0, 0, 0, 0, 0, 0))   # us
        got = [box.get(1.0), box.get(1.0), box.get(0.3)]
    assert [m.command for m in got[:2]] == [3, 4] and got[2] is None


def test_mavlink1_link_sends_v1_frames_and_reads_v2():
    a, b = pair(a_kwargs={"mavlink1": True})
    try:
        hb = b.wait_heartbeat(timeout=3, component=100)
        assert hb.get_msgbuf()[0] == 0xFE                # MAVLink 1 start byte
        hb = a.wait_heartbeat(timeout=3, system=255)
        assert hb.get_msgbuf()[0] == 0xFD                # the GCS talks MAVLink 2; still understood
    finally:
        b.close()
        a.close()


def test_command_accepted_with_nan_params(links):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    r = Responder(a, [[(mavlink2.MAV_RESULT_ACCEPTED, 0)]])
    ack = b.command_long(1, 100, mavlink2.MAV_CMD_IMAGE_START_CAPTURE, [0, 2.5, 1, math.nan], timeout=1)
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    assert r.params[0][:3] == (0, 2.5, 1) and math.isnan(r.params[0][3]) and r.params[0][4:] == (0, 0, 0)


def test_in_progress_keeps_waiting_and_reports_progress(links):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    r = Responder(a, [[(mavlink2.MAV_RESULT_IN_PROGRESS, 10), (mavlink2.MAV_RESULT_IN_PROGRESS, 60),
                       (mavlink2.MAV_RESULT_ACCEPTED, 100)]])
    seen: list[int] = []
    b.command_long(1, 100, mavlink2.MAV_CMD_STORAGE_FORMAT, [1, 1], timeout=1, progress=seen.append)
    assert seen == [10, 60] and r.confirmations == [0]


def test_a_target_that_reports_progress_for_ever_is_given_up_on(links):
    """IN_PROGRESS extended the wait by one timeout per report without end: a target repeating it kept the
    caller waiting for ever. The wait is capped at IN_PROGRESS_TIMEOUTS timeouts after the first report."""
    from wiris_tools.link import IN_PROGRESS_TIMEOUTS

    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    stop = threading.Event()
    asked = threading.Event()

    def busy():                                    # "still formatting", every 50 ms, once asked
        asked.wait(5)
        while not stop.is_set():
            a.send(a.mav.command_ack_encode(mavlink2.MAV_CMD_STORAGE_FORMAT, mavlink2.MAV_RESULT_IN_PROGRESS, 50,
                                            0, 255, 190))
            stop.wait(0.05)

    a.subscribe(lambda msg: asked.set(), "COMMAND_LONG", to_me=True)
    reporter = threading.Thread(target=busy, daemon=True)
    reporter.start()
    progress: list[int] = []
    call = timed_call(lambda: b.command_long(1, 100, mavlink2.MAV_CMD_STORAGE_FORMAT, [1, 1], timeout=0.1,
                                             retries=1, progress=progress.append),
                      IN_PROGRESS_TIMEOUTS * 0.1 + 5)
    stop.set()
    reporter.join(2)
    assert call.finished, "still waiting on a target that only reports progress"
    err = call.error
    assert "MAV_CMD_STORAGE_FORMAT" in str(err) and "IN_PROGRESS" in err.message and err.hint
    assert IN_PROGRESS_TIMEOUTS * 0.1 <= call.waited < IN_PROGRESS_TIMEOUTS * 0.1 + 3
    assert progress[:1] == [50]


def test_retries_increment_confirmation_then_fail_naming_command(links):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    r = Responder(a, [[], [], [(mavlink2.MAV_RESULT_ACCEPTED, 0)]])
    b.command_long(1, 100, mavlink2.MAV_CMD_REQUEST_CAMERA_INFORMATION, [1], timeout=0.3, retries=3)
    assert r.confirmations == [0, 1, 2]
    r2 = Responder(a, [[]] * 10)
    a.unsubscribe(r.sub)
    with pytest.raises(LinkError) as err:
        b.command_long(1, 100, mavlink2.MAV_CMD_REQUEST_CAMERA_INFORMATION, [1], timeout=0.2, retries=2)
    assert r2.confirmations == [0, 1, 2]
    text = str(err.value)
    assert "MAV_CMD_REQUEST_CAMERA_INFORMATION" in text and "3 tries" in text and "component 100" in text
    assert err.value.hint


@pytest.mark.parametrize("result", [mavlink2.MAV_RESULT_DENIED, mavlink2.MAV_RESULT_UNSUPPORTED,
                                    mavlink2.MAV_RESULT_FAILED, mavlink2.MAV_RESULT_TEMPORARILY_REJECTED,
                                    mavlink2.MAV_RESULT_COMMAND_INT_ONLY])
def test_error_results_raise_with_their_names(links, result):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    Responder(a, [[(result, 0)]])
    with pytest.raises(LinkError) as err:
        b.command_long(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, [0, 1], timeout=1, retries=0)
    assert mavlink2.enums["MAV_RESULT"][result].name in str(err.value)
    assert "MAV_CMD_SET_CAMERA_MODE" in str(err.value)
    assert err.value.hint


@pytest.mark.parametrize("result", [6, 200])   # MAV_RESULT_CANCELLED (newer common.xml), a made-up one
def test_a_result_the_dialect_does_not_define_still_gets_a_hint(links, result):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    Responder(a, [[(result, 0)]])
    with pytest.raises(LinkError, match=f"answered MAV_RESULT {result}") as err:
        b.command_long(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, [0, 1], timeout=1, retries=0)
    assert "firmware" in err.value.hint


@pytest.mark.parametrize("result", [mavlink2.MAV_RESULT_DENIED, mavlink2.MAV_RESULT_UNSUPPORTED, 200])
def test_a_refusal_carries_its_result_and_command_as_values(links, result):
    """A caller that tells a refusal from silence (the camera client: UNSUPPORTED means "try the older
    request") reads the result from the error, not from its text."""
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    Responder(a, [[(result, 0)]])
    with pytest.raises(CommandRefused) as err:
        b.command_long(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, [0, 1], timeout=1, retries=0)
    assert (err.value.result, err.value.command) == (result, mavlink2.MAV_CMD_SET_CAMERA_MODE)


def test_silence_is_no_answer_not_a_refusal(links):
    _a, b = links
    b.wait_heartbeat(timeout=3, component=100)
    with pytest.raises(NoAnswer) as err:
        b.command_long(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, [0, 1], timeout=0.2, retries=1)
    assert err.value.command == mavlink2.MAV_CMD_SET_CAMERA_MODE and not isinstance(err.value, CommandRefused)
    assert err.value.message.startswith("no answer to MAV_CMD_SET_CAMERA_MODE after 2 tries")


def test_more_than_seven_params_is_refused_with_a_hint(links):
    _a, b = links
    for call in (lambda: b.command_long(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, [0] * 8),
                 lambda: b.command_int(1, 100, mavlink2.MAV_CMD_SET_CAMERA_MODE, params=[0] * 8)):
        with pytest.raises(LinkError, match="takes 7 params, got 8") as err:
            call()
        assert "please report it" in err.value.hint


def test_ack_for_another_command_or_from_another_component_is_ignored(links):
    a, b = links
    b.wait_heartbeat(timeout=3, component=100)

    def wrong_then_right(msg):
        a.send(a.mav.command_ack_encode(msg.command + 1, mavlink2.MAV_RESULT_DENIED, 0, 0, 255, 190))
        a.send(a.mav.command_ack_encode(msg.command, mavlink2.MAV_RESULT_DENIED, 0, 0, 255, 77))
        a.send(a.mav.command_ack_encode(msg.command, mavlink2.MAV_RESULT_ACCEPTED, 0, 0, 255, 190))

    a.subscribe(wrong_then_right, "COMMAND_LONG")
    ack = b.command_long(1, 100, mavlink2.MAV_CMD_VIDEO_START_CAPTURE, [0, 1], timeout=1, retries=0)
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED


def test_command_name_falls_back_to_number():
    assert command_name(mavlink2.MAV_CMD_IMAGE_START_CAPTURE) == "MAV_CMD_IMAGE_START_CAPTURE"
    assert command_name(65000) == "MAV_CMD 65000"


def test_bad_connection_strings_are_link_errors():
    with pytest.raises(LinkError) as err:
        Link("udpin:nohostport", heartbeat_s=0)
    assert "connection string" in str(err.value)
    with pytest.raises(LinkError) as err:
        Link("udpin:127.0.0.1:0", system=0, heartbeat_s=0)
    assert err.value.hint


@pytest.mark.parametrize("url", ["udpin:127.0.0.1:99999", "udpout:127.0.0.1:65536", "tcp:127.0.0.1:70000"])
def test_a_port_over_65535_is_refused_before_anything_runs(url):
    # pymavlink takes it: udpout then fails in the heartbeat thread at its first send, tcp in a retry loop
    with pytest.raises(LinkError, match="is not 0-65535") as err:
        Link(url, heartbeat_s=1)
    assert err.value.hint


def test_send_after_close_is_a_link_error():
    a = Link("udpin:127.0.0.1:0", heartbeat_s=0)
    a.close()
    with pytest.raises(LinkError) as err:
        a.send(a.mav.heartbeat_encode(6, 8, 0, 0, 4))
    assert err.value.where == "udpin:127.0.0.1:0" and "please report it" in err.value.hint


def test_a_connection_that_cannot_be_written_says_what_to_check(tmp_path):
    """pymavlink opens a plain file given as the connection string as a telemetry log, for reading only:
    sending to it fails (as writing to a serial device that was unplugged does)."""
    log = tmp_path / "flight.tlog"
    log.write_bytes(b"")
    with Link(str(log), heartbeat_s=0) as link:
        with pytest.raises(LinkError, match="cannot send HEARTBEAT") as err:
            link.send_heartbeat()
    assert err.value.where == str(log) and "--connect" in err.value.hint


# -- signing ---------------------------------------------------------------------------------------

KEY = bytes(range(32))


def test_signed_links_talk_and_sign_everything():
    a, b = pair(a_kwargs={"signing_key": KEY}, b_kwargs={"signing_key": KEY})
    try:
        hb = b.wait_heartbeat(timeout=3, component=100)
        assert hb.get_signed()
        Responder(a, [[(mavlink2.MAV_RESULT_ACCEPTED, 0)]])
        assert b.command_long(1, 100, mavlink2.MAV_CMD_REQUEST_CAMERA_SETTINGS, [1], timeout=1).result == 0
        assert a.stats["rejected_signature"] == 0
    finally:
        b.close()
        a.close()


@pytest.mark.parametrize("gcs_kwargs", [{}, {"signing_key": bytes(32)}, {"mavlink1": True}],
                         ids=["unsigned", "wrong-key", "mavlink1"])
def test_signed_link_drops_unsigned_and_wrongly_signed(gcs_kwargs):
    a, b = pair(a_kwargs={"signing_key": KEY}, b_kwargs=gcs_kwargs | {"heartbeat_s": 0.05})
    try:
        Responder(a, [[(mavlink2.MAV_RESULT_ACCEPTED, 0)]] * 5)
        with pytest.raises(LinkError):
            b.command_long(1, 100, mavlink2.MAV_CMD_REQUEST_CAMERA_SETTINGS, [1], timeout=0.2, retries=1)
        assert a.stats["rejected_signature"] >= 2
        assert (255, 190) not in a.heartbeats()
    finally:
        b.close()
        a.close()


def signed_heartbeat(timestamp: int, *, system: int = 7, key: bytes = KEY) -> bytes:
    """A HEARTBEAT frame from `system` (component 1, signing link 0), signed with `key`, dated `timestamp`."""
    mav = mavlink2.MAVLink(None, srcSystem=system, srcComponent=1)
    mav.signing.secret_key, mav.signing.sign_outgoing, mav.signing.timestamp = key, True, timestamp
    return bytes(mav.heartbeat_encode(mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0,
                                      mavlink2.MAV_STATE_ACTIVE).pack(mav))


def verdicts(frames: list[bytes]) -> list[bool]:
    """Send each frame in turn to a fresh signed Link over UDP: was it taken (True) or rejected (False)?"""
    out = []
    with Link("udpin:127.0.0.1:0", signing_key=KEY, heartbeat_s=0) as victim, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for frame in frames:
            before = victim.stats
            sock.sendto(frame, ("127.0.0.1", victim.local_port))
            for _ in range(500):
                now = victim.stats
                if now["received"] > before["received"] or now["rejected_signature"] > before["rejected_signature"]:
                    break
                time.sleep(0.01)
            else:
                raise AssertionError("the link never read the frame")
            out.append(now["received"] > before["received"])
    return out


def test_signed_streams_follow_the_spec_timestamp_rules():
    from wiris_tools.signing import TIMESTAMP_UNITS_PER_S, signing_timestamp
    now = signing_timestamp(time.time())
    minute, hour = 60 * TIMESTAMP_UNITS_PER_S, 3600 * TIMESTAMP_UNITS_PER_S
    first = signed_heartbeat(now)
    # a replay, and an older frame, on a stream already heard are refused; a later one is taken
    assert verdicts([first, first, signed_heartbeat(now - 1), signed_heartbeat(now + 1)]) == [True, False, False, True]
    # a new stream may start up to a minute behind our clock (a recording replayed later may not) ...
    assert verdicts([signed_heartbeat(now - 2 * minute), signed_heartbeat(now - minute // 2)]) == [False, True]
    # ... and, correctly signed, any time ahead of it: peers adopt the highest timestamp they verify
    assert verdicts([signed_heartbeat(now + hour), signed_heartbeat(now + hour - 1)]) == [True, False]


def test_a_badly_signed_frame_does_not_move_its_stream_on():
    from wiris_tools.signing import TIMESTAMP_UNITS_PER_S, signing_timestamp
    now = signing_timestamp(time.time())
    nobody = bytearray(signed_heartbeat(2**48 - 1))
    nobody[-6:] = bytes(6)   # no key at all
    wrong = signed_heartbeat(now + 10 * TIMESTAMP_UNITS_PER_S, key=bytes(32))
    # before the first real frame of the stream, and between two of them
    assert verdicts([bytes(nobody), wrong, signed_heartbeat(now), bytes(nobody), wrong,
                     signed_heartbeat(now + 1)]) == [False, False, True, False, False, True]


def test_mavlink1_cannot_be_signed():
    with pytest.raises(LinkError, match="MAVLink 1 cannot be signed") as err:
        Link("udpin:127.0.0.1:0", mavlink1=True, signing_key=KEY, heartbeat_s=0)
    assert err.value.hint


@pytest.mark.parametrize("key", [b"", KEY[:16], KEY + b"\0"], ids=["empty", "16-bytes", "33-bytes"])
def test_a_signing_key_of_another_length_is_refused_with_a_hint(key):
    with pytest.raises(LinkError, match="must be 32 bytes") as err:
        Link("udpin:127.0.0.1:0", signing_key=key, heartbeat_s=0)
    assert err.value.where == "udpin:127.0.0.1:0" and "load_signing_key" in err.value.hint


def test_key_file_hex_and_passphrase_match_mavproxy(tmp_path):
    from MAVProxy.modules.mavproxy_signing import SigningModule

    hexfile = tmp_path / "key.hex"
    hexfile.write_text(KEY.hex().upper() + "\n")
    assert load_signing_key(hexfile) == KEY
    phrase = tmp_path / "phrase.txt"
    phrase.write_text("correct horse battery staple\n")
    # MAVProxy's `signing setup PASSPHRASE` key derivation, called on the real module.
    assert load_signing_key(phrase) == SigningModule.passphrase_to_key(None, "correct horse battery staple")


@pytest.mark.parametrize("content", [b"", b"   \n", b"\xff\xfe\x00", b"x" * 5000])
def test_bad_key_files_are_link_errors(tmp_path, content):
    f = tmp_path / "k"
    f.write_bytes(content)
    with pytest.raises(LinkError) as err:
        load_signing_key(f)
    assert err.value.where == str(f) and err.value.hint
    with pytest.raises(LinkError) as err:
        load_signing_key(tmp_path / "missing")
    assert err.value.hint
    assert len(key_from_text("a")) == 32


def test_callbacks_run_concurrently_with_sends(links):
    """Thread-safe send: many threads sending at once produce intact frames (no CRC failures)."""
    a, b = links
    with a.inbox("STATUSTEXT") as box:
        def spam(n):
            for i in range(50):
                b.send(b.mav.statustext_encode(6, f"t{n}-{i}".encode()))
        threads = [threading.Thread(target=spam, args=(n,)) for n in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        got = [box.get(2.0) for _ in range(200)]
    assert all(m is not None for m in got)
    assert a.stats["bad"] == 0


def test_an_interrupted_wait_heartbeat_leaves_the_link_working():
    """wait_heartbeat waited on a threading.Condition whose lock the receive thread takes for every
    HEARTBEAT: a Ctrl-C landing just after the main thread took it left it held, and the link stopped
    delivering anything. The interrupt is raised at each place of a wait where Python checks for signals,
    in turn; afterwards the peer's next HEARTBEAT must still arrive."""
    from interrupts import InterruptAt

    link, peer = pair(a_kwargs={"heartbeat_s": 0}, b_kwargs={"heartbeat_s": 0.02})  # the peer beats at 50 Hz
    try:
        n = 0
        while True:
            with InterruptAt(n) as at:
                try:
                    link.wait_heartbeat(0.05, system=42)  # nobody is system 42: the wait runs its course
                except KeyboardInterrupt:
                    assert at.fired
                except LinkError:
                    assert not at.fired
            heard = link.recv("HEARTBEAT", timeout=5)
            assert heard is not None, f"link dead after an interrupt at signal check {n}"
            if not at.fired:
                break
            n += 1
        assert n > 5  # the wait passed several signal checks before it ran out
    finally:
        link.close()
        peer.close()


def _gcs_heartbeat() -> bytes:
    """One HEARTBEAT from a ground station (system 1), as a raw peer socket sends it."""
    mav = mavlink2.MAVLink(None, 1, 1)
    return mav.heartbeat_encode(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0).pack(mav)


def test_new_udpin_peers_while_another_thread_sends():
    """pymavlink's udpin write() iterated over its peer set while our receive thread added to it: "Set
    changed size during iteration" in the sending thread (an emulator's tick died, and the emulator
    fell silent: seen once in test_flood_over_udp_keeps_the_emulator_answering). 5 of 5 runs on the old
    code raised within 1000 new peers."""
    datagram = _gcs_heartbeat()
    errors: list[BaseException] = []
    with Link("udpin:127.0.0.1:0", heartbeat_s=0) as link:
        stop = threading.Event()
        beat = link.mav.heartbeat_encode(mavlink2.MAV_TYPE_CAMERA, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)

        def sender() -> None:
            while not stop.is_set():
                try:
                    link.send(beat)
                except BaseException as err:  # noqa: BLE001 (what the thread would have died of)
                    errors.append(err)
                    return

        thread = threading.Thread(target=sender)
        thread.start()
        try:
            for _ in range(1000):
                with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:  # a new source port each time
                    peer.sendto(datagram, ("127.0.0.1", link.local_port))
                if errors:
                    break
        finally:
            stop.set()
            thread.join(10)
        assert link.wait_heartbeat(timeout=5) is not None  # the receive side kept going too
    assert errors == []


def test_a_silent_udpin_peer_is_dropped_while_another_is_alive(monkeypatch):
    """pymavlink's udpin sent to every address it had ever heard from: a long-running emulator kept sending
    to each ground station that had gone. Silent longer than UDPIN_PEER_TIMEOUT_S while another peer is
    alive, a peer gets nothing more; the last peer is kept however silent."""
    import time

    import wiris_tools.link as link_module

    monkeypatch.setattr(link_module, "UDPIN_PEER_TIMEOUT_S", 0.3)
    datagram = _gcs_heartbeat()
    with Link("udpin:127.0.0.1:0", heartbeat_s=0) as link, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gone, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as alive:
        beat = link.mav.heartbeat_encode(mavlink2.MAV_TYPE_CAMERA, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        for s in (gone, alive):
            s.settimeout(0.5)
            s.sendto(datagram, ("127.0.0.1", link.local_port))
        deadline = time.monotonic() + 5
        while link.stats["received"] < 2 and time.monotonic() < deadline:  # both are peers now
            time.sleep(0.01)
        link.send(beat)
        assert gone.recv(512) and alive.recv(512)  # both heard while both are fresh
        end = time.monotonic() + 0.6
        while time.monotonic() < end:
            alive.sendto(datagram, ("127.0.0.1", link.local_port))
            time.sleep(0.05)
        link.send(beat)
        assert alive.recv(512)
        with pytest.raises(socket.timeout):
            gone.recv(512)
        alive.settimeout(0.2)
        while True:  # what alive sent has been read by now; drain the answers to it, if any
            try:
                alive.recv(512)
            except socket.timeout:
                break
        time.sleep(0.5)  # now alive is silent too, but it is the last peer: kept
        link.send(beat)
        alive.settimeout(2)
        assert alive.recv(512)


def test_a_send_between_a_new_peer_and_its_time_does_not_fail():
    """pymavlink's receive path adds a new udpin peer to its set, then its time to a dict; with the peer
    timeout on, write() looks every peer's time up, so a send in between raised KeyError (the sender, an
    emulator's tick, would have died). The moment is two statements wide: the test stands in it by adding
    a peer to the set alone."""
    datagram = _gcs_heartbeat()
    with Link("udpin:127.0.0.1:0", heartbeat_s=0) as link, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as old, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as new:
        old.settimeout(2)
        new.settimeout(2)
        old.sendto(datagram, ("127.0.0.1", link.local_port))
        assert link.wait_heartbeat(timeout=5) is not None
        new.bind(("127.0.0.1", 0))
        link._conn.clients.add(new.getsockname())  # added to the set, its time not yet written
        link.send(link.mav.heartbeat_encode(mavlink2.MAV_TYPE_CAMERA, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0))
        assert old.recv(512) and new.recv(512)  # the new peer counts as just heard from
