"""Option types shared by the command groups."""

from __future__ import annotations

import math

import click


class FiniteRange(click.FloatRange):
    """click.FloatRange that also refuses nan and inf: float() accepts both, and nan passes every range
    test (its comparisons are all false), so `--timeout nan` waited for ever and `--timeout inf` reached
    the socket layer as an internal error."""

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number.", param, ctx)
        return number
