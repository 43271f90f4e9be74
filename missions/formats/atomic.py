"""Files written atomically (DESIGN.md): a temporary file beside the target, renamed over it, with the target's
permissions (or a new file's, by the umask); `check_writable` before any work whose result would have nowhere
to go.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path
from typing import Iterator

from missions.errors import PlanError


def _temp_beside(path: Path) -> tuple[int, str]:
    # its name is the target's and a few more characters: where it can be made, the target can be too
    return tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)


def _cannot_write(path: Path, err: OSError, what: str = "the file") -> PlanError:
    return PlanError(f"cannot write {what}: {err.strerror or err}", where=str(path),
                     hint="the directory must exist and be writable, the name at most 240 bytes")


def check_writable(path: str | Path) -> None:
    """Raise PlanError unless atomic_write(path, ...) can make its temporary file: asked before a long
    operation (a download) so that its result is not lost at the last step."""
    path = Path(path)
    try:
        fd, tmp = _temp_beside(path)
    except OSError as err:
        if not os.path.isdir(path.parent):  # isdir() answers False for any error
            raise PlanError("the output directory does not exist", where=str(path.parent),
                            hint="create it first") from None
        raise _cannot_write(path, err) from None
    os.close(fd)
    os.unlink(tmp)


def new_file_mode() -> int:
    """The permissions a new file gets here (0666 less the umask): mkstemp's temporary files are 0600."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _mode_for(path: Path) -> int:
    try:
        return stat.S_IMODE(os.stat(path).st_mode)  # a file replaced keeps its permissions
    except OSError:
        return new_file_mode()


@contextlib.contextmanager
def replacing(path: Path, what: str = "the file") -> Iterator[Path]:
    """A temporary file beside `path` to write, renamed onto `path` when the block ends; on any error it is
    removed and an existing file at `path` stays unchanged. An OSError becomes a PlanError naming `what`.
    The result has the replaced file's permissions, or a new file's (not the temporary file's 0600)."""
    try:
        fd, tmp = _temp_beside(path)
    except OSError as err:
        raise _cannot_write(path, err, what) from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _mode_for(path))
        os.replace(tmp, path)
    except BaseException as err:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(err, OSError):
            raise _cannot_write(path, err, what) from None
        raise


def atomic_write(path: Path, text: str) -> None:
    """Write `text` to `path` via a temporary file in the same directory and a rename; PlanError when
    that fails (nothing is left behind, an existing file at `path` is unchanged)."""
    with replacing(Path(path)) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="\n")
