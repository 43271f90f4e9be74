"""Errors of the capture-plan compiler."""

from __future__ import annotations

from dataclasses import dataclass, field

from cdf.errors import WirisError


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a plan, at file:line:col."""

    where: str
    message: str
    hint: str | None = None
    # where in the plan's tree ("mission", 2, "survey", "altitude_m"): which item the problem belongs to, so
    # that the later stages skip that item only; () when unknown (the whole plan)
    path: tuple = field(default=(), compare=False)

    def __str__(self) -> str:
        return f"{self.where}: {self.message}" + (f" (hint: {self.hint})" if self.hint else "")


class PlanError(WirisError):
    """A capture plan that cannot be compiled; `where` is file:line:col or a mission step. A plan with several
    problems raises one PlanError that lists them all; `problems` holds each (one for a single problem, none
    for an error raised by a later stage)."""

    def __init__(self, message: str, *, where: str | None = None, hint: str | None = None,
                 problems: tuple[Problem, ...] = ()) -> None:
        super().__init__(message, where=where, hint=hint)
        self.problems = problems
