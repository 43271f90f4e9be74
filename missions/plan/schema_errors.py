"""The plan's second pass: the JSON Schema (`missions.plan.schema`), each error said for a person.

    schema_problems(data, yaml_doc, problems)     # appends Problem values located at file:line:col

jsonschema's messages name a validator ("'40 m' is not of type 'number'"); here each error is mapped back to
where it was written and said in the plan's words: unknown keys answered with "did you mean" (difflib) and
unit hints (`altitude: 40` -> altitude_m), a number written with its unit or in quotes, the range a bound
allows, and for everything else the field's description and how to write its type in YAML.
"""

from __future__ import annotations

from dataclasses import replace
import difflib
import re
from typing import Any, Callable, Iterable, NamedTuple

from cdf.errors import ECHO_CHARS, clip, shown
from missions.errors import Problem
from missions.plan.schema import MAX_ALTITUDE_M, MIN_ALTITUDE_M, STEPS, ZONE_KINDS, plan_schema
from missions.plan.yaml_reader import PositionedYaml


def schema_problems(data: Any, doc: PositionedYaml, problems: list[Problem]) -> None:
    """Append a located problem for each schema error (once each), skipping values the YAML pass reported."""
    import jsonschema   # heavy: `wiris mission schema` imports this package and prints the schema without it

    schema = plan_schema()
    validator = jsonschema.Draft202012Validator(schema)
    seen: set[tuple] = set()
    for err in validator.iter_errors(data):
        if _already_reported(err, doc.reported):
            continue
        for problem in _translate(err, doc):
            if problem.hint is None:
                problem = replace(problem, hint=_fallback_hint(err))
            problem = replace(problem, path=tuple(err.absolute_path))
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


def _unknown_key_hint(key: str, allowed: Iterable[str]) -> str:
    """Names people write without the unit (or with another unit), or misspelt -> the plan's name."""
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


def _field_name(path: tuple) -> str:
    names = [str(p) if not isinstance(p, int) else f"[{p}]" for p in path]
    return ".".join(names).replace(".[", "[") or "plan"


class _SchemaError(NamedTuple):
    """One jsonschema error with what every translation of it needs."""

    err: Any                 # jsonschema.ValidationError
    doc: PositionedYaml
    path: tuple              # where in the plan's values the error is
    where: str               # file:line:col of that value
    name: str                # the field as a person reads it: mission[1].survey.altitude_m
    last: Any                # the last key (or index) of path, "plan" at the top
    schema: dict             # the sub-schema that failed
    hint: str | None         # its x-hint

    @classmethod
    def of(cls, err: Any, doc: PositionedYaml) -> "_SchemaError":
        path = tuple(err.absolute_path)
        schema = err.schema if isinstance(err.schema, dict) else {}
        return cls(err, doc, path, doc.where(path), _field_name(path), path[-1] if path else "plan", schema,
                   schema.get("x-hint"))

    def said(self, message: str, hint: str | None = None) -> list[Problem]:
        return [Problem(self.where, message, hint)]


def _is_step(path: tuple) -> bool:
    """Whether `path` is a mission step itself (mission[i]), which the plan writes as `- kind: {...}`."""
    return bool(path) and path[0] == "mission" and len(path) == 2


def _unknown_keys(e: _SchemaError) -> list[Problem] | None:
    inst = e.err.instance
    if not isinstance(inst, dict):
        return None
    allowed = set((e.schema.get("properties") or {}).keys())
    out = []
    for k in inst:
        if k not in allowed:
            if _is_step(e.path):
                msg, h = f"unknown mission step {shown(k)}", _unknown_key_hint(k, STEPS)
            else:
                msg, h = f"unknown key {shown(k)} in {e.name}", _unknown_key_hint(k, allowed)
            out.append(Problem(e.doc.where(e.path + (k,), key=True), msg, h))
    return out


