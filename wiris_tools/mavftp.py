"""MAVLink FTP, read-only: a tiny server (the emulator serves its camera definition with it) and a download
client (the camera client fetches `mftp://` definitions with it).

The payload layout and the read sequence are the devguide's (services/ftp.md): a 12-byte header
(seq uint16, session, opcode, size, req_opcode, burst_complete, padding, offset uint32) and up to 239
data bytes in FILE_TRANSFER_PROTOCOL.payload[251]. A read is OpenFileRO(path) -> ACK(session, size 4,
file length); ReadFile(session, offset, size) -> ACK(data) ... NAK(EOF); TerminateSession. BurstReadFile
streams the rest of the file from `offset` as consecutive ACKs, the last one with burst_complete = 1.
Responses carry the request's seq + 1; a request repeating the last seq gets the last response again
(the devguide's rule for lost ACKs).
"""

from __future__ import annotations

import random
import struct
import time
from dataclasses import dataclass
from typing import Any, Callable


from wiris_tools.errors import LinkError

PAYLOAD_BYTES = 251
HEADER = struct.Struct("<HBBBBBBI")
DATA_MAX = PAYLOAD_BYTES - HEADER.size   # 239

# Opcodes and NAK error codes (devguide services/ftp.md, "OpCodes" and "NAK Error Information")
OP_NONE, OP_TERMINATE, OP_RESET, OP_LIST, OP_OPEN_RO, OP_READ = 0, 1, 2, 3, 4, 5
OP_CRC32, OP_BURST_READ = 14, 15
OP_ACK, OP_NAK = 128, 129
ERR_FAIL, ERR_INVALID_SIZE, ERR_INVALID_SESSION, ERR_NO_SESSIONS, ERR_EOF, ERR_UNKNOWN_COMMAND = 1, 3, 4, 5, 6, 7
ERR_FILE_NOT_FOUND = 10
MAX_SESSIONS = 4
MAX_DOWNLOAD_BYTES = 4 * 1024 * 1024

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


class FtpServer:
    """Read-only files served over MAVLink FTP (pure: `handle(msg)` returns the FILE_TRANSFER_PROTOCOL replies)."""

    def __init__(self, files: dict[str, bytes], mav: Any) -> None:
        self.files = {normalise_path(k): v for k, v in files.items()}
        self.mav = mav
        self.sessions: dict[int, str] = {}
        self._last: tuple[int, list[Any]] | None = None

    def handle(self, msg: Any) -> list[Any]:
        req = Packet.unpack(msg.payload)
        if self._last is not None and self._last[0] == req.seq and req.opcode != OP_BURST_READ:
            return self._last[1]            # our answer was lost: send it again
        replies = [self._wrap(msg, p) for p in self._answer(req)]
        self._last = (req.seq, replies)
        return replies

    def _wrap(self, msg: Any, p: Packet) -> Any:
        return self.mav.file_transfer_protocol_encode(0, msg.get_srcSystem(), msg.get_srcComponent(), p.pack())

    def _ack(self, req: Packet, *, session: int | None = None, data: bytes = b"", offset: int = 0,
             seq_add: int = 1, burst_complete: int = 0) -> Packet:
        return Packet(req.seq + seq_add, req.session if session is None else session, OP_ACK, len(data),
                      req.opcode, burst_complete, offset, data)

    @staticmethod
    def _nak(req: Packet, error: int) -> Packet:
        return Packet(req.seq + 1, req.session, OP_NAK, 1, req.opcode, 0, req.offset, bytes([error]))

    def _answer(self, req: Packet) -> list[Packet]:
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
            if len(self.sessions) >= MAX_SESSIONS:
                return [self._nak(req, ERR_NO_SESSIONS)]
            session = next(i for i in range(MAX_SESSIONS) if i not in self.sessions)
            self.sessions[session] = path
            return [self._ack(req, session=session, data=struct.pack("<I", len(self.files[path])))]
        if req.opcode in (OP_READ, OP_BURST_READ):
            path = self.sessions.get(req.session)
            if path is None:
                return [self._nak(req, ERR_INVALID_SESSION)]
            body = self.files[path]
            if req.offset >= len(body):
                return [self._nak(req, ERR_EOF)]
            if req.opcode == OP_READ:
                size = min(req.size or DATA_MAX, DATA_MAX)
                return [self._ack(req, data=body[req.offset:req.offset + size], offset=req.offset)]
            out = []
            offsets = list(range(req.offset, len(body), DATA_MAX))
            for i, off in enumerate(offsets):
                out.append(self._ack(req, data=body[off:off + DATA_MAX], offset=off, seq_add=i + 1,
                                     burst_complete=int(i == len(offsets) - 1)))
            return out
        if req.opcode == OP_CRC32:
            import zlib

            path = normalise_path(req.data[:req.size].split(b"\0", 1)[0].decode("utf-8", "replace"))
            if path not in self.files:
                return [self._nak(req, ERR_FILE_NOT_FOUND)]
            return [self._ack(req, data=struct.pack("<I", zlib.crc32(self.files[path])))]
        return [self._nak(req, ERR_UNKNOWN_COMMAND)]


