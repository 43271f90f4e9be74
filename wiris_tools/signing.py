"""MAVLink 2 signing keys from a file (`--signing-key FILE`).

The file holds either
  * the 32-byte secret key as 64 hexadecimal characters (what ArduPilot stores and what
    SETUP_SIGNING carries), or
  * a passphrase of any other text, turned into the key exactly as MAVProxy's `signing setup
    PASSPHRASE` does: SHA-256 of the passphrase bytes (MAVProxy encodes it as ASCII; we use UTF-8,
    which is the same bytes for every ASCII passphrase).
Surrounding whitespace and a trailing newline are ignored, so `echo secret > key.txt` works. A file
that happens to be 64 hex characters is always taken as a raw key, never as a passphrase.

It also holds the receiving half of signing that pymavlink gets wrong (see `SignatureCheck`), kept free
of pymavlink so that it reads as the spec does.
"""

from __future__ import annotations

import hashlib
import hmac
import string
from pathlib import Path
from typing import NamedTuple

from cdf.userfile import UserFile, read_user_file
from wiris_tools.errors import LinkError

KEY_BYTES = 32
# Signing timestamps count 10 us units since 2015-01-01 00:00 UTC (MAVLink signing spec).
TIMESTAMP_EPOCH_UNIX_S = 1420070400
TIMESTAMP_UNITS_PER_S = 100_000
MAX_KEY_FILE_BYTES = 4096  # a key file is a line of text; anything bigger is the wrong file
KEY_FILE = UserFile("signing key file", MAX_KEY_FILE_BYTES, LinkError,
                    hint="give a file holding 64 hex characters or a passphrase",
                    size_hint="a key file holds one line: 64 hex characters or a passphrase")


def signing_timestamp(unix_s: float) -> int:
    """The signing timestamp of a moment given in seconds since 1970 (time.time())."""
    return int((unix_s - TIMESTAMP_EPOCH_UNIX_S) * TIMESTAMP_UNITS_PER_S)


# A stream seen for the first time is taken if its timestamp is at most this far behind ours (the spec's
# "6 million (one minute)"); a replay of an older recording is not.
NEW_STREAM_WINDOW = 60 * TIMESTAMP_UNITS_PER_S
SIGNATURE_BYTES = 6      # the end of a signed frame: link id (1), timestamp (6), signature (6)
TIMESTAMP_BYTES = 6


class SignatureBlock(NamedTuple):
    """The 13 bytes a signed MAVLink 2 frame ends with."""
    link_id: int
    timestamp: int
    signature: bytes


def signature_block(frame: bytes | bytearray) -> SignatureBlock:
    sig_at = len(frame) - SIGNATURE_BYTES
    ts_at = sig_at - TIMESTAMP_BYTES
    return SignatureBlock(frame[ts_at - 1], int.from_bytes(frame[ts_at:sig_at], "little"), bytes(frame[sig_at:]))


def signature_matches(key: bytes, frame: bytes | bytearray) -> bool:
    """The spec's signature: the first 48 bits of SHA-256(key + the frame up to the signature)."""
    expected = hashlib.sha256(key + bytes(frame[:-SIGNATURE_BYTES])).digest()[:SIGNATURE_BYTES]
    return hmac.compare_digest(expected, bytes(frame[-SIGNATURE_BYTES:]))


class SignatureCheck(NamedTuple):
    """What to make of one signed frame from stream (link id, system, component)."""
    accepted: bool
    stream: tuple[int, int, int]
    timestamp: int


def check_signed_frame(frame: bytes | bytearray, key: bytes, system: int, component: int,
                       stream_timestamps: dict[tuple[int, int, int], int], local_timestamp: int) -> SignatureCheck:
    """Verify a signed frame in the order of the MAVLink signing spec, changing nothing.

    pymavlink (2.4.50, check_signature) records the frame's timestamp as its stream's before it checks the
    signature, so a frame that anyone can make - the sender's ids, no key, timestamp 2^48-1 - made the real
    sender's frames "old" for good (or, dated 10 s ahead, for 10 s). Here the timestamp counts only once
    the signature has verified: the caller records `timestamp` for `stream` only when `accepted`.

    A correctly signed first frame dated far *ahead* of our clock is accepted, as the spec and the C
    library do: only a key holder can make one, and peers legitimately run ahead - each side adopts the
    highest timestamp it has verified and ArduPilot keeps its own across reboots, so one ground station
    with a fast clock puts the whole system ahead. Refusing those would lock out real peers."""
    block = signature_block(frame)
    stream = (block.link_id, system, component)
    last = stream_timestamps.get(stream)
    if last is None:
        fresh = block.timestamp + NEW_STREAM_WINDOW >= local_timestamp
    else:
        fresh = block.timestamp > last   # each frame on a stream is dated after the one before
    return SignatureCheck(fresh and signature_matches(key, frame), stream, block.timestamp)


def key_from_text(text: str, *, where: str = "signing key") -> bytes:
    """The 32-byte key from 64 hex characters or from a passphrase (SHA-256, as MAVProxy)."""
    value = text.strip()
    if not value:
        raise LinkError("the signing key is empty", where=where,
                        hint="write 64 hex characters (the 32-byte key) or a passphrase into the file")
    if len(value) == 2 * KEY_BYTES and all(c in string.hexdigits for c in value):
        return bytes.fromhex(value)
    return hashlib.sha256(value.encode("utf-8")).digest()


def load_signing_key(path: str | Path) -> bytes:
    """Read a key file (see module docstring); LinkError if it is missing, huge or empty."""
    p = Path(path)
    raw = read_user_file(p, KEY_FILE)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise LinkError("the signing key file is not UTF-8 text", where=str(p),
                        hint="a binary 32-byte key must be written as 64 hex characters") from None
    return key_from_text(text, where=str(p))
