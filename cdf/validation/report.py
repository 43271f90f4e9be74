"""Values the validator returns: a Finding per problem, a Report per file (and the Hit the checks yield)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from cdf.validation.rules import RULES_BY_ID, Severity


class Hit(NamedTuple):
    """A finding before the profile gives it a severity."""

    rule: str
    line: int | None
    parameter: str | None
    message: str


class Finding(NamedTuple):
    """One problem: the rule it breaks, its severity in the report's profile, where, and what (hashable:
    a report lists each finding once)."""

    rule: str
    severity: Severity
    line: int | None
    parameter: str | None
    message: str

    @property
    def rule_name(self) -> str:
        return RULES_BY_ID[self.rule].name

    def to_json(self) -> dict:
        return {"rule": self.rule, "severity": self.severity, "line": self.line,
                "parameter": self.parameter, "message": self.message}

    def format(self, file: str) -> str:
        """`file:line: SEVERITY RULE [param] message` (the CLI's text line)."""
        loc = f"{file}:{self.line}" if self.line else file
        param = f" [{self.parameter}]" if self.parameter else ""
        return f"{loc}: {self.severity.upper()} {self.rule}{param} {self.message}"


@dataclass(frozen=True)
class Report:
    """The validation result of one file in one profile (spec/cli.md `validate --json`)."""

    file: str
    profile: str
    parameters: int  # <parameter> elements in the file
    findings: tuple[Finding, ...]

    @property
    def valid(self) -> bool:
        """False exactly when there is at least one finding of severity error."""
        return not any(f.severity == "error" for f in self.findings)

    @property
    def errors(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if f.severity == "error")

    @property
    def warnings(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if f.severity == "warning")

    def rules(self, severity: Severity | None = None) -> set[str]:
        """Ids of the rules with findings (of one severity, if given)."""
        return {f.rule for f in self.findings if severity is None or f.severity == severity}

    def to_json(self) -> dict:
        """Exactly the contract's fields: file, valid, profile, parameters, findings."""
        return {"file": self.file, "valid": self.valid, "profile": self.profile,
                "parameters": self.parameters, "findings": [f.to_json() for f in self.findings]}