def _missing_keys(e: _SchemaError) -> list[Problem]:
    inst = e.err.instance
    missing = [r for r in e.err.validator_value if isinstance(inst, dict) and r not in inst]
    return [Problem(e.where, f"{e.name} needs {m!r}", _schema_at(plan_schema(), e.path + (m,)).get("description"))
            for m in missing]


def _beyond_bound(e: _SchemaError) -> list[Problem]:
    v, inst = e.err.validator, e.err.instance
    if e.last in ("altitude_m", "alt_m"):
        low = v.startswith("min") or v == "exclusiveMinimum"
        return e.said(f"altitude {shown(inst)} m is {'below' if low else 'above'} the "
                      f"{MIN_ALTITUDE_M if low else MAX_ALTITUDE_M:g} m {'minimum' if low else 'maximum'}", e.hint)
    if e.path and e.path[-2:-1] == ("overlap",) and v == "exclusiveMaximum":
        return e.said(f"{e.last} overlap {shown(inst)} %: overlap must be below 100 % (at 100 % the photos "
                      "never move on)", e.hint or "overlap in percent, e.g. 80")
    return e.said(_out_of_range(e.name, shown(inst), v, e.err.validator_value), e.hint)


def _wrong_type(e: _SchemaError) -> list[Problem]:
    expected, inst = e.err.validator_value, e.err.instance
    exp = " or ".join(map(_article, expected)) if isinstance(expected, list) else _article(expected)
    if expected == "object" and _is_step(e.path) and isinstance(inst, str):
        return e.said(f"mission step {shown(inst)} needs a colon and a body",
                      f"write `- {inst}: {{}}`" if inst in STEPS else _unknown_key_hint(inst, STEPS))
    hint = e.hint
    if expected in ("number", "integer") and isinstance(inst, str):
        hint = _number_in_text_hint(inst, quoted=e.path in e.doc.quoted) or hint
    return e.said(f"{e.name} must be {exp}, got {describe(inst)}", hint)


def _not_an_option(e: _SchemaError) -> list[Problem]:
    options = [str(o) for o in e.err.validator_value]
    # a near miss of a name is a typo; a number near another number is not ("did you mean '105'?" for 106)
    close = difflib.get_close_matches(e.err.instance, options, n=1) if isinstance(e.err.instance, str) else []
    return e.said(f"{e.name}: {shown(e.err.instance)} is not one of {', '.join(options)}",
                  f"did you mean {close[0]!r}?" if close else e.hint)


def _not_the_constant(e: _SchemaError) -> list[Problem]:
    return e.said(f"{e.name} must be {e.err.validator_value!r}, got {shown(e.err.instance)}",
                  "this tool reads capture-plan format version 1" if e.last == "version" else e.hint)


def _item_count(e: _SchemaError) -> list[Problem]:
    inst = e.err.instance
    if e.last == "line":
        return e.said("a corridor line needs at least 2 points", "give [[lat, lon], [lat, lon], ...]")
    if e.name.endswith("area") or any(k in e.path for k in ZONE_KINDS):
        return e.said("an inline area needs at least 3 [lat, lon] points", _AREA_HINT)
    if isinstance(inst, list) and len(inst) in (2, 3) or e.schema.get("description", "").startswith("[lat"):
        return e.said(f"{e.name} must be [lat, lon], got {describe(inst)}", _LATLON_HINT)
    return e.said(f"{e.name}: {clip(e.err.message, 2 * ECHO_CHARS)}")


def _property_count(e: _SchemaError) -> list[Problem]:
    if _is_step(e.path):
        return e.said("each mission step is one of " + ", ".join(STEPS) + ", written as `- name: {...}`",
                      "start a new list item (`-`) for each step")
    return e.said(f"{e.name} must not be empty")


