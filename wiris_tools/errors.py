"""Errors of the link layer."""

from __future__ import annotations

from cdf.errors import WirisError


class LinkError(WirisError):
    """A link, command or transfer that failed; `where` names the step, command or mission item."""
