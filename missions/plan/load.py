"""Load a capture plan (YAML, format version 1) into frozen values, or fail with every problem located.

    plan = load_plan("survey.yaml")          # -> Plan
    plan.where("mission", 1, "survey", "altitude_m")   # "survey.yaml:14:19" for later stages' errors

Loading is three passes over untrusted text, each collecting problems instead of stopping at the first:
1. YAML with positions: PyYAML's safe composer (no object construction, no custom tags) gives nodes with
   line/column; we convert them ourselves with a size cap, a depth cap and a node budget (an alias bomb
   expands through the budget, not through memory), reject duplicate keys (PyYAML silently keeps the last)
   and read only `true`/`false` as booleans (YAML 1.1 turns `off`, an isotherm mode, into False).
2. The JSON Schema (`missions.plan.schema`), each error mapped back to file:line:col, unknown keys answered with
   "did you mean" (difflib) and unit hints (`altitude: 40` -> altitude_m).
3. Meaning: payload and camera names, settings against the camera catalogue (the same `Setting.check` and
   messages as the camera definition), altitude_m xor gsd_cm, overlap, the RedEdge/WIRIS component clash.

All problems are raised together as one PlanError; `err.problems` holds them as `Problem` values.
Paths in a plan are relative to the plan file.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import difflib
import math
import re
from pathlib import Path
from types import MappingProxyType
from typing import Any, Iterable, Mapping

from cdf.errors import ECHO_CHARS, clip, shown
from cdf.userfile import STDIN_LABEL, UserFile, names_stdin, not_a_file, read_user_file
from missions.errors import PlanError, Problem
from missions.plan.schema import COMPONENT_IDS, MAX_ALTITUDE_M, MIN_ALTITUDE_M, STEPS, plan_schema

MAX_PLAN_BYTES = 1_000_000      # a hand-written plan is a few kB; inline areas of thousands of points still fit
MAX_NODES = 200_000             # YAML nodes after alias expansion
MAX_DEPTH = 40
# Above this the front overlap puts photos closer than a consumer GNSS receiver's position noise
# (missions.geometry.footprint.MAX_OVERLAP_PCT gives the same limit to the geometry).
MAX_OVERLAP_PCT = 95.0

# The RedEdge answers only on component 100 (MAV_COMP_ID_CAMERA) or 0 (rededge serial API); a WIRIS that
# the plan leaves unplaced is moved to the first free id of 101..105 instead (reported as a note).
REDEDGE_COMPONENT = 100



@dataclass(frozen=True)
class Vehicle:
    firmware: str                   # "ardupilot" | "px4"
    frame: str                      # "copter" | "plane" | "vtol"
    speed_mps: float
    max_mission_items: int | None = None


@dataclass(frozen=True)
class Home:
    lat: float
    lon: float
    alt_amsl_m: float


@dataclass(frozen=True)
class Payload:
    name: str
    camera: str                                    # catalogue id
    imager: str | None = None                      # None: the camera's first imager with known optics
    lens_mm: float | None = None
    component_id: int = 100
    component_given: bool = True                   # False: chosen by the loader (see REDEDGE_COMPONENT)
    landscape: bool = True
    settings: tuple[tuple[str, Any], ...] = ()     # as written in the plan
    values: tuple[tuple[str, float | int], ...] = ()   # checked wire values (Setting.check), same order

    def value(self, key: str) -> float | int | None:
        return dict(self.values).get(key)


@dataclass(frozen=True)
class TakeoffStep:
    index: int
    alt_m: float


@dataclass(frozen=True)
class SurveyStep:
    index: int
    area: str | tuple[tuple[float, float], ...]
    payloads: tuple[str, ...]
    front_pct: float
    side_pct: float
    altitude_m: float | None = None
    gsd_cm: float | None = None
    exclude: tuple[Any, ...] = ()
    angle_deg: float | str = "auto"
    trigger: str = "distance"
    turnaround_m: float | None = None
    refly_90: bool = False


@dataclass(frozen=True)
class CorridorStep:
    index: int
    line: tuple[tuple[float, float], ...]
    width_m: float
    payloads: tuple[str, ...]
    front_pct: float
    side_pct: float
    altitude_m: float | None = None
    gsd_cm: float | None = None
    trigger: str = "distance"
    turnaround_m: float | None = None


@dataclass(frozen=True)
class WaypointStep:
    index: int
    lat: float
    lon: float
    alt_m: float
    hold_s: float = 0.0
    capture: str | None = None


@dataclass(frozen=True)
class CameraStep:
    index: int
    payload: str
    settings: tuple[tuple[str, Any], ...]
    values: tuple[tuple[str, float | int], ...]


@dataclass(frozen=True)
class RtlStep:
    index: int


@dataclass(frozen=True)
class LandStep:
    index: int
    lat: float | None = None
    lon: float | None = None


Step = TakeoffStep | SurveyStep | CorridorStep | WaypointStep | CameraStep | RtlStep | LandStep


@dataclass(frozen=True)
class Plan:
    version: int
    name: str
    vehicle: Vehicle
    home: Home
    payloads: tuple[Payload, ...]
    mission: tuple[Step, ...]
    path: str = "<plan>"
    base_dir: str = "."
    notes: tuple[str, ...] = ()          # decisions the loader took for the user (e.g. a moved component id)
    locations: Mapping[tuple, str] = field(default_factory=lambda: MappingProxyType({}), compare=False, repr=False)

    def payload(self, name: str) -> Payload:
        return next(p for p in self.payloads if p.name == name)

    def where(self, *path: Any) -> str:
        """file:line:col of the deepest located node on `path` (the file name when nothing is located)."""
        p = tuple(path)
        while p:
            if p in self.locations:
                return self.locations[p]
            p = p[:-1]
        return self.locations.get((), self.path)

    def step_where(self, step: Step, *path: Any) -> str:
        kind = _STEP_KIND[type(step)]
        return self.where("mission", step.index, kind, *path)


_STEP_KIND = {TakeoffStep: "takeoff", SurveyStep: "survey", CorridorStep: "corridor", WaypointStep: "waypoint",
              CameraStep: "camera", RtlStep: "rtl", LandStep: "land"}


# --------------------------------------------------------------------------------------------- YAML pass

class _Budget(Exception):
    pass


class _Yaml:
    """Node tree -> plain Python values, recording where every value and key is."""

    def __init__(self, file: str, problems: list[Problem]) -> None:
        self.file = file
        self.problems = problems
        self.values: dict[tuple, tuple[int, int]] = {}
        self.keys: dict[tuple, tuple[int, int]] = {}
        # values already reported here and read as None (.inf, a YAML tag): the schema pass skips them,
        # or `name: .inf` would also be "name must be text, got nothing"
        self.reported: set[tuple] = set()
        self.quoted: set[tuple] = set()     # values written in quotes: "remove the quotes" is a fix only there
        self.nodes = 0

    def loc(self, mark: Any) -> str:
        return f"{self.file}:{mark.line + 1}:{mark.column + 1}"

    def convert(self, node: Any, path: tuple, depth: int = 0) -> Any:
        import yaml

        self.nodes += 1
        if self.nodes > MAX_NODES:
            raise _Budget(f"the YAML expands to more than {MAX_NODES} nodes (aliases?)")
        if depth > MAX_DEPTH:
            raise _Budget(f"the YAML is nested deeper than {MAX_DEPTH} levels")
        self.values.setdefault(path, (node.start_mark.line, node.start_mark.column))
        if isinstance(node, yaml.MappingNode):
            out: dict[str, Any] = {}
            for knode, vnode in node.value:
                if not isinstance(knode, yaml.ScalarNode) or knode.tag == "tag:yaml.org,2002:merge":
                    what = "merge keys (<<)" if isinstance(knode, yaml.ScalarNode) else "complex keys"
                    self.problems.append(Problem(self.loc(knode.start_mark), f"{what} are not supported",
                                                 "write the keys out"))
                    continue
                key = knode.value
                if key in out:
                    self.problems.append(Problem(self.loc(knode.start_mark), f"duplicate key {shown(key)}",
                                                 "YAML keeps only the last one; remove one of them"))
                    continue
                self.keys[path + (key,)] = (knode.start_mark.line, knode.start_mark.column)
                out[key] = self.convert(vnode, path + (key,), depth + 1)
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.convert(v, path + (i,), depth + 1) for i, v in enumerate(node.value)]
        return self.scalar(node, path)

    def scalar(self, node: Any, path: tuple) -> Any:
        import yaml

        tag, text = node.tag, node.value
        if node.style in ("'", '"'):
            self.quoted.add(path)
        if node.style is None and tag == "tag:yaml.org,2002:str" and _EXPONENT_NUMBER.fullmatch(text):
            # YAML 1.1 reads 1e-9 and 1.0e308 (no dot, or no sign in the exponent) as text, YAML 1.2 and
            # every editor as numbers: read them as numbers, as booleans are read the YAML 1.2 way
            return self.number(float(text), text, node, path)
        if tag == "tag:yaml.org,2002:str" or node.style in ("'", '"', "|", ">"):
            return text
        if tag == "tag:yaml.org,2002:null":
            return None
        if tag == "tag:yaml.org,2002:bool":
            # YAML 1.1 booleans yes/no/on/off stay text: `alarm_mode: off` means the option "off".
            return {"true": True, "false": False}.get(text.lower(), text)
        if tag in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float"):
            try:
                c = yaml.constructor.SafeConstructor()
                value = c.construct_yaml_int(node) if tag.endswith("int") else c.construct_yaml_float(node)
            except ValueError:      # more digits than Python converts (4300)
                self.problems.append(Problem(self.loc(node.start_mark),
                                             f"a number of {len(text)} characters is too long to read",
                                             "write the value with a few digits (a plan's quantities are metres, "
                                             "seconds, percent: small numbers)"))
                self.reported.add(path)
                return None
            except (TypeError, OverflowError, yaml.YAMLError):
                return text
            return self.number(value, text, node, path)
        if tag == "tag:yaml.org,2002:timestamp":
            return text
        self.problems.append(Problem(self.loc(node.start_mark), f"YAML tag {shown(tag)} is not allowed in a plan",
                                     "remove the tag"))
        self.reported.add(path)
        return None

    def number(self, value: int | float, text: str, node: Any, path: tuple) -> int | float | None:
        """A number read from the YAML, or None and a problem when it is not finite."""
        if isinstance(value, float) and not math.isfinite(value):
            self.problems.append(Problem(self.loc(node.start_mark), f"{shown(text)} is not a finite number",
                                         "YAML reads .inf and .nan (and 1e999) as numbers: give a finite one, or "
                                         "quote the text if that is what you meant"))
            self.reported.add(path)
            return None
        return value


# A number with an exponent as YAML 1.2 writes it (1e-9, 2E5, 1.0e308), which YAML 1.1 resolves as text.
_EXPONENT_NUMBER = re.compile(r"[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)[eE][-+]?[0-9]+")

_TOO_DEEP_HINT = "a plan nests a few levels deep; look for unclosed brackets or runaway indentation"


def _parse_yaml(text: str, file: str, problems: list[Problem]) -> tuple[Any, _Yaml]:
    import yaml

    conv = _Yaml(file, problems)
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = conv.loc(mark) if mark is not None else file
        msg = " ".join(x for x in (e.context, e.problem) if x) or "invalid YAML"
        problems.append(Problem(where, f"invalid YAML: {msg}", "check indentation, colons and quotes"))
        return None, conv
    except yaml.YAMLError as e:
        problems.append(Problem(file, f"invalid YAML: {clip(str(e), 2 * ECHO_CHARS)}", "check indentation, colons and quotes"))
        return None, conv
    except RecursionError:
        problems.append(Problem(file, "the YAML is nested too deeply", _TOO_DEEP_HINT))
        return None, conv
    if node is None:
        problems.append(Problem(file, "the plan is empty", "start from `wiris mission schema` or examples/"))
        return None, conv
    try:
        data = conv.convert(node, ())
    except _Budget as e:
        problems.append(Problem(file, str(e), "write the plan without anchors and aliases"))
        return None, conv
    except RecursionError:
        problems.append(Problem(file, "the YAML is nested too deeply", _TOO_DEEP_HINT))
        return None, conv
    return data, conv


# ------------------------------------------------------------------------------------------- schema pass

# Names people write without the unit (or with another unit) -> the plan's name.
_UNIT_STEMS = ("_m", "_mps", "_cm", "_s", "_deg", "_mm", "_amsl_m", "_pct")


def _unknown_key_hint(key: str, allowed: Iterable[str]) -> str:
    allowed = sorted(allowed)
    stem = key.lower()
    for suffix in ("_ft", "_feet", "_km", "_kmh", "_kph", "_ms", "_mph", "_min", "_deg", "_rad", "_in", "_cm",
                   "_m", "_s", "_mm", "_percent", "_pct"):
        if stem.endswith(suffix):
            stem = stem[: -len(suffix)]
            break
    same_stem = [a for a in allowed if a != key and (a == stem or a.startswith(stem + "_"))]
    if same_stem and stem != key:
        return (f"did you mean {same_stem[0]!r}? names carry their unit and the units are fixed "
                f"(metres, seconds, m/s, cm/px, degrees)")
    if same_stem:
        return f"did you mean {same_stem[0]!r}? names carry their unit"
    close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
    if close:
        return f"did you mean {close[0]!r}?"
    return f"allowed here: {', '.join(allowed)}" if allowed else "no keys are allowed here"


def _schema_at(schema: dict, path: Iterable[Any]) -> dict:
    """The sub-schema describing `path` (good enough for our schema's shape: objects and arrays)."""
    s = schema
    for p in path:
        if isinstance(p, int):
            s = s.get("items", {}) if isinstance(s.get("items"), dict) else {}
        else:
            props = s.get("properties", {})
            s = props[p] if p in props else (s.get("additionalProperties") or {})
            if not isinstance(s, dict):
                s = {}
    return s


def _schema_problems(data: Any, conv: _Yaml, problems: list[Problem]) -> None:
    import jsonschema

    schema = plan_schema()
    validator = jsonschema.Draft202012Validator(schema)
    seen: set[tuple] = set()
    for err in validator.iter_errors(data):
        if _already_reported(err, conv.reported):
            continue
        for problem in _translate(err, conv):
            if problem.hint is None:
                problem = replace(problem, hint=_fallback_hint(err))
            k = (problem.where, problem.message)
            if k not in seen:
                seen.add(k)
                problems.append(problem)


_AREA_HINT = "a KML or GeoJSON file next to the plan, e.g. area: areas/field.kml, or [[lat, lon], [lat, lon], ...]"
_LATLON_HINT = "two numbers, WGS84 degrees: [lat, lon], e.g. [50.0696, 14.7263]"

# How to write a value of each JSON type in YAML: the hint of a type error (with the field's description)
_FORMS = {"object": "indent its keys below it, or write {key: value, ...}",
          "array": "write a list: [a, b] on one line, or one `- item` per line",
          "number": "write a plain number, without quotes or a unit",
          "integer": "write a whole number, without quotes",
          "string": "write text (quote it if YAML would read it as a number or true/false)",
          "boolean": "write true or false"}


def _fallback_hint(err: Any) -> str:
    """A hint for a schema error that _translate has none for: what the field is (its description) and,
    for a wrong type, how to write the right one."""
    sub = _schema_at(plan_schema(), tuple(err.absolute_path))
    desc = sub.get("description")
    form = None
    expected = sub.get("type")
    if isinstance(expected, list):
        expected = next((t for t in expected if t != "null"), None)
    if expected == "object" and sub.get("properties") == {}:
        form = "write {} (it takes no keys)"
    elif expected == "object" and sub.get("properties"):
        keys = sub.get("required") or list(sub["properties"])[:4]
        form = "write {" + ", ".join(f"{k}: ..." for k in keys) + "}" + (" (or leave it empty)" if not sub.get(
            "required") and "null" in (sub.get("type") or []) else "")
    elif isinstance(expected, str):
        form = _FORMS.get(expected)
    if err.validator in _BOUNDS:
        span = _range_text(sub)
        return f"{desc}: {span}" if desc else span
    if desc and (err.validator == "type" or form is None):
        return f"{desc}: {form}" if err.validator == "type" and form else desc
    return form or "see `wiris mission schema` for the plan format"


_BOUNDS = ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum")


def _range_text(sub: dict) -> str:
    """The range a number schema allows, in words: "from 0 to 500", "above 0 and at most 1000"."""
    low = (f"from {sub['minimum']:g}" if "minimum" in sub else
           f"above {sub['exclusiveMinimum']:g}" if "exclusiveMinimum" in sub else "")
    high = (f"to {sub['maximum']:g}" if "maximum" in sub and "minimum" in sub else
            f"at most {sub['maximum']:g}" if "maximum" in sub else
            f"below {sub['exclusiveMaximum']:g}" if "exclusiveMaximum" in sub else "")
    joint = " and " if low.startswith("above") and high else " "
    return (low + joint + high).strip() or "a number"


def _already_reported(err: Any, reported: set[tuple]) -> bool:
    """Whether a schema error is about a value the YAML pass reported (and read as None): that value
    itself, or an anyOf (an area) that fails because of it."""
    path = tuple(err.absolute_path)
    if path in reported:
        return True
    return err.validator == "anyOf" and any(r[:len(path)] == path for r in reported)


def _at(conv: _Yaml, path: tuple, key: bool = False) -> str:
    table = conv.keys if key else conv.values
    p = tuple(path)
    while p:
        if p in table:
            line, col = table[p]
            return f"{conv.file}:{line + 1}:{col + 1}"
        p = p[:-1]
    return conv.file


def _field_name(path: tuple) -> str:
    names = [str(p) if not isinstance(p, int) else f"[{p}]" for p in path]
    return ".".join(names).replace(".[", "[") or "plan"


def _translate(err: Any, conv: _Yaml) -> list[Problem]:
    path = tuple(err.absolute_path)
    where = _at(conv, path)
    name = _field_name(path)
    last = path[-1] if path else "plan"
    v = err.validator
    inst = err.instance
    schema = err.schema if isinstance(err.schema, dict) else {}
    hint = schema.get("x-hint")
    if v == "additionalProperties" and isinstance(inst, dict):
        allowed = set((schema.get("properties") or {}).keys())
        out = []
        for k in inst:
            if k not in allowed:
                if path and path[0] == "mission" and len(path) == 2:
                    msg, h = f"unknown mission step {shown(k)}", _unknown_key_hint(k, STEPS)
                else:
                    msg, h = f"unknown key {shown(k)} in {name}", _unknown_key_hint(k, allowed)
                out.append(Problem(_at(conv, path + (k,), key=True), msg, h))
        return out
    if v == "required":
        missing = [r for r in err.validator_value if isinstance(inst, dict) and r not in inst]
        return [Problem(where, f"{name} needs {m!r}", _schema_at(plan_schema(), path + (m,)).get("description"))
                for m in missing]
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        if last in ("altitude_m", "alt_m"):
            low = v.startswith("min") or v == "exclusiveMinimum"
            msg = (f"altitude {shown(inst)} m is {'below' if low else 'above'} the "
                   f"{MIN_ALTITUDE_M if low else MAX_ALTITUDE_M:g} m {'minimum' if low else 'maximum'}")
            return [Problem(where, msg, hint)]
        if path and path[-2:-1] == ("overlap",) and v == "exclusiveMaximum":
            return [Problem(where, f"{last} overlap {shown(inst)} %: overlap must be below 100 % (at 100 % the photos "
                            "never move on)", hint or "overlap in percent, e.g. 80")]
        return [Problem(where, _out_of_range(name, shown(inst), v, err.validator_value), hint)]
    if v == "type":
        expected = err.validator_value
        exp = " or ".join(map(_article, expected)) if isinstance(expected, list) else _article(expected)
        if expected == "object" and path and path[0] == "mission" and len(path) == 2 and isinstance(inst, str):
            return [Problem(where, f"mission step {shown(inst)} needs a colon and a body",
                            f"write `- {inst}: {{}}`" if inst in STEPS else _unknown_key_hint(inst, STEPS))]
        if expected in ("number", "integer") and isinstance(inst, str):
            hint = _number_in_text_hint(inst, quoted=path in conv.quoted) or hint
        return [Problem(where, f"{name} must be {exp}, got {_describe(inst)}", hint)]
    if v == "enum":
        opts = ", ".join(str(o) for o in err.validator_value)
        close = difflib.get_close_matches(str(inst), [str(o) for o in err.validator_value], n=1)
        return [Problem(where, f"{name}: {shown(inst)} is not one of {opts}",
                        f"did you mean {close[0]!r}?" if close else hint)]
    if v == "const":
        return [Problem(where, f"{name} must be {err.validator_value!r}, got {shown(inst)}",
                        "this tool reads capture-plan format version 1" if last == "version" else hint)]
    if v in ("minItems", "maxItems"):
        if last == "line":
            return [Problem(where, "a corridor line needs at least 2 points", "give [[lat, lon], [lat, lon], ...]")]
        if name.endswith("area") or "exclude" in path:
            return [Problem(where, "an inline area needs at least 3 [lat, lon] points", _AREA_HINT)]
        if isinstance(inst, list) and len(inst) in (2, 3) or schema.get("description", "").startswith("[lat"):
            return [Problem(where, f"{name} must be [lat, lon], got {_describe(inst)}", _LATLON_HINT)]
        return [Problem(where, f"{name}: {clip(err.message, 2 * ECHO_CHARS)}")]
    if v == "minProperties" or v == "maxProperties":
        if path and path[0] == "mission" and len(path) == 2:
            return [Problem(where, "each mission step is one of " + ", ".join(STEPS) +
                            ", written as `- name: {...}`", "start a new list item (`-`) for each step")]
        return [Problem(where, f"{name} must not be empty")]
    if v == "anyOf":
        if last in ("area",) or (len(path) >= 2 and path[-2] == "exclude"):
            return [Problem(where, f"{name} must be a file path or a list of at least 3 [lat, lon] points, got "
                            f"{_describe(inst)}", _AREA_HINT)]
        if last == "angle_deg":
            return [Problem(where, f"angle_deg must be 'auto' or a number of degrees -360..360, got {shown(inst)}",
                            "degrees clockwise from north, e.g. angle_deg: 30 (0 = north-south lines)")]
    if v == "uniqueItems":
        return [Problem(where, f"{name} lists a name twice", "name each payload once")]
    if v == "pattern":
        if last == "name":
            return [Problem(where, f"name {shown(inst)} must be a file-name-safe word (letters, digits, . _ -), at most 64",
                            "output files are named after it")]
        return [Problem(where, f"{name}: {shown(inst)} is not allowed here ({clip(err.message, 2 * ECHO_CHARS)})")]
    if v == "propertyNames":
        return [Problem(where, f"payload name {shown(err.instance)} must be a word (letters, digits, _ -)",
                        "start with a letter or _, at most 32 characters, e.g. thermal")]
    return [Problem(where, f"{name}: {clip(err.message, 2 * ECHO_CHARS)}", hint)]


def _out_of_range(name: str, value: str, bound: str, limit: float) -> str:
    """The message of a value beyond a schema bound (minimum, maximum, exclusiveMinimum, exclusiveMaximum)."""
    if bound == "minimum":
        return f"{name} {value} is below the minimum of {limit:g}"
    if bound == "maximum":
        return f"{name} {value} is above the maximum of {limit:g}"
    return f"{name} must be {'greater' if bound == 'exclusiveMinimum' else 'less'} than {limit:g}, got {value}"


def _article(t: str) -> str:
    return {"object": "a mapping", "array": "a list", "number": "a number", "integer": "a whole number",
            "string": "text", "boolean": "true or false", "null": "nothing"}.get(t, t)


def _number_in_text_hint(text: str, quoted: bool) -> str | None:
    """For a number written as text: '40' (quoted) or '40 m' / '40m' (with a unit)."""
    m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*)?", text)
    if m is None:
        return None
    if m.group(2):
        return f"write the number alone ({clip(m.group(1))}): the unit is fixed by the key's name"
    return f"remove the quotes: {clip(m.group(1))}" if quoted else None


