"""Errors of the link layer."""

from __future__ import annotations

from cdf.errors import WirisError


class LinkError(WirisError):
    """A link, command or transfer that failed; `where` names the step, command or mission item."""


class CommandRefused(LinkError):
    """The target answered a command (COMMAND_LONG or COMMAND_INT) with a result other than ACCEPTED or
    IN_PROGRESS: `result` is that MAV_RESULT (a number the dialect may not define), `command` the MAV_CMD."""

    def __init__(self, message: str, *, command: int, result: int, where: str | None = None,
                 hint: str | None = None) -> None:
        super().__init__(message, where=where, hint=hint)
        self.command = command
        self.result = result


class NoAnswer(LinkError):
    """No COMMAND_ACK for a command after every try: the target (or the link to it) stayed silent."""

    def __init__(self, message: str, *, command: int, where: str | None = None, hint: str | None = None) -> None:
        super().__init__(message, where=where, hint=hint)
        self.command = command
