"""The directory guard of every command that reads or writes a directory (cdf build, mission compile,
cdf serve): one wording of "not a directory" for all of them, raised in the caller's error family."""

from __future__ import annotations

import os
from pathlib import Path

from cdf.errors import WirisError


def require_directory(path: str | Path, error_class: type[WirisError], *, hint: str, missing_ok: bool = False,
                      access_hint: str = "") -> None:
    """Raise `error_class` (where: `path`) unless `path` is a directory.

    missing_ok: `path` is an output directory still to be made: only something else in its place is refused
    ("the output path exists and is not a directory"), and a path the system cannot look at (a name too
    long) says so with `access_hint`. Otherwise the directory must be there ("not a directory"), and a path
    that cannot be looked at is not one."""
    if not missing_ok:
        if not os.path.isdir(path):  # False for any error (a name too long), where Path.is_dir() raises
            raise error_class("not a directory", where=str(path), hint=hint)
        return
    p = Path(path)
    try:
        in_the_way = p.exists() and not p.is_dir()
    except OSError as err:  # exists() answers only "no such file"; a name too long raises
        raise error_class(f"cannot use the output directory: {err.strerror}", where=str(path),
                          hint=access_hint) from None
    if in_the_way:
        raise error_class("the output path exists and is not a directory", where=str(path), hint=hint)