def _describe(v: Any) -> str:
    if v is None:
        return "nothing"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, dict):
        return "a mapping"
    if isinstance(v, list):
        return f"a list of {len(v)}"
    return shown(v)


# ----------------------------------------------------------------------------------------- meaning pass

def _num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_file(p: Path) -> tuple[bool, str]:
    """Whether p is a regular file, and if not, why in a few words. Path.is_file() raises for a name the
    system refuses (longer than NAME_MAX, a NUL byte) instead of answering False."""
    try:
        other = not_a_file(p.stat().st_mode)
    except FileNotFoundError:
        return False, "not found"
    except (OSError, ValueError) as e:
        return False, f"cannot be looked up ({getattr(e, 'strerror', None) or e})"
    return (False, f"{other}, not a file") if other else (True, "")


def _check_settings(camera: Any, settings: Any, path: tuple, conv: _Yaml, problems: list[Problem],
                    state: dict[str, float | int]) -> tuple[tuple[tuple[str, Any], ...], tuple[tuple[str, Any], ...]]:
    """Check settings against the catalogue; return (as written, checked values)."""
    from cdf.errors import CdfError

    if not isinstance(settings, dict):
        return (), ()
    raw, values = [], []
    for key, value in settings.items():
        s = camera.setting(key)
        if s is None:
            keys = [x.key for x in camera.settings]
            close = difflib.get_close_matches(key, keys, n=1)
            problems.append(Problem(_at(conv, path + (key,), key=True),
                                    f"{camera.id} has no setting {shown(key)}",
                                    (f"did you mean {close[0]!r}? " if close else "") + "settings: " + ", ".join(keys)))
            continue
        try:
            checked = s.check(value)
        except CdfError as e:
            problems.append(Problem(_at(conv, path + (key,)), f"{camera.id}: {e.message}", e.hint))
            continue
        raw.append((key, value))
        values.append((key, checked))
    given = dict(values)
    merged = {**state, **given}
    for key, _ in values:
        s = camera.setting(key)
        if s.command and s.command.when:
            for wkey, wval in s.command.when:
                if merged.get(wkey) != wval:
                    opt = camera.option_key(wkey, wval)
                    problems.append(Problem(_at(conv, path + (key,), key=True),
                                            f"{key} takes effect only with {wkey}: {opt}",
                                            f"add `{wkey}: {opt}` to the same settings"))
    # A message such as DIGICAM_CONFIGURE sends every field at once and, unlike a MAV_CMD (NaN), has no
    # value meaning "keep": a field whose `when` holds must be given, or the camera would get a made-up one.
    for s in camera.settings:
        slot = s.command
        if slot is None or slot.message in (None, "PARAM_SET") or not slot.when or s.key in merged:
            continue
        trigger = next((k for k, v in slot.when if k in given and given[k] == v), None)
        if trigger is not None and all(merged.get(k) == v for k, v in slot.when):
            opt = camera.option_key(trigger, given[trigger])
            problems.append(Problem(_at(conv, path + (trigger,)),
                                    f"{trigger}: {opt} also needs {s.key} ({s.label}): the {slot.message} message "
                                    "carries it and has no value meaning 'keep'",
                                    f"add `{s.key}` to the same settings"))
    state.update(given)
    return tuple(raw), tuple(values)


