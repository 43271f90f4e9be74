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
