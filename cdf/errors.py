"""The error family every wiris package builds on.

An error says where (file:line:col, parameter, mission item), what is wrong, and what to do about it.
The CLI prints `str(err)` without a traceback and exits 1.
"""

from __future__ import annotations


class WirisError(Exception):
    """Base of CdfError, PlanError and LinkError: a message, a location and a hint."""

    def __init__(self, message: str, *, where: str | None = None, hint: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.where = where
        self.hint = hint

    def __str__(self) -> str:
        head = f"{self.where}: {self.message}" if self.where else self.message
        return f"{head}\n  hint: {self.hint}" if self.hint else head


class CdfError(WirisError):
    """A camera catalogue or camera definition problem."""


# How much of a value from untrusted input a message repeats: enough to recognise it, never the whole
# thing (a 5 MB KML coordinate token would otherwise become a 5 MB message).
ECHO_CHARS = 60


def clip(text: str, limit: int = ECHO_CHARS) -> str:
    """`text` as a message repeats it: the first `limit` characters and the length when it is longer."""
    return text if len(text) <= limit else f"{text[:limit]}… ({len(text)} characters)"


def shown(value: object, limit: int = ECHO_CHARS) -> str:
    """repr(value) as a message repeats it (clipped); an integer too long for Python to print (over 4300
    digits) is described by its size."""
    try:
        text = repr(value)
    except ValueError:
        if isinstance(value, int):
            return f"a whole number of about {int(abs(value).bit_length() * 0.30103) + 1} digits"
        return f"a {type(value).__name__} holding a number too long to print"
    return clip(text, limit)
