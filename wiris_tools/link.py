"""A MAVLink link: one connection, our own HEARTBEAT, a receive thread, filtered inboxes, and the
command protocol. Used by the ground-station tools and by the camera emulators alike.

    from wiris_tools.link import Link

    with Link("udpout:127.0.0.1:14550") as link:               # a GCS: 255/190, MAV_TYPE_GCS
        hb = link.wait_heartbeat(timeout=5, component=100)     # the camera's HEARTBEAT
        ack = link.command_long(hb.get_srcSystem(), 100, mavlink2.MAV_CMD_REQUEST_CAMERA_INFORMATION,
                                [1])                           # waits for COMMAND_ACK, retries
        with link.inbox(types=["CAMERA_INFORMATION"], src_component=100) as box:
            link.send(link.mav.command_long_encode(...))       # subscribe first, then send
            info = box.get(timeout=1.0)                        # None on timeout

    # a camera (emulator side): MAV_TYPE_CAMERA, component 100, MAVLink 1 for a RedEdge
    cam = Link("udpin:127.0.0.1:0", system=1, component=100, mav_type=mavlink2.MAV_TYPE_CAMERA,
               mavlink1=True)
    cam.subscribe(on_message, types=["COMMAND_LONG"], to_me=True)   # runs on the receive thread

API (everything else is private):
  Link(url, *, system=255, component=190, mav_type=MAV_TYPE_GCS, autopilot=MAV_AUTOPILOT_INVALID,
       heartbeat_s=1.0, mavlink1=False, signing_key=None, baud=57600)
  .mav                      pymavlink encoder (ardupilotmega dialect, MAVLink 2 definitions): build
                            messages with `link.mav.<name>_encode(...)`, send them with `link.send`
  .send(msg)                thread-safe; MAVLink 1 framing when `mavlink1=True`
  .inbox(types=, src_system=, src_component=, to_me=, predicate=) -> Inbox (context manager);
                            Inbox.get(timeout) -> message or None. Messages are queued from the
                            moment the inbox exists, so open it *before* sending a request.
  .recv(...same filters..., timeout=1.0) -> message or None   (a one-shot inbox)
  .subscribe(callback, ...same filters...) -> Subscription; .unsubscribe(sub). Callbacks run on
                            the receive thread: keep them short (sending is fine, waiting is not).
  .wait_heartbeat(timeout, system=None, component=None) -> HEARTBEAT (LinkError on timeout)
  .command_long(target_system, target_component, command, params, *, timeout=1.0, retries=3,
                progress=None) -> COMMAND_ACK (ACCEPTED); CommandRefused (.result: the MAV_RESULT) for
                            another answer, NoAnswer after the last try (wiris_tools.errors, both LinkError)
  .command_int(...) likewise, for COMMAND_INT (frame, x/y as integers)
  .local_port               the bound UDP port (useful with udpin:127.0.0.1:0)
  .stats                    counters: received, sent, bad (CRC/signature failures), rejected_signature
  .close()                  stops the threads and closes the socket (also on `with` exit)

Filters: `types` is a name or a collection of names ("COMMAND_ACK"); `src_system`/`src_component`
match the sender; `to_me=True` drops messages whose target_system/target_component fields (when the
message has them and they are not 0 = broadcast) name someone else.

Signing (MAVLink 2, as ArduPilot supports it): pass `signing_key` (32 bytes, see
wiris_tools.signing for the key file format). Everything we send is signed; incoming messages that
are unsigned, MAVLink 1, signed with another key or replayed with an old timestamp are dropped and
counted in `stats["rejected_signature"]` - they never reach an inbox or callback. A frame that fails
leaves its stream's timestamp where it was (pymavlink's own check does not: see _MAVLink).
"""

from __future__ import annotations

import importlib
import os
import queue
import select
import threading
import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from typing import Any


def _import_optional(*names: str) -> None:
    for name in names:
        try:
            importlib.import_module(name)
        except ImportError:  # pymavlink runs without them
            pass


