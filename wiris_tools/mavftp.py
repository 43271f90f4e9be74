"""MAVLink FTP, read-only: a tiny server (the emulator serves its camera definition with it) and a download
client (the camera client fetches `mftp://` definitions with it).

The payload layout and the read sequence are the devguide's (services/ftp.md): a 12-byte header
(seq uint16, session, opcode, size, req_opcode, burst_complete, padding, offset uint32) and up to 239
data bytes in FILE_TRANSFER_PROTOCOL.payload[251]. A read is OpenFileRO(path) -> ACK(session, size 4,
file length); ReadFile(session, offset, size) -> ACK(data) ... NAK(EOF); TerminateSession. BurstReadFile
streams the file from `offset` as consecutive ACKs, at most ServerLimits.burst_packets of them, the last
one with burst_complete = 1 (the client asks again from there).
Responses carry the request's seq + 1; a request repeating the last seq gets the last response again
(the devguide's rule for lost ACKs).

A session nobody closes does not hold its slot for ever (a client whose TerminateSession was lost on the
radio, or that vanished): see ServerLimits. The client sends TerminateSession until it is answered
(TERMINATE_TRIES), whatever ended the download.
"""

from __future__ import annotations

import random
import struct
import time
import zlib
from dataclasses import dataclass
from typing import Any, Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import LinkError

PAYLOAD_BYTES = 251
HEADER = struct.Struct("<HBBBBBBI")
DATA_MAX = PAYLOAD_BYTES - HEADER.size   # 239

# Opcodes and NAK error codes (devguide services/ftp.md, "OpCodes" and "NAK Error Information"; common.xml's
# MAV_FTP_OPCODE and MAV_FTP_ERR)
OP_NONE = mavlink2.MAV_FTP_OPCODE_NONE
OP_TERMINATE = mavlink2.MAV_FTP_OPCODE_TERMINATESESSION
OP_RESET = mavlink2.MAV_FTP_OPCODE_RESETSESSION
OP_LIST = mavlink2.MAV_FTP_OPCODE_LISTDIRECTORY
OP_OPEN_RO = mavlink2.MAV_FTP_OPCODE_OPENFILERO
OP_READ = mavlink2.MAV_FTP_OPCODE_READFILE
OP_CRC32 = mavlink2.MAV_FTP_OPCODE_CALCFILECRC
OP_BURST_READ = mavlink2.MAV_FTP_OPCODE_BURSTREADFILE
OP_ACK = mavlink2.MAV_FTP_OPCODE_ACK
OP_NAK = mavlink2.MAV_FTP_OPCODE_NAK
ERR_FAIL = mavlink2.MAV_FTP_ERR_FAIL
ERR_INVALID_SIZE = mavlink2.MAV_FTP_ERR_INVALIDDATASIZE
ERR_INVALID_SESSION = mavlink2.MAV_FTP_ERR_INVALIDSESSION
ERR_NO_SESSIONS = mavlink2.MAV_FTP_ERR_NOSESSIONSAVAILABLE
ERR_EOF = mavlink2.MAV_FTP_ERR_EOF
ERR_UNKNOWN_COMMAND = mavlink2.MAV_FTP_ERR_UNKNOWNCOMMAND
ERR_FILE_NOT_FOUND = mavlink2.MAV_FTP_ERR_FILENOTFOUND
MAX_SESSIONS = 4
MAX_DOWNLOAD_BYTES = 4 * 1024 * 1024
TERMINATE_TRIES = 3      # TerminateSession sent at most this often, until the server answers it

# What to do when the camera's FTP server refuses to open a file (NAK error code -> hint) or misbehaves.
_OPEN_HINTS = {
    ERR_FILE_NOT_FOUND: "file not found: the camera's mftp:// URI names a file it does not serve",
    ERR_NO_SESSIONS: "all the camera's MAVLink FTP sessions are in use; retry in a moment",
}
_BROKEN_SERVER_HINT = "retry; if it happens again, check the camera's firmware (its MAVLink FTP server)"


