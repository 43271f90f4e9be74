"""Reading a file a user named: at most a cap, and only a regular file (or standard input by intent).

Every command that reads a file from its user (a capture plan, an area, a .plan or .waypoints file, a setup
file, a camera definition, a signing key) reads it here. A size taken from stat() before reading is no limit:
a pipe, /dev/zero or /dev/stdin report 0 bytes and then never end, and a FIFO blocks open() until someone
writes to it. So the file is opened without waiting (O_NONBLOCK), its kind is taken from the opened
descriptor (no race with a rename), anything but a regular file is refused, and at most cap + 1 bytes are
read, so more than the cap is known without reading it.

Standard input is read only where the caller allows it and the user names it on purpose ("-" or
/dev/stdin); it is capped the same way.
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
import stat
import sys
from typing import Callable

from cdf.errors import CdfError, WirisError

STDIN_NAMES = ("-", "/dev/stdin")
STDIN_LABEL = "<stdin>"
_CHUNK = 1 << 20

# What each kind of file that is not a regular one is called in a refusal.
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


@dataclass(frozen=True)
class UserFile:
    """One kind of file users give: what it is called, its cap, the package's error and what to do.

    hint: what to do when the file cannot be read or is not a file; size_hint: when it is larger than cap.
    size_hint None returns cap + 1 bytes of a larger file instead of refusing it (the camera definition
    validator reports the excess as a finding)."""

    what: str                       # "plan", "area file", ...: "cannot read the plan: ..."
    cap: int                        # bytes
    error: type[WirisError] = CdfError
    hint: str = "check the path and that you may read the file"
    size_hint: str | None = "give the file itself, not another one"
    stdin_ok: bool = False          # "-" and /dev/stdin read standard input


def not_a_file(mode: int) -> str | None:
    """None for a regular file's st_mode, else what it is: "is a directory", "is a pipe (FIFO)", ..."""
    if stat.S_ISREG(mode):
        return None
    return "is " + next((name for test, name in _KINDS if test(mode)), "a special file")


def names_stdin(path: str | Path, kind: UserFile) -> bool:
    """Whether `path` means standard input for this kind of file."""
    return kind.stdin_ok and str(path) in STDIN_NAMES


def read_user_file(path: str | Path, kind: UserFile) -> bytes:
    """The bytes of a regular file (or of standard input, see names_stdin), at most kind.cap of them;
    kind.error with the path and kind.hint for anything else."""
    if names_stdin(path, kind):
        stdin = getattr(sys.stdin, "buffer", None)
        if stdin is None:
            raise kind.error(f"cannot read the {kind.what}: there is no standard input", where=STDIN_LABEL,
                             hint=kind.hint)
        return _read_capped(stdin.read, STDIN_LABEL, kind)
    where = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
                     | getattr(os, "O_BINARY", 0))
    except FileNotFoundError:
        raise kind.error(f"cannot read the {kind.what}: no such file", where=where, hint=kind.hint) from None
    except (OSError, ValueError) as err:    # ValueError: a NUL byte in the name
        _refuse_other(_mode_of(path), where, kind)     # a socket cannot be opened (ENXIO): say what it is
        raise kind.error(f"cannot read the {kind.what}: {getattr(err, 'strerror', None) or err}", where=where,
                         hint=kind.hint) from None
    try:
        _refuse_other(os.fstat(fd).st_mode, where, kind)
        # O_NONBLOCK changes nothing for a regular file's reads
        return _read_capped(lambda n: os.read(fd, n), where, kind)
    finally:
        os.close(fd)


def _refuse_other(mode: int | None, where: str, kind: UserFile) -> None:
    other = not_a_file(mode) if mode is not None else None
    if other:
        tip = " (to read standard input, give -)" if kind.stdin_ok else ""
        raise kind.error(f"{other}, not a file", where=where, hint=kind.hint + tip)


def _mode_of(path: str | Path) -> int | None:
    try:
        return os.stat(path).st_mode
    except (OSError, ValueError):
        return None


def _read_capped(read: Callable[[int], bytes], where: str, kind: UserFile) -> bytes:
    """At most cap + 1 bytes from `read` (which returns b"" at the end); refused when more than cap."""
    chunks: list[bytes] = []
    left = kind.cap + 1
    try:
        while left > 0:
            chunk = read(min(left, _CHUNK))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except (OSError, ValueError) as err:     # ValueError: standard input is closed
        raise kind.error(f"cannot read the {kind.what}: {getattr(err, 'strerror', None) or err}", where=where,
                         hint=kind.hint) from None
    data = b"".join(chunks)
    if len(data) > kind.cap and kind.size_hint is not None:
        raise kind.error(f"the {kind.what} is larger than {_size(kind.cap)}", where=where, hint=kind.size_hint)
    return data


def _size(n: int) -> str:
    if n >= 2**20 and n % 2**20 == 0:
        return f"{n // 2**20} MiB ({n} bytes)"
    return f"{n} bytes"