# pymavlink imports two optional modules inside bare `except:` clauses (mavextra: its quaternion module
# and numpy, 0.12 s; mavutil: curses.ascii), which swallow a Ctrl-C that lands during those imports: the
# command then runs on to its own timeout (reproduced: 3 of 40 `wiris camera info` runs interrupted
# 0.05-0.83 s after start). Imported here first, a Ctrl-C propagates; pymavlink then finds them loaded.
_import_optional("pymavlink.quaternion", "curses.ascii")

from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import ardupilotmega as mavlink2  # noqa: E402

from wiris_tools.errors import CommandRefused, LinkError, NoAnswer  # noqa: E402
from wiris_tools.signing import check_signed_frame, signing_timestamp  # noqa: E402

Message = Any  # a pymavlink MAVLink_message
Filter = Callable[[Message], bool]

# Results of COMMAND_ACK that end a command with an error; everything else but ACCEPTED and
# IN_PROGRESS is reported by its MAV_RESULT name as well.
_RESULT_HINTS = {
    mavlink2.MAV_RESULT_DENIED: "the target refused it in its current state (armed? busy? wrong mode?)",
    mavlink2.MAV_RESULT_UNSUPPORTED: "the target does not implement this command",
    mavlink2.MAV_RESULT_FAILED: "the target tried and failed; check its status messages",
    mavlink2.MAV_RESULT_TEMPORARILY_REJECTED: "the target is busy; try again in a moment",
    mavlink2.MAV_RESULT_COMMAND_LONG_ONLY: "the target takes this command only as COMMAND_LONG (Link.command_long)",
    mavlink2.MAV_RESULT_COMMAND_INT_ONLY: "the target takes this command only as COMMAND_INT (Link.command_int)",
}
# any other result (MAV_RESULT_CANCELLED, a number this dialect does not define)
_OTHER_RESULT_HINT = "a result this tool has no advice for: see the target's documentation or firmware"

# A command (or a PARAM_EXT_SET) reported IN_PROGRESS is waited for at most this many timeouts from the first
# such report (10 s at the default 1 s), however many reports follow: each report extends the wait by one
# timeout, and a target that reports progress for ever (seen: a camera repeating PARAM_ACK_IN_PROGRESS) used
# to keep the caller waiting for ever. A longer timeout gives a slow operation (a format) more time.
IN_PROGRESS_TIMEOUTS = 10

# udpin: pymavlink sends to every address it has ever heard from, so a long-running emulator or camera
# kept sending to each ground station that had gone (every restart of one comes from a new port). A peer
# silent this long is dropped while another is alive (pymavlink keeps the last one); MAVLink peers send a
# heartbeat every second.
UDPIN_PEER_TIMEOUT_S = 30.0

# target_system 0 addresses every system (common.xml names the component one, MAV_COMP_ID_ALL, but not this)
BROADCAST_SYSTEM = 0


def command_name(command: int) -> str:
    """MAV_CMD_… name of a command id (or the number when the dialect does not know it)."""
    entry = mavlink2.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"MAV_CMD {command}"