@dataclass(frozen=True)
class Packet:
    seq: int
    session: int
    opcode: int
    size: int
    req_opcode: int
    burst_complete: int
    offset: int
    data: bytes

    def pack(self) -> bytes:
        data = self.data[:DATA_MAX]
        return (HEADER.pack(self.seq & 0xFFFF, self.session, self.opcode, self.size, self.req_opcode,
                            self.burst_complete, 0, self.offset & 0xFFFFFFFF) + data).ljust(PAYLOAD_BYTES, b"\0")

    @classmethod
    def unpack(cls, payload: bytes | list[int]) -> "Packet":
        raw = bytes(payload).ljust(PAYLOAD_BYTES, b"\0")[:PAYLOAD_BYTES]
        seq, session, opcode, size, req_opcode, burst, _pad, offset = HEADER.unpack_from(raw)
        return cls(seq, session, opcode, size, req_opcode, burst, offset, raw[HEADER.size:HEADER.size + min(size, DATA_MAX)])


def normalise_path(path: str) -> str:
    """`/a.xml`, `a.xml` and `@ROMFS/`-less forms name the same served file."""
    return path.strip().lstrip("/")


@dataclass(frozen=True)
class ServerLimits:
    """How long an unclosed session keeps its slot, and how much one request can make the server send.

    What real servers do (read at source). ArduPilot, libraries/GCS_MAVLink/GCS_FTP.cpp: when every session
    slot is taken, the oldest one idle for FTP_SESSION_TIMEOUT (3000 ms) goes to the new client, and a session
    idle for FTP_SESSION_KILL_TIMEOUT (20000 ms) is closed. PX4, src/modules/mavlink/mavlink_ftp.cpp: its one
    session is closed after 10 s without a request ("Session was closed without activity"). Both answer a
    BurstReadFile with a big burst (ArduPilot up to 2000 packets, PX4 about 35 KB), but paced to the link:
    ArduPilot uses at most a third of the port's bandwidth, PX4 sends as its MAVLink TX buffer frees. This
    server answers at once, unpaced, over UDP, where one burst request brought back the whole file (126
    datagrams, 33 KB, for a 19-byte request): so the burst itself is bounded. A client asks for the next burst
    at the offset where one ended with burst_complete (devguide ftp.md, "Reading a file (BurstReadFile)").
    """

    max_sessions: int = MAX_SESSIONS
    reclaim_idle_s: float = 3.0      # all slots taken: the oldest session idle this long goes to the new client
    expire_idle_s: float = 10.0      # a session idle this long is closed
    burst_packets: int = 8           # ACKs answering one BurstReadFile (8 x 239 data bytes)


@dataclass
class Session:
    path: str
    last_request_s: float            # the server's clock at the last request on this session


