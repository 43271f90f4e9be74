"""MAVLink 2 signing keys from a file (`--signing-key FILE`).

The file holds either
  * the 32-byte secret key as 64 hexadecimal characters (what ArduPilot stores and what
    SETUP_SIGNING carries), or
  * a passphrase of any other text, turned into the key exactly as MAVProxy's `signing setup
    PASSPHRASE` does: SHA-256 of the passphrase bytes (MAVProxy encodes it as ASCII; we use UTF-8,
    which is the same bytes for every ASCII passphrase).
Surrounding whitespace and a trailing newline are ignored, so `echo secret > key.txt` works. A file
that happens to be 64 hex characters is always taken as a raw key, never as a passphrase.
"""

from __future__ import annotations

import hashlib
import string
from pathlib import Path

from cdf.userfile import UserFile, read_user_file
from wiris_tools.errors import LinkError

KEY_BYTES = 32
MAX_KEY_FILE_BYTES = 4096  # a key file is a line of text; anything bigger is the wrong file
KEY_FILE = UserFile("signing key file", MAX_KEY_FILE_BYTES, LinkError,
                    hint="give a file holding 64 hex characters or a passphrase",
                    size_hint="a key file holds one line: 64 hex characters or a passphrase")


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