def result_name(result: int) -> str:
    entry = mavlink2.enums["MAV_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_RESULT {result}"


def _type_set(types: str | Collection[str] | None) -> frozenset[str] | None:
    if types is None:
        return None
    if isinstance(types, str):
        return frozenset((types,))
    return frozenset(types)


@dataclass(frozen=True)
class _Match:
    types: frozenset[str] | None
    src_system: int | None
    src_component: int | None
    to_me: bool
    predicate: Filter | None
    own_system: int
    own_component: int

    def __call__(self, msg: Message) -> bool:
        if self.types is not None and msg.get_type() not in self.types:
            return False
        if self.src_system is not None and msg.get_srcSystem() != self.src_system:
            return False
        if self.src_component is not None and msg.get_srcComponent() != self.src_component:
            return False
        if self.to_me:
            ts = getattr(msg, "target_system", BROADCAST_SYSTEM)
            tc = getattr(msg, "target_component", mavlink2.MAV_COMP_ID_ALL)
            if ts not in (BROADCAST_SYSTEM, self.own_system):
                return False
            if tc not in (mavlink2.MAV_COMP_ID_ALL, self.own_component):
                return False
        return self.predicate is None or bool(self.predicate(msg))


@dataclass(eq=False)
class Subscription:
    match: _Match
    callback: Callable[[Message], None]


class Inbox:
    """Messages matching a filter, queued from creation until closed. Use as a context manager."""

    def __init__(self, link: "Link", match: _Match, maxsize: int = 10000) -> None:
        self._link = link
        self._maxsize = maxsize
        # SimpleQueue waits in C, where a Ctrl-C cannot leave a lock held. queue.Queue waits in Python
        # through threading.Condition: a KeyboardInterrupt landing just after its lock was taken left it
        # held, and the next get() and the receive thread's next put then blocked for ever
        # (tests/test_cli_errors.py raises the interrupt at every place of a wait where one can land)
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._sub = link._add(Subscription(match, self._put))

    def _put(self, msg: Message) -> None:
        # a stuck consumer must not fill the memory (only the receive thread puts: no race at the bound)
        if self._queue.qsize() < self._maxsize:
            self._queue.put(msg)

    def get(self, timeout: float | None = 1.0) -> Message | None:
        """The next matching message, or None after `timeout` seconds (0: don't wait)."""
        try:
            if timeout is not None and timeout <= 0:
                return self._queue.get_nowait()
            return self._queue.get(timeout=timeout)
        except queue.Empty:
            return None

    def close(self) -> None:
        self._link.unsubscribe(self._sub)

    def __enter__(self) -> "Inbox":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class _Stats:
    counts: dict[str, int] = field(default_factory=lambda: {
        "received": 0, "sent": 0, "bad": 0, "rejected_signature": 0, "bytes_sent": 0})


class _Peers(set):
    """The peers of a udpin connection. pymavlink's receive path adds each new sender to this set while
    its write() iterates over it; with our receive thread and a sending thread (an emulator's tick, a
    heartbeat), a peer appearing mid-send raised "Set changed size during iteration" in the sender (an
    emulator fell silent). Iterating over a copy taken in one C call, under the GIL, cannot race."""

    def __iter__(self):
        return iter(list(set.__iter__(self)))


class _LastHeard(dict):
    """When each udpin peer was last heard from. pymavlink's receive path adds a new peer to the peer set
    first and to this dict after; a send in between would look the peer up here (UDPIN_PEER_TIMEOUT_S makes
    write() read the time) and fail with KeyError. A peer not yet here has just been heard from."""

    def __missing__(self, address):
        return time.time()  # pymavlink's clock for these entries


class _MAVLink(mavlink2.MAVLink):
    """pymavlink's encoder and parser (framing, CRC, decoding all its own) with the signature check of the
    MAVLink signing spec: a stream's timestamp is recorded only from a frame whose signature verified (see
    wiris_tools.signing.check_signed_frame for what pymavlink does instead and why it matters)."""

    def check_signature(self, msgbuf: bytearray, srcSystem: int, srcComponent: int) -> bool:
        signing = self.signing
        check = check_signed_frame(msgbuf, signing.secret_key, srcSystem, srcComponent,
                                   signing.stream_timestamps, signing.timestamp)
        if check.accepted:
            signing.stream_timestamps[check.stream] = check.timestamp
            # we sign onwards from the highest verified timestamp, as pymavlink and the spec do
            signing.timestamp = max(signing.timestamp, check.timestamp)
        return check.accepted


class Link:
    """One MAVLink connection (see the module docstring for the API)."""

    def __init__(self, url: str, *, system: int = 255, component: int = mavlink2.MAV_COMP_ID_MISSIONPLANNER,
                 mav_type: int = mavlink2.MAV_TYPE_GCS, autopilot: int = mavlink2.MAV_AUTOPILOT_INVALID,
                 heartbeat_s: float = 1.0, mavlink1: bool = False, signing_key: bytes | None = None,
                 baud: int = 57600, signing_link_id: int = 0) -> None:
        if not (1 <= system <= 255 and 0 <= component <= 255):
            raise LinkError(f"system id {system} / component id {component} out of range", where=url,
                            hint="system ids are 1..255, component ids 0..255")
        if signing_key is not None and mavlink1:
            raise LinkError("MAVLink 1 cannot be signed", where=url,
                            hint="signing needs MAVLink 2; drop --signing-key or the MAVLink 1 option")
        if signing_key is not None and len(signing_key) != 32:
            raise LinkError("a signing key must be 32 bytes", where=url,
                            hint="pass the key that wiris_tools.signing.load_signing_key(FILE) returns")
        self.url = url
        self.system = system
        self.component = component
        self.mav_type = mav_type
        self.autopilot = autopilot
        self.mavlink1 = mavlink1
        self._conn = self._open(url, baud)
        # Our own encoder/parser rather than mavutil's: mavutil picks MAVLink 1 or 2 through a
        # process-wide environment variable, which would leak between links in one process.
        self.mav = _MAVLink(self._conn, srcSystem=system, srcComponent=component)
        self.mav.robust_parsing = True
        if signing_key is not None:
            self.mav.signing.secret_key = bytes(signing_key)
            self.mav.signing.sign_outgoing = True
            self.mav.signing.allow_unsigned_callback = None
            self.mav.signing.link_id = signing_link_id
            self.mav.signing.timestamp = signing_timestamp(time.time())
        self._stats = _Stats()
        self._subs: list[Subscription] = []
        self._subs_lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._closed = threading.Event()
        self._heartbeats: dict[tuple[int, int], Message] = {}
        self._hb_lock = threading.Lock()  # held for a dict read or write only, never waited on (see Inbox)
        self._reader = threading.Thread(target=self._read_loop, name=f"link-rx {url}", daemon=True)
        self._reader.start()
        self._heartbeat_s = heartbeat_s
        self._beater: threading.Thread | None = None
        if heartbeat_s and heartbeat_s > 0:
            self._beater = threading.Thread(target=self._beat_loop, name=f"link-hb {url}", daemon=True)
            self._beater.start()

    # -- opening -------------------------------------------------------------------------------
    @staticmethod
    def _open(url: str, baud: int):
        kind, port = url.partition(":")[0], url.rpartition(":")[2]
        if kind in ("udp", "udpin", "udpout", "udpbcast", "tcp", "tcpin") and port.isdigit() and int(port) > 65535:
            # pymavlink would take it and fail later: in a thread at udpout's first send, or in tcp's retries
            raise LinkError(f"port {port} is not 0-65535", where=url,
                            hint="e.g. udpin:127.0.0.1:14550 or udpout:127.0.0.1:14550")
        device = url
        if "," in url and not url.startswith(("udp", "tcp")):
            device, _, b = url.partition(",")
            try:
                baud = int(b)
            except ValueError:
                raise LinkError(f"bad baud rate {b!r}", where=url, hint="write it as /dev/ttyUSB0,57600") from None
        try:
            conn = mavutil.mavlink_connection(device, baud=baud, autoreconnect=False,
                                              source_system=255, source_component=0,
                                              udp_timeout=UDPIN_PEER_TIMEOUT_S)
        except (OSError, ValueError, OverflowError, ImportError) as err:  # OverflowError: a port over 65535
            raise LinkError(f"cannot open the link: {err}", where=url,
                            hint="use a pymavlink connection string such as udpin:127.0.0.1:14550, "
                                 "udpout:HOST:PORT, tcp:HOST:PORT or /dev/ttyUSB0,57600") from None
        if type(getattr(conn, "clients", None)) is set:  # udpin: see _Peers and _LastHeard
            conn.clients = _Peers(conn.clients)
            conn.clients_last_alive = _LastHeard(conn.clients_last_alive)
        return conn

    @property
    def local_port(self) -> int | None:
        sock = getattr(self._conn, "port", None)
        try:
            return sock.getsockname()[1]  # type: ignore[union-attr]
        except (AttributeError, OSError):
            return None

    @property
    def stats(self) -> dict[str, int]:
        return dict(self._stats.counts)

    @property
    def signing(self) -> bool:
        return self.mav.signing.secret_key is not None

    # -- sending -------------------------------------------------------------------------------
    def send(self, msg: Message) -> None:
        """Send one message (thread-safe). Framing follows the link: MAVLink 2, or 1 if asked."""
        if self._closed.is_set():
            raise LinkError("the link is closed", where=self.url,
                            hint="a bug in wiris-tools or the program using it (send after close): please report it")
        with self._send_lock:
            buf = msg.pack(self.mav, force_mavlink1=self.mavlink1)
            self.mav.seq = (self.mav.seq + 1) % 256
            self.mav.total_packets_sent += 1
            self.mav.total_bytes_sent += len(buf)
            try:
                self._conn.write(buf)
            except (OSError, OverflowError) as err:  # OverflowError: sendto() to a port over 65535
                raise LinkError(f"cannot send {msg.get_type()}: {err}", where=self.url,
                                hint="check --connect (a file path opens as a read-only log) and that a serial "
                                     "device is still plugged in") from None
            self._stats.counts["sent"] += 1
            self._stats.counts["bytes_sent"] += len(buf)

    def send_heartbeat(self) -> None:
        self.send(self.mav.heartbeat_encode(self.mav_type, self.autopilot, 0, 0,
                                            mavlink2.MAV_STATE_ACTIVE))

    def _beat_loop(self) -> None:
        while not self._closed.is_set():
            try:
                self.send_heartbeat()
            except LinkError:
                pass
            self._closed.wait(self._heartbeat_s)

    # -- receiving -----------------------------------------------------------------------------
    def _read_loop(self) -> None:
        fd = getattr(self._conn, "fd", None)
        while not self._closed.is_set():
            try:
                data = self._conn.recv(4096)
            except (OSError, ValueError):
                if self._closed.is_set():
                    return
                time.sleep(0.05)
                continue
            if not data:
                if fd is not None:
                    try:
                        select.select([fd], [], [], 0.05)
                    except (OSError, ValueError):
                        time.sleep(0.01)
                else:
                    time.sleep(0.005)
                continue
            if isinstance(data, str):
                data = data.encode("latin-1")
            try:
                msgs = self.mav.parse_buffer(bytes(data)) or []
            except Exception:  # robust_parsing should catch all; never let the reader die
                self._stats.counts["bad"] += 1
                continue
            for msg in msgs:
                self._dispatch(msg)

    def _dispatch(self, msg: Message) -> None:
        mtype = msg.get_type()
        if mtype == "BAD_DATA":
            self._stats.counts["bad"] += 1
            if "signature" in str(getattr(msg, "reason", "")).lower():
                self._stats.counts["rejected_signature"] += 1
            return
        self._stats.counts["received"] += 1
        if mtype == "HEARTBEAT":
            with self._hb_lock:  # before the subscribers: wait_heartbeat's inbox wakes to a dict that has it
                self._heartbeats[(msg.get_srcSystem(), msg.get_srcComponent())] = msg
        with self._subs_lock:
            subs = list(self._subs)
        for sub in subs:
            try:
                if sub.match(msg):
                    sub.callback(msg)
            except Exception:  # a faulty callback must not kill the link for everyone else
                if os.environ.get("WIRIS_DEBUG"):
                    raise

    def _match(self, types, src_system, src_component, to_me, predicate) -> _Match:
        return _Match(_type_set(types), src_system, src_component, to_me, predicate,
                      self.system, self.component)

    def _add(self, sub: Subscription) -> Subscription:
        with self._subs_lock:
            self._subs.append(sub)
        return sub

    def subscribe(self, callback: Callable[[Message], None], types: str | Collection[str] | None = None, *,
                  src_system: int | None = None, src_component: int | None = None, to_me: bool = False,
                  predicate: Filter | None = None) -> Subscription:
        """Call `callback(msg)` on the receive thread for every matching message."""
        return self._add(Subscription(self._match(types, src_system, src_component, to_me, predicate), callback))

    def unsubscribe(self, sub: Subscription) -> None:
        with self._subs_lock:
            if sub in self._subs:
                self._subs.remove(sub)

    def inbox(self, types: str | Collection[str] | None = None, *, src_system: int | None = None,
              src_component: int | None = None, to_me: bool = False, predicate: Filter | None = None) -> Inbox:
        """A queue of matching messages from now on (close it, or use `with`)."""
        return Inbox(self, self._match(types, src_system, src_component, to_me, predicate))

    def recv(self, types: str | Collection[str] | None = None, *, src_system: int | None = None,
             src_component: int | None = None, to_me: bool = False, predicate: Filter | None = None,
             timeout: float = 1.0) -> Message | None:
        """The next matching message that arrives from now on, or None after `timeout` seconds."""
        with self.inbox(types, src_system=src_system, src_component=src_component, to_me=to_me,
                        predicate=predicate) as box:
            return box.get(timeout)

    def heartbeats(self) -> dict[tuple[int, int], Message]:
        """The last HEARTBEAT seen from each (system, component)."""
        with self._hb_lock:
            return dict(self._heartbeats)

    def wait_heartbeat(self, timeout: float = 5.0, *, system: int | None = None,
                       component: int | None = None) -> Message:
        """A HEARTBEAT from a peer (already seen or arriving within `timeout`), else LinkError."""
        def pick() -> Message | None:
            for (s, c), hb in self.heartbeats().items():
                if (system is None or s == system) and (component is None or c == component) \
                        and (s, c) != (self.system, self.component):
                    return hb
            return None

        deadline = time.monotonic() + timeout
        # woken by every HEARTBEAT from now on (an Inbox, not a threading.Condition: see Inbox.__init__)
        with self.inbox("HEARTBEAT") as arrivals:
            while True:
                hb = pick()
                if hb is not None:
                    return hb
                left = deadline - time.monotonic()
                if left <= 0:
                    who = f"system {system if system is not None else 'any'}, component " \
                          f"{component if component is not None else 'any'}"
                    raise LinkError(f"no HEARTBEAT from {who} within {timeout:g} s", where=self.url,
                                    hint="check the connection string, that the vehicle/camera is powered, "
                                         "and the signing key if the link is signed")
                arrivals.get(left)

    # -- the command protocol ------------------------------------------------------------------
    def command_long(self, target_system: int, target_component: int, command: int,
                     params: Sequence[float] = (), *, timeout: float = 1.0, retries: int = 3,
                     progress: Callable[[int], None] | None = None) -> Message:
        """Send COMMAND_LONG and wait for its COMMAND_ACK.

        Resends up to `retries` times (confirmation 0, 1, 2, …) when no ACK arrives within
        `timeout` s. MAV_RESULT_IN_PROGRESS means "still working": we keep waiting (each report
        extends the wait by `timeout`, up to IN_PROGRESS_TIMEOUTS × `timeout` after the first report)
        and pass its progress (0-100, 255 = unknown) to `progress`.
        Returns the ACCEPTED ack. Otherwise raises a LinkError naming the command, target and result:
        CommandRefused (its `result` the MAV_RESULT) for any other answer, NoAnswer when none came.
        """
        p = self._params(params, command)

        def encode(confirmation: int) -> Message:
            return self.mav.command_long_encode(target_system, target_component, command, confirmation, *p)

        return self._run_command(encode, target_system, target_component, command, timeout, retries, progress)

    def command_int(self, target_system: int, target_component: int, command: int, *,
                    frame: int = mavlink2.MAV_FRAME_GLOBAL, params: Sequence[float] = (), x: int = 0, y: int = 0,
                    z: float = 0.0, timeout: float = 1.0, retries: int = 3,
                    progress: Callable[[int], None] | None = None) -> Message:
        """COMMAND_INT with the same waiting and retry rules as command_long (no confirmation field)."""
        p = self._params(params, command)[:4]

        def encode(_confirmation: int) -> Message:
            return self.mav.command_int_encode(target_system, target_component, frame, command, 0, 0,
                                               *p, int(x), int(y), float(z))

        return self._run_command(encode, target_system, target_component, command, timeout, retries, progress)

    @staticmethod
    def _params(params: Sequence[float], command: int) -> list[float]:
        if len(params) > 7:
            raise LinkError(f"{command_name(command)} takes 7 params, got {len(params)}",
                            hint="a bug in wiris-tools or the program using it (at most 7 params): please report it")
        return [float(v) for v in params] + [0.0] * (7 - len(params))

    def _run_command(self, encode: Callable[[int], Message], target_system: int, target_component: int,
                     command: int, timeout: float, retries: int,
                     progress: Callable[[int], None] | None) -> Message:
        name = command_name(command)
        where = f"{name} to system {target_system} component {target_component}"

        def is_ours(ack: Message) -> bool:
            if ack.command != command:
                return False
            # Broadcast targets (0) accept an answer from anyone; otherwise it must come from the target.
            if target_system and ack.get_srcSystem() != target_system:
                return False
            if target_component and ack.get_srcComponent() != target_component:
                return False
            # MAVLink 2 acks may name who they answer; 0 (or a MAVLink 1 ack) means "not said".
            ts = getattr(ack, "target_system", BROADCAST_SYSTEM)
            tc = getattr(ack, "target_component", mavlink2.MAV_COMP_ID_ALL)
            return ts in (BROADCAST_SYSTEM, self.system) and tc in (mavlink2.MAV_COMP_ID_ALL, self.component)

        tries = retries + 1
        busy_until: float | None = None       # set by the first IN_PROGRESS: the latest we wait for the result
        with self.inbox("COMMAND_ACK", predicate=is_ours) as box:
            for attempt in range(tries):
                self.send(encode(min(attempt, 255)))
                deadline = time.monotonic() + timeout
                while True:
                    left = deadline - time.monotonic()
                    ack = box.get(max(left, 0.0)) if left > 0 else None
                    if ack is None:
                        if busy_until is not None and time.monotonic() >= busy_until:
                            limit = IN_PROGRESS_TIMEOUTS * timeout
                            raise LinkError(f"{name} still not finished {limit:g} s after the target reported "
                                            f"it IN_PROGRESS", where=where,
                                            hint=f"the target reports progress but no result; check it, or give "
                                                 f"a longer timeout (the wait is capped at {IN_PROGRESS_TIMEOUTS} "
                                                 "times the timeout)")
                        break
                    if ack.result == mavlink2.MAV_RESULT_ACCEPTED:
                        return ack
                    if ack.result == mavlink2.MAV_RESULT_IN_PROGRESS:
                        if progress is not None:
                            progress(int(getattr(ack, "progress", 255)))
                        now = time.monotonic()
                        if busy_until is None:
                            busy_until = now + IN_PROGRESS_TIMEOUTS * timeout
                        deadline = min(now + timeout, busy_until)
                        continue
                    hint = _RESULT_HINTS.get(ack.result, _OTHER_RESULT_HINT)
                    raise CommandRefused(f"{name} answered {result_name(ack.result)}", command=command,
                                         result=ack.result, where=where, hint=hint)
        raise NoAnswer(f"no answer to {name} after {tries} tries ({timeout:g} s each)", command=command, where=where,
                       hint="check the target's system/component id, the link, and the signing key")

    # -- closing -------------------------------------------------------------------------------
    def close(self) -> None:
        if self._closed.is_set():
            return
        self._closed.set()
        if self._beater is not None:
            self._beater.join(timeout=2)
        self._reader.join(timeout=2)
        try:
            self._conn.close()
        except OSError:
            pass

    def __enter__(self) -> "Link":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Link({self.url!r}, system={self.system}, component={self.component})"

