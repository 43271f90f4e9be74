"""Every error the tools raise says what to do (DESIGN.md: where, what, and a hint).

Read from the source: each construction of CdfError, PlanError, LinkError (or a subclass) in the packages
passes `hint=`. The behaviour tests check the wording of the hints that matter most (plan problems, area
files, waypoint files, setup files, catalogue tables); this one keeps a new raise from forgetting its hint.
"""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("cdf", "missions", "wiris_tools")
ERRORS = {"WirisError", "CdfError", "PlanError", "LinkError", "UploadUnconfirmed", "CommandRefused", "NoAnswer"}


def _constructions(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            name = node.func.id if isinstance(node.func, ast.Name) else (
                node.func.attr if isinstance(node.func, ast.Attribute) else None)
            if name in ERRORS:
                yield node


def _missing_hints() -> list[str]:
    missing = []
    for package in PACKAGES:
        for path in sorted((REPO / package).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
            for call in _constructions(tree):
                keywords = {k.arg for k in call.keywords}
                if "hint" not in keywords and None not in keywords:  # None: **kwargs passed on
                    missing.append(f"{path.relative_to(REPO)}:{call.lineno}: {ast.unparse(call)[:100]}")
    return missing


def test_every_error_raised_carries_a_hint():
    missing = _missing_hints()
    assert not missing, "errors without a hint:\n" + "\n".join(missing)


def test_the_scan_sees_the_errors():
    # the scan must find the constructions it checks (a renamed class would otherwise pass silently)
    counts = {name: 0 for name in ("CdfError", "PlanError", "LinkError")}
    for package in PACKAGES:
        for path in (REPO / package).rglob("*.py"):
            for call in _constructions(ast.parse(path.read_text(encoding="utf-8"))):
                name = call.func.id if isinstance(call.func, ast.Name) else call.func.attr
                counts[name] = counts.get(name, 0) + 1
    assert all(counts[name] >= 20 for name in ("CdfError", "PlanError", "LinkError")), counts