def _meaning(data: dict, conv: _Yaml, problems: list[Problem], base_dir: Path) -> tuple[dict, list[str]]:
    """Checks beyond the schema. Returns resolved component ids by payload name and notes."""
    from cdf.catalogue import catalogue
    from cdf.errors import CdfError

    cat = catalogue()
    notes: list[str] = []
    payloads = data.get("payloads") if isinstance(data.get("payloads"), dict) else {}
    cameras: dict[str, Any] = {}
    for name, p in payloads.items():
        if not isinstance(p, dict) or not isinstance(p.get("camera"), str):
            continue
        try:
            cam = cat.get(p["camera"])
        except CdfError as e:
            problems.append(Problem(_at(conv, ("payloads", name, "camera")), f"payload {name}: {e.message}",
                                    f"{e.hint} (cameras: {', '.join(cat.ids)})"))
            continue
        cameras[name] = cam
        imager = p.get("imager")
        if isinstance(imager, str) and cam.imager(imager) is None:
            problems.append(Problem(_at(conv, ("payloads", name, "imager")),
                                    f"{cam.id} has no imager {shown(imager)}",
                                    "imagers: " + ", ".join(i.id for i in cam.imagers)))
        cid = p.get("component_id")
        if isinstance(cid, int) and not isinstance(cid, bool) and cid not in cam.component_ids:
            problems.append(Problem(_at(conv, ("payloads", name, "component_id")),
                                    f"{cam.model} cannot use component id {cid}",
                                    f"allowed: {', '.join(map(str, cam.component_ids))}"
                                    + (" (the RedEdge answers only on 100)" if cam.protocol == "rededge-serial" else "")))
    # settings, per payload; the state carries across in-flight changes for `when` checks
    states: dict[str, dict] = {}
    for name, cam in cameras.items():
        states[name] = {}
        _check_settings(cam, payloads[name].get("settings"), ("payloads", name, "settings"), conv, problems,
                        states[name])

    # component ids: explicit ones first, then fill in
    comp: dict[str, int] = {}
    taken: dict[int, str] = {}
    for name, cam in cameras.items():
        cid = payloads[name].get("component_id")
        if isinstance(cid, int) and not isinstance(cid, bool) and cid in COMPONENT_IDS:
            if cid in taken:
                other = taken[cid]
                red = [n for n in (name, other) if cameras[n].protocol == "rededge-serial"]
                wiris = [n for n in (name, other) if cameras[n].protocol != "rededge-serial"]
                if red and wiris:
                    msg = (f"payloads {other} and {name} are both on component {cid}: the RedEdge ({red[0]}) "
                           f"is fixed at {REDEDGE_COMPONENT}")
                    hint = f"set the WIRIS ({wiris[0]}) to a free id of 101..105 in its menu and here"
                else:
                    msg = f"payloads {other} and {name} are both on component {cid}"
                    hint = "each camera needs its own component id 100..105"
                problems.append(Problem(_at(conv, ("payloads", name, "component_id")), msg, hint))
            else:
                taken[cid] = name
            comp[name] = cid
    for name, cam in cameras.items():
        if name in comp:
            continue
        if cam.protocol == "rededge-serial":
            cid = REDEDGE_COMPONENT
            if cid in taken and taken[cid] != name:
                problems.append(Problem(_at(conv, ("payloads", taken[cid], "component_id")),
                                        f"payload {taken[cid]} is on component {cid}, where the RedEdge ({name}) "
                                        "is fixed", "move the WIRIS to a free id of 101..105 in its menu and here"))
        else:
            free = [c for c in cam.component_ids if c not in taken]
            has_rededge = any(c.protocol == "rededge-serial" for c in cameras.values())
            if has_rededge:
                free = [c for c in free if c != REDEDGE_COMPONENT]
            if not free:
                problems.append(Problem(_at(conv, ("payloads", name)), f"no free component id for {name}",
                                        f"ids 100..105 are all taken; {cam.model} can use "
                                        f"{', '.join(map(str, cam.component_ids))}"))
                continue
            cid = free[0]
            if has_rededge or cid != cam.default_component_id:
                notes.append(f"payload {name}: component_id not given, using {cid}"
                             + (" (100 is the RedEdge's)" if has_rededge else "")
                             + "; set the same id in the camera's menu")
        comp[name] = cid
        taken.setdefault(cid, name)

    # mission steps
    mission = data.get("mission") if isinstance(data.get("mission"), list) else []
    defined = sorted(payloads)
    for i, step in enumerate(mission):
        if not isinstance(step, dict) or len(step) != 1:
            continue
        kind, body = next(iter(step.items()))
        if not isinstance(body, dict):
            continue
        base = ("mission", i, kind)

        def payload_ref(ref: Any, path: tuple) -> None:
            if isinstance(ref, str) and ref not in payloads:
                close = difflib.get_close_matches(ref, defined, n=1)
                problems.append(Problem(_at(conv, path), f"unknown payload {shown(ref)}",
                                        (f"did you mean {close[0]!r}? " if close else "")
                                        + f"payloads defined: {', '.join(defined) or 'none'}"))

        if kind in ("survey", "corridor"):
            refs = body.get("payloads") if isinstance(body.get("payloads"), list) else []
            for j, ref in enumerate(refs):
                payload_ref(ref, base + ("payloads", j))
            has_alt, has_gsd = "altitude_m" in body, "gsd_cm" in body
            if has_alt and has_gsd:
                problems.append(Problem(_at(conv, base + ("gsd_cm",), key=True),
                                        f"{kind} gives both altitude_m and gsd_cm",
                                        "give exactly one: the other follows from the first payload's optics"))
            elif not has_alt and not has_gsd:
                problems.append(Problem(_at(conv, base), f"{kind} needs altitude_m or gsd_cm",
                                        "e.g. altitude_m: 40, or gsd_cm: 3.5"))
            ov = body.get("overlap") if isinstance(body.get("overlap"), dict) else {}
            for side in ("front", "side"):
                v = ov.get(side)
                if _num(v) and MAX_OVERLAP_PCT < v < 100:
                    problems.append(Problem(_at(conv, base + ("overlap", side)),
                                            f"{side} overlap {v} % is above the {MAX_OVERLAP_PCT:g} % this planner "
                                            "accepts", "photos would be closer than GNSS position noise; "
                                            "thermal mapping usually flies 90/80"))
            frame = data["vehicle"].get("frame") if isinstance(data.get("vehicle"), dict) else None
            if body.get("trigger") == "hover" and frame in ("plane", "vtol"):
                # a VTOL flies the mission in fixed-wing flight after NAV_VTOL_TAKEOFF (the compiler emits no
                # transition back to multicopter): ArduPlane drops NAV_WAYPOINT's hold time, PX4 flies through
                problems.append(Problem(_at(conv, base + ("trigger",)),
                                        "a plane cannot hover" if frame == "plane" else
                                        "a VTOL flies the mission in fixed-wing flight and cannot hover there",
                                        "use trigger: distance"))
            area, exclude = body.get("area"), body.get("exclude")
            # a wrong type of either (exclude: 5) is the schema's finding: only strings are looked up here
            sources = [area] + (exclude if isinstance(exclude, list) else []) if kind == "survey" else []
            for j, src in enumerate(sources):
                if isinstance(src, str) and src:
                    p = Path(src) if Path(src).is_absolute() else base_dir / src
                    found, why = _is_file(p)
                    if not found:
                        at = base + ("area",) if j == 0 else base + ("exclude", j - 1)
                        problems.append(Problem(_at(conv, at), f"area file {shown(src)} {why} (looked at {clip(str(p), 2 * ECHO_CHARS)})",
                                                "paths in a plan are relative to the plan file"))
        elif kind == "waypoint":
            payload_ref(body.get("capture"), base + ("capture",))
        elif kind == "land" and ("lat" in body) != ("lon" in body):
            problems.append(Problem(_at(conv, base), "land needs both lat and lon, or neither (land where it is)",
                                    "give the landing point as lat and lon, or remove both"))
        elif kind == "camera":
            ref = body.get("payload")
            payload_ref(ref, base + ("payload",))
            if isinstance(ref, str) and ref in cameras:
                _check_settings(cameras[ref], body.get("settings"), base + ("settings",), conv, problems,
                                states[ref])
    return comp, notes


