"""Load a capture plan (YAML, format version 1) into frozen values, or fail with every problem located.

    plan = load_plan("survey.yaml")          # -> Plan
    plan.where("mission", 1, "survey", "altitude_m")   # "survey.yaml:14:19" for later stages' errors

Loading is three passes over untrusted text, each collecting problems instead of stopping at the first:
1. YAML with positions (`missions.plan.yaml_reader`): a size cap, a depth cap, a node budget, no duplicate keys,
   only `true`/`false` as booleans.
2. The JSON Schema (`missions.plan.schema`), each error mapped back to file:line:col and said for a person
   (`missions.plan.schema_errors`).
3. Meaning (`missions.plan.meaning`): payload and camera names, settings against the camera catalogue, component
   ids, altitude_m xor gsd_cm, overlap, area files.
Then `missions.plan.build` turns the checked values into a `Plan`.

All problems are raised together as one PlanError; `err.problems` holds them as `Problem` values.
Paths in a plan are relative to the plan file.

The compiler checks a plan in one pass: `parse_plan_partly` returns the problems and, when they lie only in
some payloads and steps, the plan without those (and without the steps that use a payload with a problem), so
that the later stages still check the rest and every problem is reported at once.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple
from types import MappingProxyType

from cdf.userfile import STDIN_LABEL, UserFile, names_stdin, read_user_file
from missions.errors import PlanError, Problem
from missions.plan.build import build_plan
from missions.plan.meaning import check_meaning
from missions.plan.schema_errors import describe, schema_problems
# The value types are the plan stage's interface (missions.plan re-exports them too); they are importable from
# here because missions.compile imports its step classes from this module.
from missions.plan.types import (CameraStep, CorridorStep, Home, LandStep, Payload, Plan, RtlStep, Step,
                                 SurveyStep, TakeoffStep, Vehicle, WaypointStep)
from missions.plan.yaml_reader import parse_yaml

__all__ = ["MAX_PLAN_BYTES", "PLAN_FILE", "PartPlan", "input_files", "load_plan", "load_plan_partly", "parse_plan",
           "parse_plan_partly", "raise_problems",
           "CameraStep", "CorridorStep", "Home", "LandStep", "Payload", "Plan", "RtlStep", "Step", "SurveyStep",
           "TakeoffStep", "Vehicle", "WaypointStep"]

MAX_PLAN_BYTES = 1_000_000      # a hand-written plan is a few kB; inline areas of thousands of points still fit


_LOCATED = re.compile(r"^(?P<file>.*?):(?P<line>\d+):(?P<col>\d+)(?:\s|$)")


def _by_position(file: str):
    """The sort key of problems: the plan file's by line and column, then other files' (an area file's) by
    theirs, then the unlocated ones, each group in the order found."""
    def key(p: Problem) -> tuple:
        m = _LOCATED.match(p.where)
        if m is None:
            return (2, "", 0, 0)
        return (0 if m["file"] == file else 1, m["file"], int(m["line"]), int(m["col"]))
    return key


def raise_problems(problems: list[Problem], file: str) -> None:
    """One PlanError for all problems (sorted by position in `file`, then in other files); `err.problems`
    keeps them."""
    if not problems:
        return
    problems = sorted(dict.fromkeys(problems), key=_by_position(file))
    if len(problems) == 1:
        p = problems[0]
        raise PlanError(p.message, where=p.where, hint=p.hint, problems=(p,))
    lines = [f"{len(problems)} problems in the plan:"]
    for p in problems:
        lines.append(f"  {p.where}: {p.message}" + (f"\n      hint: {p.hint}" if p.hint else ""))
    raise PlanError("\n".join(lines), where=None, hint=None, problems=tuple(problems))


class PartPlan(NamedTuple):
    """A plan as far as it could be read: every problem found, and the plan without the parts they are in
    (None: a problem outside payloads and steps, or in the YAML itself, leaves nothing to check further)."""

    plan: Plan | None
    problems: list[Problem]
    file: str                       # how locations name the plan file (raise_problems sorts by it)


def parse_plan(text: str, path: str = "<plan>", base_dir: str | Path | None = None) -> Plan:
    """Parse plan text (see module doc). `path` names it in locations; areas resolve against `base_dir`."""
    plan, problems, _ = parse_plan_partly(text, path, base_dir)
    raise_problems(problems, path)
    assert plan is not None        # without a problem the whole plan is built (or the builder raised)
    return plan


def _affected(problems: list[Problem], data: dict) -> tuple[set[str], set[int]] | None:
    """(payload names, step indices) the problems lie in, with the steps using such a payload; None when a
    problem lies elsewhere (version, vehicle, home, the mission list itself, or no known place)."""
    payloads: set[str] = set()
    steps: set[int] = set()
    for p in problems:
        if len(p.path) >= 2 and p.path[0] == "payloads" and isinstance(p.path[1], str):
            payloads.add(p.path[1])
        elif len(p.path) >= 2 and p.path[0] == "mission" and isinstance(p.path[1], int):
            steps.add(p.path[1])
        else:
            return None
    for i, step in enumerate(data["mission"]):
        if i not in steps and payloads & _payloads_used(step):
            steps.add(i)
    return payloads, steps


def _payloads_used(step: dict) -> set[str]:
    """The payload names a (schema-valid) mission step refers to."""
    body = next(iter(step.values()), None) if isinstance(step, dict) else None
    if not isinstance(body, dict):
        return set()
    listed = body.get("payloads") if isinstance(body.get("payloads"), list) else []
    return {u for u in [*listed, body.get("capture"), body.get("payload")] if isinstance(u, str)}


def parse_plan_partly(text: str, path: str = "<plan>", base_dir: str | Path | None = None) -> PartPlan:
    """Parse plan text into what can be checked further and every problem found (see the module doc)."""
    problems: list[Problem] = []
    base = Path(base_dir) if base_dir is not None else Path(path).resolve().parent
    if len(text.encode("utf-8", "surrogatepass")) > MAX_PLAN_BYTES:
        raise PlanError(f"the plan is larger than {MAX_PLAN_BYTES} bytes", where=path,
                        hint="put large areas in KML/GeoJSON files next to the plan")
    data, doc = parse_yaml(text, path, problems)
    if data is None and problems:
        return PartPlan(None, problems, path)
    if not isinstance(data, dict):
        doc.report((), f"a plan is a mapping of keys, got {describe(data)}",
                   "start from `wiris mission schema` or examples/")
        return PartPlan(None, problems, path)
    schema_problems(data, doc, problems)
    resolved = check_meaning(data, doc, base)
    affected = _affected(problems, data) if problems else (set(), set())
    if affected is None:
        return PartPlan(None, problems, path)
    locations = {p: f"{path}:{l + 1}:{c + 1}" for p, (l, c) in doc.values.items()}
    locations[()] = path
    try:
        return PartPlan(build_plan(data, resolved, path, base, MappingProxyType(locations),
                                   skip_payloads=affected[0], skip_steps=affected[1]), problems, path)
    except (KeyError, TypeError, ValueError, StopIteration) as e:
        if problems:        # a part the problems left half-checked: they are what to fix
            return PartPlan(None, problems, path)
        # a gap between schema and builder: a bug
        raise PlanError(f"internal: the plan passed validation but could not be built ({type(e).__name__}: {e})",
                        where=path, hint="please report this with the plan") from None


def input_files(plan: Plan) -> tuple[str, ...]:
    """Every file the plan is read from: the plan file itself and each area and exclusion file, as paths."""
    files = [plan.path] if plan.path != "<plan>" else []
    for step in plan.mission:
        if isinstance(step, (SurveyStep, CorridorStep)):
            area = (step.area,) if isinstance(step, SurveyStep) else ()
            for src in (*area, *step.exclude, *step.no_fly, *step.no_photo):
                if isinstance(src, str):
                    files.append(str(Path(src) if Path(src).is_absolute() else Path(plan.base_dir) / src))
    for src in plan.terrain.dem if plan.terrain is not None else ():
        files.append(str(Path(src) if Path(src).is_absolute() else Path(plan.base_dir) / src))
    return tuple(dict.fromkeys(files))


PLAN_FILE = UserFile("plan", MAX_PLAN_BYTES, PlanError, stdin_ok=True,
                     hint="check the path and that you may read the file",
                     size_hint="put large areas in KML/GeoJSON files next to the plan")


def load_plan(path: str | Path) -> Plan:
    """Read and parse a plan file (size-capped, UTF-8); "-" or /dev/stdin reads standard input, whose
    relative area paths are then relative to the current directory."""
    part = load_plan_partly(path)
    raise_problems(part.problems, part.file)
    return part.plan


def load_plan_partly(path: str | Path) -> PartPlan:
    """`load_plan`, returning the problems with what could be built (`parse_plan_partly`) instead of raising
    them; a file that cannot be read or decoded still raises."""
    raw = read_user_file(path, PLAN_FILE)
    stdin = names_stdin(path, PLAN_FILE)
    name = STDIN_LABEL if stdin else str(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise PlanError(f"the plan is not UTF-8 text (byte {e.start})", where=name,
                        hint="save the plan as UTF-8 (the default of every current editor)") from None
    return parse_plan_partly(text, name, Path.cwd() if stdin else Path(path).resolve().parent)
