"""Errors of the capture-plan compiler."""

from __future__ import annotations

from cdf.errors import WirisError


class PlanError(WirisError):
    """A capture plan that cannot be compiled; `where` is file:line:col or a mission step."""