# ----------------------------------------------------------------------------------------------- building

def _pairs(points: Any) -> tuple[tuple[float, float], ...]:
    return tuple((float(p[0]), float(p[1])) for p in points)


def _area_value(v: Any) -> Any:
    return v if isinstance(v, str) else _pairs(v)


def _build(data: dict, comp: dict[str, int], path: str, base_dir: Path, notes: list[str],
           locations: Mapping) -> Plan:
    from cdf.catalogue import catalogue

    cat = catalogue()
    v = data["vehicle"]
    payloads = []
    for name, p in data["payloads"].items():
        cam = cat.get(p["camera"])
        settings = p.get("settings") or {}
        checked = tuple((k, cam.setting(k).check(val)) for k, val in settings.items())
        payloads.append(Payload(
            name=name, camera=cam.id, imager=p.get("imager"),
            lens_mm=float(p["lens_mm"]) if "lens_mm" in p else None,
            component_id=comp[name], component_given="component_id" in p,
            landscape=p.get("orientation", "landscape") == "landscape",
            settings=tuple((k, tuple(x) if isinstance(x, list) else x) for k, x in settings.items()),
            values=checked))
    steps: list[Step] = []
    for i, step in enumerate(data["mission"]):
        kind, b = next(iter(step.items()))
        b = b or {}
        if kind == "takeoff":
            steps.append(TakeoffStep(i, float(b["alt_m"])))
        elif kind == "survey":
            ov = b["overlap"]
            steps.append(SurveyStep(
                i, _area_value(b["area"]), tuple(b["payloads"]), float(ov["front"]), float(ov["side"]),
                altitude_m=float(b["altitude_m"]) if "altitude_m" in b else None,
                gsd_cm=float(b["gsd_cm"]) if "gsd_cm" in b else None,
                exclude=tuple(_area_value(x) for x in b.get("exclude", ())),
                angle_deg=b.get("angle_deg", "auto") if b.get("angle_deg", "auto") == "auto" else float(b["angle_deg"]),
                trigger=b.get("trigger", "distance"),
                turnaround_m=float(b["turnaround_m"]) if "turnaround_m" in b else None,
                refly_90=bool(b.get("refly_90", False))))
        elif kind == "corridor":
            ov = b["overlap"]
            steps.append(CorridorStep(
                i, _pairs(b["line"]), float(b["width_m"]), tuple(b["payloads"]), float(ov["front"]),
                float(ov["side"]), altitude_m=float(b["altitude_m"]) if "altitude_m" in b else None,
                gsd_cm=float(b["gsd_cm"]) if "gsd_cm" in b else None, trigger=b.get("trigger", "distance"),
                turnaround_m=float(b["turnaround_m"]) if "turnaround_m" in b else None))
        elif kind == "waypoint":
            steps.append(WaypointStep(i, float(b["lat"]), float(b["lon"]), float(b["alt_m"]),
                                      float(b.get("hold_s", 0.0)), b.get("capture")))
        elif kind == "camera":
            cam = cat.get(data["payloads"][b["payload"]]["camera"])
            steps.append(CameraStep(i, b["payload"], tuple((k, tuple(x) if isinstance(x, list) else x)
                                                           for k, x in b["settings"].items()),
                                    tuple((k, cam.setting(k).check(val)) for k, val in b["settings"].items())))
        elif kind == "rtl":
            steps.append(RtlStep(i))
        elif kind == "land":
            steps.append(LandStep(i, b.get("lat"), b.get("lon")))
    h = data["home"]
    return Plan(
        version=int(data["version"]), name=data.get("name") or _default_name(path),
        vehicle=Vehicle(v["firmware"], v["frame"], float(v["speed_mps"]), v.get("max_mission_items")),
        home=Home(float(h["lat"]), float(h["lon"]), float(h["alt_amsl_m"])),
        payloads=tuple(payloads), mission=tuple(steps), path=path, base_dir=str(base_dir), notes=tuple(notes),
        locations=locations)


def _default_name(path: str) -> str:
    import re

    stem = Path(path).name
    for suffix in (".yaml", ".yml"):
        if stem.lower().endswith(suffix):
            stem = stem[: -len(suffix)]
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", stem).lstrip(".-_") or "plan"
    return stem[:64]


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
    data, conv = _parse_yaml(text, path, problems)
    if data is None:
        raise_problems(problems, path)
    if not isinstance(data, dict):
        problems.append(Problem(_at(conv, ()), f"a plan is a mapping of keys, got {_describe(data)}",
                                "start from `wiris mission schema` or examples/"))
        raise_problems(problems, path)
    _schema_problems(data, conv, problems)
    comp, notes = _meaning(data, conv, problems, base)
    raise_problems(problems, path)
    locations = {p: f"{path}:{l + 1}:{c + 1}" for p, (l, c) in conv.values.items()}
    locations[()] = path
    try:
        return _build(data, comp, path, base, notes, MappingProxyType(locations))
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
