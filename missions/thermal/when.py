"""`when:` values: an ISO 8601 date and time with its UTC offset (2026-06-14T11:30+02:00, or Z for UTC)."""

from __future__ import annotations

import datetime as dt

WHEN_EXAMPLE = "2026-06-14T11:30+02:00"


class WhenError(ValueError):
    """A `when` that is not a date and time with UTC offset; `hint` says how to write it."""

    def __init__(self, message: str, hint: str) -> None:
        super().__init__(message)
        self.hint = hint


def parse_when(text: str) -> dt.datetime:
    """The aware datetime `text` names; WhenError when it is not one (no time of day, no offset, no date)."""
    try:
        when = dt.datetime.fromisoformat(text.strip().replace("z", "Z"))
    except ValueError:
        raise WhenError(f"when {text!r} is not an ISO 8601 date and time",
                        f"write date, time and UTC offset, e.g. when: {WHEN_EXAMPLE}") from None
    if "T" not in text.upper() and " " not in text.strip():
        raise WhenError(f"when {text!r} gives a date but no time of day",
                        f"the sun checks need the hour: e.g. when: {text.strip()}T11:30+02:00")
    if when.tzinfo is None or when.utcoffset() is None:
        raise WhenError(f"when {text!r} has no UTC offset, so the hour is ambiguous",
                        f"add the offset of the local time, e.g. {text.strip()}+02:00 (or Z for UTC)")
    return when