class FtpServer:
    """Read-only files served over MAVLink FTP (pure: `handle(msg, now)` returns the FILE_TRANSFER_PROTOCOL
    replies; `now` is the caller's clock, in seconds)."""

    def __init__(self, files: dict[str, bytes], mav: Any, limits: ServerLimits | None = None) -> None:
        self.files = {normalise_path(k): v for k, v in files.items()}
        self.mav = mav
        self.limits = limits or ServerLimits()
        self.sessions: dict[int, Session] = {}
        self._next_session = 0
        self._last: tuple[int, list[Any]] | None = None

    def handle(self, msg: Any, now: float) -> list[Any]:
        req = Packet.unpack(msg.payload)
        self._expire_idle(now)
        if req.opcode in (OP_READ, OP_BURST_READ) and req.session in self.sessions:
            self.sessions[req.session].last_request_s = now
        if self._last is not None and self._last[0] == req.seq and req.opcode != OP_BURST_READ:
            return self._last[1]            # our answer was lost: send it again
        replies = [self._wrap(msg, p) for p in self._answer(req, now)]
        self._last = (req.seq, replies)
        return replies

    def _expire_idle(self, now: float) -> None:
        for sid in [sid for sid, s in self.sessions.items() if now - s.last_request_s > self.limits.expire_idle_s]:
            del self.sessions[sid]

    def _new_session_id(self, now: float) -> int | None:
        """A session id for an OpenFileRO, or None when every slot is in use. When all are taken, the slot of
        the oldest session idle for `reclaim_idle_s` is freed. Ids rotate through 0-255, so a client that
        comes back to a reclaimed session is told ERR_INVALID_SESSION instead of reading someone else's file."""
        if len(self.sessions) >= self.limits.max_sessions:
            oldest = min(self.sessions, key=lambda sid: self.sessions[sid].last_request_s)
            if now - self.sessions[oldest].last_request_s < self.limits.reclaim_idle_s:
                return None
            del self.sessions[oldest]
        while self._next_session in self.sessions:
            self._next_session = (self._next_session + 1) % 256
        sid = self._next_session
        self._next_session = (sid + 1) % 256
        return sid

    def _wrap(self, msg: Any, p: Packet) -> Any:
        return self.mav.file_transfer_protocol_encode(0, msg.get_srcSystem(), msg.get_srcComponent(), p.pack())

    def _ack(self, req: Packet, *, session: int | None = None, data: bytes = b"", offset: int = 0,
             seq_add: int = 1, burst_complete: int = 0) -> Packet:
        return Packet(req.seq + seq_add, req.session if session is None else session, OP_ACK, len(data),
                      req.opcode, burst_complete, offset, data)

    @staticmethod
    def _nak(req: Packet, error: int) -> Packet:
        return Packet(req.seq + 1, req.session, OP_NAK, 1, req.opcode, 0, req.offset, bytes([error]))

    def _answer(self, req: Packet, now: float) -> list[Packet]:
        if req.opcode == OP_NONE:
            return [self._ack(req)]
        if req.opcode == OP_RESET:
            self.sessions.clear()
            return [self._ack(req)]
        if req.opcode == OP_TERMINATE:
            if self.sessions.pop(req.session, None) is None:
                return [self._nak(req, ERR_INVALID_SESSION)]
            return [self._ack(req)]
        if req.opcode == OP_OPEN_RO:
            path = normalise_path(req.data[:req.size].split(b"\0", 1)[0].decode("utf-8", "replace"))
            if path not in self.files:
                return [self._nak(req, ERR_FILE_NOT_FOUND)]
            session = self._new_session_id(now)
            if session is None:
                return [self._nak(req, ERR_NO_SESSIONS)]
            self.sessions[session] = Session(path, now)
            return [self._ack(req, session=session, data=struct.pack("<I", len(self.files[path])))]
        if req.opcode in (OP_READ, OP_BURST_READ):
            session = self.sessions.get(req.session)
            if session is None:
                return [self._nak(req, ERR_INVALID_SESSION)]
            body = self.files[session.path]
            if req.offset >= len(body):
                return [self._nak(req, ERR_EOF)]
            if req.opcode == OP_READ:
                size = min(req.size or DATA_MAX, DATA_MAX)
                return [self._ack(req, data=body[req.offset:req.offset + size], offset=req.offset)]
            out = []
            offsets = list(range(req.offset, len(body), DATA_MAX))[:self.limits.burst_packets]
            for i, off in enumerate(offsets):
                out.append(self._ack(req, data=body[off:off + DATA_MAX], offset=off, seq_add=i + 1,
                                     burst_complete=int(i == len(offsets) - 1)))
            return out
        if req.opcode == OP_CRC32:
            path = normalise_path(req.data[:req.size].split(b"\0", 1)[0].decode("utf-8", "replace"))
            if path not in self.files:
                return [self._nak(req, ERR_FILE_NOT_FOUND)]
            return [self._ack(req, data=struct.pack("<I", zlib.crc32(self.files[path])))]
        return [self._nak(req, ERR_UNKNOWN_COMMAND)]


@dataclass(frozen=True)
class _OpenFile:
    session: int
    length: int           # bytes, as OpenFileRO's ACK announces them


class _Requests:
    """One download's requests to one server: each gets the next seq and is sent until its answer comes."""

    def __init__(self, link: Any, system: int, component: int, where: str, timeout_s: float, retries: int) -> None:
        self.link = link
        self.system = system
        self.component = component
        self.where = where
        self.timeout_s = timeout_s
        self.retries = retries
        # A server answers a request that repeats its last seq with its last answer (a lost ACK): a download
        # starting at a fixed seq would get the previous one's answer when that one ended at the same seq (seq 1
        # after a refused OpenFileRO). A random start makes that a 1 in 65536 chance.
        self.seq = random.randrange(0x10000)

    def exchange(self, opcode: int, *, session: int = 0, offset: int = 0, size: int = 0, data: bytes = b"",
                 tries: int | None = None) -> Packet:
        """The server's answer to one request (tried `retries` + 1 times unless told), else LinkError."""
        tries = self.retries + 1 if tries is None else tries
        self.seq = (self.seq + 1) & 0xFFFF
        answer_seq = (self.seq + 1) & 0xFFFF
        pkt = Packet(self.seq, session, opcode, size, 0, 0, offset, data)
        msg = self.link.mav.file_transfer_protocol_encode(0, self.system, self.component, pkt.pack())

        def ours(m: Any) -> bool:
            p = Packet.unpack(m.payload)
            return p.req_opcode == opcode and p.seq == answer_seq

        with self.link.inbox("FILE_TRANSFER_PROTOCOL", src_component=self.component, predicate=ours) as box:
            for _ in range(tries):
                self.link.send(msg)
                got = box.get(self.timeout_s)
                if got is not None:
                    return Packet.unpack(got.payload)
        raise LinkError(f"no MAVLink FTP answer to opcode {opcode} after {tries} tries", where=self.where,
                        hint="the camera may not serve MAVLink FTP; use its http:// definition if it has one")


