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
"""

from __future__ import annotations

from pathlib import Path
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

__all__ = ["MAX_PLAN_BYTES", "PLAN_FILE", "input_files", "load_plan", "parse_plan", "raise_problems",
           "CameraStep", "CorridorStep", "Home", "LandStep", "Payload", "Plan", "RtlStep", "Step", "SurveyStep",
           "TakeoffStep", "Vehicle", "WaypointStep"]

MAX_PLAN_BYTES = 1_000_000      # a hand-written plan is a few kB; inline areas of thousands of points still fit


def raise_problems(problems: list[Problem], file: str) -> None:
    """One PlanError for all problems (sorted by position); `err.problems` keeps them."""
    if not problems:
        return

    def key(p: Problem) -> tuple:
        parts = p.where.rsplit(":", 2)
        try:
            return (0, int(parts[1]), int(parts[2]))
        except (IndexError, ValueError):
            return (1, 0, 0)

    problems = sorted(problems, key=key)
    if len(problems) == 1:
        p = problems[0]
        raise PlanError(p.message, where=p.where, hint=p.hint, problems=(p,))
    lines = [f"{len(problems)} problems in the plan:"]
    for p in problems:
        lines.append(f"  {p.where}: {p.message}" + (f"\n      hint: {p.hint}" if p.hint else ""))
    raise PlanError("\n".join(lines), where=None, hint=None, problems=tuple(problems))


def parse_plan(text: str, path: str = "<plan>", base_dir: str | Path | None = None) -> Plan:
    """Parse plan text (see module doc). `path` names it in locations; areas resolve against `base_dir`."""
    problems: list[Problem] = []
    base = Path(base_dir) if base_dir is not None else Path(path).resolve().parent
    if len(text.encode("utf-8", "surrogatepass")) > MAX_PLAN_BYTES:
        raise PlanError(f"the plan is larger than {MAX_PLAN_BYTES} bytes", where=path,
                        hint="put large areas in KML/GeoJSON files next to the plan")
    data, doc = parse_yaml(text, path, problems)
    if data is None:
        raise_problems(problems, path)
    if not isinstance(data, dict):
        doc.report((), f"a plan is a mapping of keys, got {describe(data)}",
                   "start from `wiris mission schema` or examples/")
        raise_problems(problems, path)
    schema_problems(data, doc, problems)
    resolved = check_meaning(data, doc, base)
    raise_problems(problems, path)
    locations = {p: f"{path}:{l + 1}:{c + 1}" for p, (l, c) in doc.values.items()}
    locations[()] = path
    try:
        return build_plan(data, resolved, path, base, MappingProxyType(locations))
    except (KeyError, TypeError, ValueError, StopIteration) as e:   # a gap between schema and builder: a bug
        raise PlanError(f"internal: the plan passed validation but could not be built ({type(e).__name__}: {e})",
                        where=path, hint="please report this with the plan") from None


def input_files(plan: Plan) -> tuple[str, ...]:
    """Every file the plan is read from: the plan file itself and each area and exclusion file, as paths."""
    files = [plan.path] if plan.path != "<plan>" else []
    for step in plan.mission:
        if isinstance(step, SurveyStep):
            for src in (step.area, *step.exclude):
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
    raw = read_user_file(path, PLAN_FILE)
    stdin = names_stdin(path, PLAN_FILE)
    name = STDIN_LABEL if stdin else str(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise PlanError(f"the plan is not UTF-8 text (byte {e.start})", where=name,
                        hint="save the plan as UTF-8 (the default of every current editor)") from None
    return parse_plan(text, name, Path.cwd() if stdin else Path(path).resolve().parent)