def download(link: Any, system: int, component: int, path: str, *, timeout_s: float = 0.5, retries: int = 5,
             max_bytes: int = MAX_DOWNLOAD_BYTES, progress: Callable[[int, int], None] | None = None) -> bytes:
    """Read one file with OpenFileRO / ReadFile / TerminateSession; LinkError naming the step on failure."""
    where = f"mftp {path} on component {component}"
    # A server answers a request that repeats its last seq with its last answer (a lost ACK): a download
    # starting at a fixed seq would get the previous one's answer when that one ended at the same seq (seq 1
    # after a refused OpenFileRO). A random start makes that a 1 in 65536 chance.
    seq = [random.randrange(0x10000)]

    def exchange(opcode: int, *, session: int = 0, offset: int = 0, size: int = 0, data: bytes = b"") -> Packet:
        seq[0] = (seq[0] + 1) & 0xFFFF
        pkt = Packet(seq[0], session, opcode, size, 0, 0, offset, data)
        msg = link.mav.file_transfer_protocol_encode(0, system, component, pkt.pack())

        def ours(m: Any) -> bool:
            p = Packet.unpack(m.payload)
            return p.req_opcode == opcode and p.seq == (seq[0] + 1) & 0xFFFF

        with link.inbox("FILE_TRANSFER_PROTOCOL", src_component=component, predicate=ours) as box:
            for _ in range(retries + 1):
                link.send(msg)
                got = box.get(timeout_s)
                if got is not None:
                    return Packet.unpack(got.payload)
        raise LinkError(f"no MAVLink FTP answer to opcode {opcode} after {retries + 1} tries", where=where,
                        hint="the camera may not serve MAVLink FTP; use its http:// definition if it has one")

    name = path.encode()
    if len(name) > DATA_MAX:
        raise LinkError("path too long for MAVLink FTP", where=where,
                        hint=f"a MAVLink FTP path holds at most {DATA_MAX} bytes: check the camera's mftp:// URI")
    opened = exchange(OP_OPEN_RO, size=len(name), data=name)
    if opened.opcode == OP_NAK:
        code = opened.data[0] if opened.data else 0
        raise LinkError(f"the camera cannot open the file (FTP error {code})", where=where,
                        hint=_OPEN_HINTS.get(code, "retry; if it persists, use the camera's http:// definition "
                                                   "if it has one"))
    length = struct.unpack("<I", opened.data[:4].ljust(4, b"\0"))[0]
    session = opened.session
    chunks = bytearray()
    deadline = time.monotonic() + max(10.0, length / 1000)
    try:  # from here on the session is open: the finally closes it, whatever stops the download
        if length > max_bytes:
            raise LinkError(f"file is {length} bytes; the limit is {max_bytes}", where=where,
                            hint="check that the mftp:// URI names the camera definition, not another file")
        while len(chunks) < length:
            if time.monotonic() > deadline:
                raise LinkError("download took too long", where=where,
                                hint="check the radio link (lost packets, a low baud rate) and retry")
            got = exchange(OP_READ, session=session, offset=len(chunks), size=DATA_MAX)
            if got.opcode == OP_NAK:
                if got.data[:1] == bytes([ERR_EOF]):
                    break
                raise LinkError(f"read failed (FTP error {got.data[0] if got.data else '?'})", where=where,
                                hint=_BROKEN_SERVER_HINT)
            if got.offset != len(chunks) or not got.data:
                raise LinkError("the camera answered a read at the wrong offset", where=where,
                                hint=_BROKEN_SERVER_HINT)
            chunks += got.data
            if progress is not None:
                progress(len(chunks), length)
    finally:
        try:
            seq[0] = (seq[0] + 1) & 0xFFFF
            link.send(link.mav.file_transfer_protocol_encode(
                0, system, component, Packet(seq[0], session, OP_TERMINATE, 0, 0, 0, 0, b"").pack()))
        except LinkError:
            pass
    if len(chunks) != length:
        raise LinkError(f"got {len(chunks)} of {length} bytes", where=where,
                        hint="the camera ended the file before its announced size; " + _BROKEN_SERVER_HINT)
    return bytes(chunks)