def _neither_form(e: _SchemaError) -> list[Problem] | None:
    """An anyOf: an area (a file or inline points) or angle_deg ('auto' or degrees)."""
    path = e.path
    if e.last in ("area",) or (len(path) >= 2 and path[-2] in ZONE_KINDS):
        return e.said(f"{e.name} must be a file path or a list of at least 3 [lat, lon] points, got "
                      f"{describe(e.err.instance)}", _AREA_HINT)
    if e.last == "angle_deg":
        return e.said(f"angle_deg must be 'auto' or a number of degrees -360..360, got {shown(e.err.instance)}",
                      "degrees clockwise from north, e.g. angle_deg: 30 (0 = north-south lines)")
    if e.last == "speed_mps":
        return _speed_form(e)
    if e.last == "profile":
        return _profile_form(e)
    return None


def _speed_form(e: _SchemaError) -> list[Problem]:
    """speed_mps: 'auto' or a number in the frame's range (the range error of the number branch, when it is one)."""
    inst = e.err.instance
    if isinstance(inst, (int, float)) and not isinstance(inst, bool):
        bound = next((c for c in e.err.context if c.validator in ("minimum", "maximum")), None)
        if bound is not None:
            return e.said(_out_of_range(e.name, shown(inst), bound.validator, bound.validator_value),
                          bound.schema.get("x-hint"))
    return e.said(f"speed_mps must be a number of m/s or auto, got {describe(inst)}",
                  "e.g. speed_mps: 5, or speed_mps: auto (the fastest the cameras allow)")


def _profile_form(e: _SchemaError) -> list[Problem]:
    """profile: a name, or {name, level, overrides}: say which part is wrong."""
    from missions.thermal.pv import PROFILE_NAMES, PvProfile

    inst = e.err.instance
    names = ", ".join(PROFILE_NAMES)
    if isinstance(inst, dict):
        bad = [c for c in e.err.context if c.validator != "enum" or c.path]
        detail = bad[0].message if bad else "unknown form"
        return e.said(f"profile: {clip(detail, 2 * ECHO_CHARS)}",
                      f"write profile: {{name: {PROFILE_NAMES[0]}, level: module}}; numbers to override: "
                      + ", ".join(PvProfile.OVERRIDABLE))
    return e.said(f"profile {shown(inst)} is not a profile this compiler knows", f"profiles: {names}")


def _listed_twice(e: _SchemaError) -> list[Problem]:
    return e.said(f"{e.name} lists a name twice", "name each payload once")


def _pattern_mismatch(e: _SchemaError) -> list[Problem]:
    if e.last == "name":
        return e.said(f"name {shown(e.err.instance)} must be a file-name-safe word (letters, digits, . _ -), "
                      "at most 64", "output files are named after it")
    return e.said(f"{e.name}: {shown(e.err.instance)} is not allowed here ({clip(e.err.message, 2 * ECHO_CHARS)})")


def _payload_name(e: _SchemaError) -> list[Problem]:
    return e.said(f"payload name {shown(e.err.instance)} must be a word (letters, digits, _ -)",
                  "start with a letter or _, at most 32 characters, e.g. thermal")


# What each JSON Schema keyword's failure means in a plan; None from a translation: say jsonschema's message.
_TRANSLATIONS: dict[str, Callable[[_SchemaError], list[Problem] | None]] = {
    "additionalProperties": _unknown_keys, "required": _missing_keys, **{b: _beyond_bound for b in _BOUNDS},
    "type": _wrong_type, "enum": _not_an_option, "const": _not_the_constant,
    "minItems": _item_count, "maxItems": _item_count, "minProperties": _property_count,
    "maxProperties": _property_count, "anyOf": _neither_form, "uniqueItems": _listed_twice,
    "pattern": _pattern_mismatch, "propertyNames": _payload_name,
}


def _translate(err: Any, doc: PositionedYaml) -> list[Problem]:
    e = _SchemaError.of(err, doc)
    translation = _TRANSLATIONS.get(err.validator)
    problems = translation(e) if translation is not None else None
    if problems is None:
        return e.said(f"{e.name}: {clip(err.message, 2 * ECHO_CHARS)}", e.hint)
    return problems



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


def describe(v: Any) -> str:
    if v is None:
        return "nothing"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, dict):
        return "a mapping"
    if isinstance(v, list):
        return f"a list of {len(v)}"
    return shown(v)