def _open(requests: _Requests, path: str) -> _OpenFile:
    name = path.encode()
    if len(name) > DATA_MAX:
        raise LinkError("path too long for MAVLink FTP", where=requests.where,
                        hint=f"a MAVLink FTP path holds at most {DATA_MAX} bytes: check the camera's mftp:// URI")
    opened = requests.exchange(OP_OPEN_RO, size=len(name), data=name)
    if opened.opcode == OP_NAK:
        code = opened.data[0] if opened.data else 0
        raise LinkError(f"the camera cannot open the file (FTP error {code})", where=requests.where,
                        hint=_OPEN_HINTS.get(code, "retry; if it persists, use the camera's http:// definition "
                                                   "if it has one"))
    return _OpenFile(opened.session, struct.unpack("<I", opened.data[:4].ljust(4, b"\0"))[0])


def _read(requests: _Requests, file: _OpenFile, max_bytes: int,
          progress: Callable[[int, int], None] | None) -> bytes:
    """ReadFile from offset 0 until the announced length or EOF (the caller checks which)."""
    where = requests.where
    if file.length > max_bytes:
        raise LinkError(f"file is {file.length} bytes; the limit is {max_bytes}", where=where,
                        hint="check that the mftp:// URI names the camera definition, not another file")
    chunks = bytearray()
    deadline = time.monotonic() + max(10.0, file.length / 1000)
    while len(chunks) < file.length:
        if time.monotonic() > deadline:
            raise LinkError("download took too long", where=where,
                            hint="check the radio link (lost packets, a low baud rate) and retry")
        got = requests.exchange(OP_READ, session=file.session, offset=len(chunks), size=DATA_MAX)
        if got.opcode == OP_NAK:
            if got.data[:1] == bytes([ERR_EOF]):
                break
            raise LinkError(f"read failed (FTP error {got.data[0] if got.data else '?'})", where=where,
                            hint=_BROKEN_SERVER_HINT)
        if got.offset != len(chunks) or not got.data:
            raise LinkError("the camera answered a read at the wrong offset", where=where, hint=_BROKEN_SERVER_HINT)
        chunks += got.data
        if progress is not None:
            progress(len(chunks), file.length)
    return bytes(chunks)


def _terminate(requests: _Requests, session: int) -> None:
    """Sent until answered (an ACK, or a NAK when the server has already closed it): a TerminateSession lost
    on the radio left the session holding one of the server's few slots. When none of the tries is answered
    the camera has gone quiet, and its idle-session expiry frees the slot."""
    try:
        requests.exchange(OP_TERMINATE, session=session, tries=TERMINATE_TRIES)
    except LinkError:
        pass


def download(link: Any, system: int, component: int, path: str, *, timeout_s: float = 0.5, retries: int = 5,
             max_bytes: int = MAX_DOWNLOAD_BYTES, progress: Callable[[int, int], None] | None = None) -> bytes:
    """Read one file with OpenFileRO / ReadFile / TerminateSession; LinkError naming the step on failure."""
    requests = _Requests(link, system, component, f"mftp {path} on component {component}", timeout_s, retries)
    file = _open(requests, path)
    try:  # from here on the session is open: closed whatever stops the download, which keeps its own outcome
        data = _read(requests, file, max_bytes, progress)
    finally:
        _terminate(requests, file.session)
    if len(data) != file.length:
        raise LinkError(f"got {len(data)} of {file.length} bytes", where=requests.where,
                        hint="the camera ended the file before its announced size; " + _BROKEN_SERVER_HINT)
    return data
