"""Checks beyond the XSD: structure as each parser finds it, typed values, cross-references, semantics.

Each check names the rule it implements (cdf/validation/rules.py); severities come from the profile later.
Parser behaviour cited in the messages is from ../shared/reference/camera-definition-files.md and was
measured with MAVSDK 4.1.0 and MAVProxy 1.8.75 where §D says so.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterator, Mapping, NamedTuple

from cdf.paramtypes import wire_name
from cdf.validation.report import Hit
from cdf.validation.schema import TYPED_ATTRS
from cdf.validation.values import (INT_RANGES, KNOWN_TYPES, NUMERIC_TYPES, STOI_MAX, STOI_TYPES, canonical_int,
                                   parse_typed)
from cdf.validation.vocabulary import CDF_TAGS, VOCABULARY, owning_parameter

# camera_def.md §Common Parameters (devguide PR #395)
RESERVED = frozenset("""CAM_APERTURE CAM_EV CAM_VIDEV CAM_PHOTOEV CAM_EXPMODE CAM_ISO CAM_VIDISO CAM_PHOTOISO
CAM_METERING CAM_SHUTTERSPD CAM_VIDSHUTSPD CAM_PHOTOSHUTSPD CAM_VIDRES CAM_WBMODE CAM_VIDSTREAM CAM_VIDFPS
CAM_VIDFOV CAM_VIDFMT CAM_PHOTORATIO CAM_PHOTOFMT CAM_PHOTOSIZE CAM_PHOTOQUAL CAM_MODE""".split())

_NAME_OK = re.compile(r"[ -~]{1,16}")
_NAME_STYLE = re.compile(r"[A-Z0-9_]+")
_COND_TEST = re.compile(r"([A-Za-z0-9_\-]+)(!=|=|>|<)(\S+)")
_LOCALE = re.compile(r"[a-z]{2}_[A-Z]{2}")
_MARKUP = re.compile(r'[&<>"]')
_ENCODING = re.compile(rb"<\?xml[^>]*encoding\s*=\s*[\"']([A-Za-z0-9._-]+)[\"']")


@dataclass(frozen=True)
class CameraInfo:
    """What the camera reports, for the CDF3xx checks (all optional).

    param_types: parameter name -> CDF type name of the PARAM_EXT type the camera answers with
    (bool/uint8 travel as UINT8; string/custom as CUSTOM). answered: names the camera answers.
    """

    vendor_name: str | None = None
    model_name: str | None = None
    cam_definition_version: int | None = None
    cam_definition_uri: str | None = None
    param_types: Mapping[str, str] | None = None
    answered: frozenset[str] | None = None


def _line(el) -> int | None:
    return getattr(el, "sourceline", None)


def _child(el, tag: str):
    """The first child with this tag, or None (el.find(tag) without ElementPath's parsing of the path)."""
    return next(el.iterchildren(tag), None)


def _missing(**attributes: str | None) -> str:
    """'name and value': the names of the attributes that are None, joined for a message."""
    return " and ".join(a for a, v in attributes.items() if v is None)


class _Params:
    """The parameters as MAVSDK sees them: direct children of <parameters>, the first of each name by name."""

    def __init__(self, elements: list) -> None:
        self.elements = elements
        self.by_name: dict[str, object] = {}
        for p in elements:
            self.by_name.setdefault(p.get("name"), p)
        self.by_name.pop(None, None)
        self._range_targets: dict[str, _RangeTarget] = {}
        self._parsed: dict[tuple[str, str], tuple] = {}

    def parse(self, text: str, ptype: str) -> tuple:
        """parse_typed, once per text and type in the document: option values (0, 1, 2, ...) repeat in every
        parameter, and parsing costs about as much as libxml2 spends building the option's element."""
        key = (text, ptype)
        if key not in self._parsed:
            self._parsed[key] = parse_typed(text, ptype)
        return self._parsed[key]

    def range_target(self, name: str) -> _RangeTarget:
        """What a <parameterrange> needs of the parameter `name`, worked out once (many ranges share one)."""
        if name not in self._range_targets:
            self._range_targets[name] = _range_target(self.by_name[name], self.parse)
        return self._range_targets[name]


class _RangeTarget(NamedTuple):
    """What a <parameterrange> needs of the parameter it restricts."""

    type: str  # in lower case
    values: list[str] | None  # its option value texts; None without <options>
    typed: frozenset  # the options' values that parse by its type
    numeric: bool


def _range_target(p, parse) -> _RangeTarget:
    ptype = (p.get("type") or "").lower()
    options = _child(p, "options")
    values = None if options is None else [o.get("value") for o in options.iterchildren("option")
                                           if o.get("value") is not None]
    numeric = ptype in NUMERIC_TYPES
    parsed = [parse(v, ptype) for v in values] if numeric and values is not None else []
    return _RangeTarget(ptype, values, frozenset(v for v, why in parsed if why is None), numeric)


def check_document(root, data: bytes) -> Iterator[Hit]:
    """All Python checks of one parsed document (`data`: the bytes it was parsed from)."""
    yield from _check_encoding(data)
    if root.tag != "mavlinkcamera":
        yield Hit("CDF101", _line(root), None,
                  f"root element is <{root.tag}>, not <mavlinkcamera> (MAVSDK and MAVProxy reject the file)")
    definition = yield from _section(root, "definition")
    parameters = yield from _section(root, "parameters")
    if definition is not None:
        yield from _check_definition(definition)
    if parameters is None:
        return
    elements = list(parameters.iterchildren("parameter"))
    if not elements:
        yield Hit("CDF108", _line(parameters), None, "no <parameter> (QGC rejects a file where none loads)")
    if len(elements) > 65535:
        yield Hit("CDF212", _line(parameters), None, f"{len(elements)} parameters; PARAM_EXT counts are uint16")
    params = _Params(elements)
    seen: dict[str, int | None] = {}
    for p in elements:
        yield from _check_parameter(p, params, seen)
    yield from _check_localization(root, params, definition)
    yield from _check_vocabulary(root)


# How a UTF-16 or UTF-32 document starts: a byte-order mark, or "<" with its NUL bytes (XML 1.0 §F.1).
_WIDE_STARTS = {b"\xff\xfe\x00\x00": "UTF-32", b"\x00\x00\xfe\xff": "UTF-32", b"\x3c\x00\x00\x00": "UTF-32",
                b"\x00\x00\x00\x3c": "UTF-32", b"\xff\xfe": "UTF-16", b"\xfe\xff": "UTF-16",
                b"\x3c\x00": "UTF-16", b"\x00\x3c": "UTF-16"}


def wide_encoding(data: bytes) -> str | None:
    """"UTF-16" or "UTF-32" when the document is stored in one of them, else None (UTF-8 or 8-bit)."""
    for start, name in _WIDE_STARTS.items():  # longest first: a UTF-32LE mark begins like UTF-16LE's
        if data.startswith(start):
            return name
    return None


def _check_encoding(data: bytes) -> Iterator[Hit]:
    wide = wide_encoding(data)
    if wide is not None:
        yield Hit("CDF008", 1, None, f"the file is stored as {wide}; MAVSDK reads UTF-8 only and rejects it "
                                     'at line 1: save it as UTF-8 with <?xml version="1.0" encoding="UTF-8"?>')
        return
    head = data[:200].lstrip(b"\xef\xbb\xbf")
    if not head.lstrip().startswith(b"<?xml"):
        yield Hit("CDF007", 1, None, 'no XML declaration; start with <?xml version="1.0" encoding="UTF-8"?>')
        return
    m = _ENCODING.search(head)
    if m is None:
        yield Hit("CDF007", 1, None, 'the XML declaration names no encoding; declare encoding="UTF-8"')
    elif m.group(1).decode().upper().replace("_", "-") not in ("UTF-8", "UTF8"):
        yield Hit("CDF007", 1, None, f"encoding {m.group(1).decode()} declared; use UTF-8")


def _section(root, tag: str):
    """The section as QGC finds it: a direct child of the root, else the first one anywhere below it."""
    direct = _child(root, tag)
    if direct is not None:
        return direct
    nested = next(root.iter(tag), None) if root.tag != tag else None
    if nested is None:
        yield Hit("CDF103", _line(root), None, f"no <{tag}> element (QGC and MAVSDK reject the file)")
        return None
    yield Hit("CDF102", _line(nested), None,
              f"<{tag}> is not a direct child of the root (MAVSDK and MAVProxy do not find it; QGC does)")
    return nested


def _check_definition(d) -> Iterator[Hit]:
    version = d.get("version")
    if version is None:
        yield Hit("CDF106", _line(d), None, "<definition> has no version attribute (QGC rejects the file)")
    elif not (re.fullmatch(r"[0-9]+", version.strip()) and int(version) <= 65535):
        yield Hit("CDF107", _line(d), None,
                  f"version={version!r} is not an integer 0-65535 (cam_definition_version is uint16)")
    for tag in ("model", "vendor"):
        el = _child(d, tag)
        if el is None:
            yield Hit("CDF104", _line(d), None, f"<definition> has no <{tag}> child (QGC and MAVSDK reject the file)")
        elif not el.text:
            yield Hit("CDF105", _line(el), None, f"<{tag}> is empty (MAVSDK crashes on empty text)")
        else:
            text = el.text.strip()
            if len(text.encode()) > 31:
                yield Hit("CDF214", _line(el), None,
                          f"<{tag}> is {len(text.encode())} bytes; CAMERA_INFORMATION holds 31 + NUL")
            if "/" in text or "\\" in text:
                yield Hit("CDF214", _line(el), None, f"<{tag}> {text!r} contains a path separator "
                                                     "(GCSs build cache file names from it)")


# ---- one <parameter> ---------------------------------------------------------------------------------------

class _Parameter(NamedTuple):
    """What the checks read of one <parameter>, read once."""

    el: object
    attrs: dict[str, str]
    name: str | None
    line: int | None
    description: object | None  # the first <description> child
    options_el: object | None  # the first <options> child
    options: list  # the <option>s inside it
    stray_options: list  # <option> children of the parameter itself
    updates: object | None  # the first <updates> child


def _read_parameter(p) -> _Parameter:
    attrs = dict(p.attrib)
    options_el = _child(p, "options")
    options = list(options_el.iterchildren("option")) if options_el is not None else []
    return _Parameter(p, attrs, attrs.get("name"), p.sourceline, _child(p, "description"), options_el, options,
                      list(p.iterchildren("option")), _child(p, "updates"))


def _check_parameter(p, params: _Params, seen: dict) -> Iterator[Hit]:
    param = _read_parameter(p)
    yield from _check_name(param, seen)
    # the attributes' findings come before the options' CDF121s (findings are sorted by line and rule later)
    verdict = _attribute_rules(tuple(map(param.attrs.get, TYPED_ATTRS)), param.options_el is not None)
    for rule, message in verdict.findings:
        yield Hit(rule, param.line, param.name, message)
    yield from _check_description(param)
    if any(k.lower() == "decimalplaces" and k != "decimalPlaces" for k in param.attrs):
        yield Hit("CDF207", param.line, param.name, "attribute must be spelled decimalPlaces (QGC ignores other spellings)")
    yield from _check_options(param, verdict, params)
    if verdict.ptype == "bool":
        yield from _check_bool_triggers(param)
    yield from _check_control(param, verdict.ptype)
    if param.updates is not None:
        yield from _check_updates(param.updates, param.name, params)
    for o in param.options:
        if len(o):  # only an option with children can hold exclusions or ranges
            yield from _check_option_refs(o, param.name, verdict.ptype, params)


def _check_name(param: _Parameter, seen: dict) -> Iterator[Hit]:
    """Name and type present (CDF109), the name fit for PARAM_EXT (CDF116, CDF134, CDF118) and unique (CDF117)."""
    name, line, ptype = param.name, param.line, param.attrs.get("type")
    if name is None or ptype is None:
        yield Hit("CDF109", line, name, f"<parameter> has no {_missing(name=name, type=ptype)} "
                                        "(QGC and MAVSDK reject the file)")
    if name is None:
        return
    if len(name.encode("utf-8")) > 16:
        yield Hit("CDF116", line, name, f"name {name!r} is longer than 16 bytes (PARAM_EXT param_id is char[16]; "
                                        "MAVSDK never asks the camera for it)")
    elif not _NAME_OK.fullmatch(name):
        yield Hit("CDF134", line, name, f"name {name!r} is not 1-16 printable ASCII characters "
                                        "(MAVProxy rejects the file; use [A-Z0-9_])")
    elif not _NAME_STYLE.fullmatch(name):
        yield Hit("CDF118", line, name, f"name {name!r} uses characters outside [A-Z0-9_]")
    if name in seen:
        yield Hit("CDF117", line, name, f"duplicate parameter name (first at line {seen[name]})")
    else:
        seen[name] = line


class AttributeVerdict(NamedTuple):
    """What a parameter's attributes decide by themselves."""

    ptype: str  # the type in lower case
    numeric: bool  # whether its values are typed by it (a known numeric type, written in lower case)
    default: int | float | None  # the typed default; None when absent or invalid (CDF120 is the XSD's)
    findings: tuple[tuple[str, str], ...]  # (rule, message), all at the parameter's line


def _attribute_rules(values: tuple[str | None, ...], has_options: bool) -> AttributeVerdict:
    """The rules on a parameter's attributes (`values`: those of schema.TYPED_ATTRS, in that order), given
    whether it has <options>."""
    control, readonly, writeonly, _decimal_places, ptype_raw, default_text, lo_t, hi_t, st_t = values
    ptype = (ptype_raw or "").lower()
    numeric = ptype in NUMERIC_TYPES and ptype_raw == ptype
    typed = {k: parse_typed(text, ptype)[0] for k, text in
             (("default", default_text), ("min", lo_t), ("max", hi_t), ("step", st_t)) if numeric and text is not None}
    out = [*_type_rules(ptype_raw, ptype)]
    if readonly == "1" and writeonly == "1":
        out.append(("CDF131", 'readonly="1" and writeonly="1" together (MAVSDK rejects the file)'))
    if ptype in ("custom", "string") and control != "0":
        out.append(("CDF132", f'{ptype} parameter without control="0"'))
    if default_text is None and ptype in NUMERIC_TYPES:
        out.append(("CDF119", "no default (MAVSDK silently skips the parameter: 'Default missing')"))
    if numeric and ptype in STOI_TYPES:
        for attr, v in typed.items():
            if isinstance(v, int) and v > STOI_MAX:
                out.append(("CDF121", f"{attr}={v} exceeds 2147483647 (MAVSDK's std::stoi throws: crash)"))
    if numeric and ptype != "bool":
        out += _range_rules(ptype, typed, (default_text, lo_t, hi_t, st_t), has_options)
    return AttributeVerdict(ptype, numeric, typed.get("default"), tuple(out))


def _type_rules(ptype_raw: str | None, ptype: str) -> Iterator[tuple[str, str]]:
    if ptype_raw is None:
        return
    if ptype == "elapsedseconds":
        yield "CDF133", (f"type {ptype_raw!r} is known to QGC only (MAVSDK and MAVProxy reject "
                         "the file); use uint32 with unit=\"s\"")
    elif ptype not in KNOWN_TYPES:
        yield "CDF110", f"unknown type {ptype_raw!r} (QGC and MAVSDK reject the file)"
    elif ptype_raw != ptype:
        yield "CDF111", f"type {ptype_raw!r} is not lower case (MAVSDK rejects the file)"
    if ptype == "string":
        yield "CDF112", "type string is not in the spec (MAVSDK skips it, MAVProxy rejects the file)"
    elif ptype == "custom":
        yield "CDF113", "type custom is silently skipped by MAVSDK"
    elif ptype == "uint16":
        yield "CDF115", "uint16 is broken in MAVSDK's camera plugin; use uint32 or int32"


def _range_rules(ptype: str, typed: dict, texts: tuple[str | None, ...], has_options: bool
                 ) -> Iterator[tuple[str, str]]:
    """min/max/step of a numeric, non-bool parameter (`texts`: default, min, max and step as written)."""
    default_text, lo_t, hi_t, st_t = texts
    default, lo, hi, st = (typed.get(k) for k in ("default", "min", "max", "step"))
    if not has_options and (lo_t is None or hi_t is None):
        yield "CDF127", "no options and no min/max range (MAVSDK silently skips the parameter: 'Range not found')"
    if lo is not None and hi is not None and lo > hi:
        yield "CDF128", f"min {lo_t} > max {hi_t} (MAVProxy rejects the file)"
    if st is not None and st <= 0:
        yield "CDF128", f"step {st_t} is not positive (MAVProxy rejects the file)"
    if has_options and (lo_t is not None or hi_t is not None):
        yield "CDF129", ("min/max combined with <options> (MAVSDK ignores the range, the spec "
                         "forbids combining a range with exclusions or option ranges)")
    if default is not None and not has_options:
        if (lo is not None and default < lo) or (hi is not None and default > hi):
            yield "CDF129", f"default {default_text} outside [{lo_t}, {hi_t}]"
        elif lo is not None and st and st > 0 and ptype in INT_RANGES and (default - lo) % st:
            yield "CDF129", f"default {default_text} is not on the step grid {lo_t} + n*{st_t}"


def _check_description(param: _Parameter) -> Iterator[Hit]:
    desc = param.description
    if desc is None:
        yield Hit("CDF114", param.line, param.name, "no <description> child (QGC and MAVSDK reject the file)")
    elif not desc.text:
        yield Hit("CDF105", desc.sourceline, param.name, "<description> is empty (MAVSDK crashes on empty text)")


def _check_options(param: _Parameter, verdict: AttributeVerdict, params: _Params) -> Iterator[Hit]:
    """Options outside <options> (CDF122), each option's name and value (CDF123, CDF120, CDF121), duplicate
    values (CDF124) and the default among them (CDF125)."""
    name, stray = param.name, param.stray_options
    if stray:
        yield Hit("CDF122", _line(stray[0]), name, f"{len(stray)} <option> element(s) directly under <parameter>, "
                                                    "not inside <options> (MAVSDK does not see them)")
    values: list = []  # the options' typed values
    for o in param.options:
        oname, oval = o.get("name"), o.get("value")
        if oname is None or oval is None:
            yield Hit("CDF123", _line(o), name, f"<option> without {_missing(name=oname, value=oval)} "
                                                "(QGC rejects the file, MAVSDK skips the parameter)")
        if oval is None or not verdict.numeric:
            continue
        v, why = params.parse(oval, verdict.ptype)
        if why:
            yield Hit("CDF120", _line(o), name, f"option value: {why}")
            continue
        if verdict.ptype in STOI_TYPES and v > STOI_MAX:
            yield Hit("CDF121", _line(o), name, f"option value {v} exceeds 2147483647 (MAVSDK's std::stoi throws: crash)")
        values.append(v)
    if len(set(values)) < len(values):
        dups = sorted(repr(v) for v in set(values) if values.count(v) > 1)
        yield Hit("CDF124", _line(param.options_el), name, f"option value(s) {', '.join(dups)} appear more than once")
    if verdict.numeric and verdict.default is not None and param.options_el is not None:
        hits = values.count(verdict.default)
        if hits != 1:
            listed = ", ".join(o.get("value") or "?" for o in param.options)
            yield Hit("CDF125", param.line, name,
                      f"default {param.attrs['default']!r} matches {'no' if hits == 0 else hits} option value(s) "
                      f"[{listed}] (MAVSDK rejects the whole file: 'No default found')")


def _check_bool_triggers(param: _Parameter) -> Iterator[Hit]:
    for o in param.options:
        if next(o.iter("exclude", "parameterrange"), None) is not None:
            yield Hit("CDF126", _line(o), param.name, "exclusions/ranges keyed on a bool option never fire in QGC "
                                                      "(it renders bools as true/false); use uint8 with options")
            return


def _check_control(param: _Parameter, ptype: str) -> Iterator[Hit]:
    """A readonly control that never sends (CDF213), CAM_MODE as QGC uses it (CDF208), reserved names (CDF209)."""
    name, line, control = param.name, param.line, param.attrs.get("control")
    if param.options and param.attrs.get("readonly") == "1" and control != "0":
        yield Hit("CDF213", line, name, 'readonly="1" with options but not control="0": a control that never sends')
    if name == "CAM_MODE":
        if control != "0" or sorted(o.get("value") or "" for o in param.options) != ["0", "1"]:
            yield Hit("CDF208", line, name, 'CAM_MODE should be control="0" with options 0 (photo) and 1 (video); '
                                            "QGC then sets modes via PARAM_EXT_SET, so the camera must serve it")
    elif name in RESERVED and ptype in ("bool", "custom", "string"):
        yield Hit("CDF209", line, name, f"reserved name {name} used with type {ptype}")


# ---- cross-references ----------------------------------------------------------------------------------------

def _check_updates(updates, name, params: _Params) -> Iterator[Hit]:
    for u in updates.iterchildren("update"):
        if not u.text:
            yield Hit("CDF105", _line(u), name, "<update> is empty (MAVSDK crashes on empty text)")
            continue
        target = u.text.strip()
        if target == name:
            yield Hit("CDF202", _line(u), name, "<update> names the parameter itself")
        elif target not in params.by_name:
            yield Hit("CDF202", _line(u), name, f"<update> names unknown parameter {target!r} "
                                                "(QGC dereferences a null pointer for it)")


def _check_option_refs(o, name, ptype, params: _Params) -> Iterator[Hit]:
    """Exclusions and parameter ranges of one option, and the option's value as their trigger."""
    is_trigger = False
    for ex in o.iter("exclude"):  # recursive like QGC; nesting itself is CDF200 (XSD)
        is_trigger = True
        if not ex.text:
            yield Hit("CDF105", _line(ex), name, "<exclude> is empty (MAVSDK crashes on empty text)")
        elif ex.text.strip() not in params.by_name:
            yield Hit("CDF201", _line(ex), name, f"<exclude> names unknown parameter {ex.text.strip()!r}")
    for pr in o.iter("parameterrange"):
        is_trigger = True
        yield from _check_parameterrange(pr, name, params)
    val = o.get("value")
    if not is_trigger or val is None:
        return
    if ptype in INT_RANGES and ptype != "bool" and not canonical_int(val):
        yield Hit("CDF206", _line(o), name, f"trigger option value {val!r} is not a canonical integer "
                                            "(QGC compares it as text with the current value)")
    elif ptype in ("float", "double"):
        yield Hit("CDF206", _line(o), name, f"{ptype} option {val!r} triggers exclusions/ranges; QGC matches it "
                                            "only if written exactly as it renders the value")


def _check_parameterrange(pr, name, params: _Params) -> Iterator[Hit]:
    target = pr.get("parameter")
    if target is None:
        yield Hit("CDF123", _line(pr), name, "<parameterrange> without parameter "
                                             "(QGC rejects the file, MAVSDK skips the parameter)")
        return
    if target == name or target not in params.by_name:
        why = "its own parameter" if target == name else f"unknown parameter {target!r}"
        yield Hit("CDF203", _line(pr), name, f"<parameterrange> targets {why} "
                                             "(MAVSDK skips the parameter: 'Unknown roption type')")
        return
    restricted = params.range_target(target)
    if restricted.values is None:
        yield Hit("CDF204", _line(pr), name, f"range target {target} has no <options> to restrict")
    yield from _check_roptions(pr.iterchildren("roption"), name, target, restricted, params)
    cond = pr.get("condition")
    if cond is not None:
        yield from _check_condition(cond, pr, name, params)


def _check_roptions(roptions, name, target: str, restricted: _RangeTarget, params: _Params) -> Iterator[Hit]:
    for r in roptions:
        rname, rval = r.get("name"), r.get("value")
        if rname is None or rval is None:
            yield Hit("CDF123", _line(r), name, f"<roption> without {_missing(name=rname, value=rval)} "
                                                "(QGC rejects the file, MAVSDK skips the parameter)")
            continue
        if restricted.numeric:
            v, why = params.parse(rval, restricted.type)
            if why:
                yield Hit("CDF120", _line(r), name, f"roption value for {target} ({restricted.type}): {why}")
            elif restricted.values is not None and v not in restricted.typed:
                yield Hit("CDF204", _line(r), name, f"roption value {rval} is not an option of {target}")


def _check_condition(cond: str, pr, name, params: _Params) -> Iterator[Hit]:
    problems = [f"unknown parameter {pname}" if message is None else message
                for pname, message in _condition_parts(cond) if message is not None or pname not in params.by_name]
    if problems:
        yield Hit("CDF205", _line(pr), name, f"condition {cond!r}: " + "; ".join(problems))


def _condition_parts(cond: str) -> list[tuple[str | None, str | None]]:
    """What is wrong with a condition, in order: (None, message) for what the text alone shows, and
    (name, None) for each parameter it names (whether that one exists depends on the file)."""
    tokens = cond.split(" ")
    parts: list[tuple[str | None, str | None]] = []
    if len(tokens) % 2 == 0:
        parts.append((None, "expected TEST (AND|OR TEST)..."))
    for i, tok in enumerate(tokens):
        if i % 2:
            if tok not in ("AND", "OR"):
                parts.append((None, f"{tok!r} where AND/OR is expected"))
            continue
        m = _COND_TEST.fullmatch(tok)
        if not m:
            parts.append((None, f"{tok!r} is not NAME=VALUE (no spaces around the operator)"))
            continue
        pname, op, val = m.groups()
        parts.append((pname, None))
        if op in (">", "<"):
            parts.append((None, f"{op} compares text in QGC (lexicographic)"))
        if not canonical_int(val):
            parts.append((None, f"value {val!r} is not a canonical integer"))
    return parts


# ---- localization --------------------------------------------------------------------------------------------

def _localization_strings(params: _Params) -> tuple[set[str], set[str]]:
    """What QGC's byte replacement on the whole file may hit: (the texts a translation is for: each
    parameter's first <description>, the option and roption names; the structural strings it must leave
    alone: option and roption values, the parameters' name, type and default, exclude and update targets),
    from each parameter at any depth, as QGC reads them."""
    texts: set[str] = set()
    structural: set[str] = set()
    for p in params.elements:
        desc = _child(p, "description")
        if desc is not None and desc.text:
            texts.add(desc.text)
        structural.update(v for v in (p.get("name"), p.get("type"), p.get("default")) if v)
        for o in p.iter("option", "roption"):
            oname, ovalue = o.get("name"), o.get("value")
            if oname:
                texts.add(oname)
            if ovalue:
                structural.add(ovalue)
        structural.update(e.text.strip() for e in p.iter("exclude", "update") if e.text)
    return texts, structural


def _check_localization(root, params: _Params, definition) -> Iterator[Hit]:
    locs = list(root.iterchildren("localization"))
    if not locs:
        return
    if len(locs) > 1:
        yield Hit("CDF210", _line(locs[1]), None, "more than one <localization> (QGC uses the first)")
    texts, structural = _localization_strings(params)
    if definition is not None:
        for tag in ("model", "vendor"):
            el = _child(definition, tag)
            if el is not None and el.text:
                structural.add(el.text.strip())
    for loc in locs[0].iterchildren("locale"):
        lname = loc.get("name")
        if lname is None:
            yield Hit("CDF210", _line(loc), None, "<locale> without name")
        elif not _LOCALE.fullmatch(lname):
            yield Hit("CDF210", _line(loc), None, f"locale name {lname!r} is not ll_CC (e.g. de_DE): "
                                                  "QGC matches the full name or its first 3 characters")
        unmatched: list[tuple[object, str]] = []  # (element, original); only the first one's line is used
        for s in loc.iterchildren("strings"):
            orig, trans = s.get("original"), s.get("translated")
            if orig is None or trans is None:
                yield Hit("CDF210", _line(s), None, "<strings> needs original and translated")
                continue
            if orig in structural:
                yield Hit("CDF210", _line(s), None, f"original {orig!r} also occurs as a name/value/model text: QGC's "
                                                    "byte replacement on the whole file would change it too")
            elif orig not in texts:
                unmatched.append((s, orig))
            if _MARKUP.search(orig) or _MARKUP.search(trans):
                yield Hit("CDF210", _line(s), None, "original/translated contain &, <, > or \" "
                                                    "(QGC replaces raw bytes: such strings never match or break XML)")
        if unmatched:
            shown = ", ".join(repr(o) for _l, o in unmatched[:5]) + (", ..." if len(unmatched) > 5 else "")
            yield Hit("CDF210", _line(unmatched[0][0]), None, f"locale {lname}: {len(unmatched)} original string(s) match "
                                                       f"no description or option name: {shown}")



# ---- vocabulary (CDF211) -------------------------------------------------------------------------------------

def _check_vocabulary(root) -> list[Hit]:
    """Unknown elements (reported once, at the top of the unknown subtree), stray text inside elements that
    hold only elements, and unknown attributes (once per element and attribute name, in document order).

    Each element taken from `pending` is checked with its children: a child that holds nothing is checked
    on the spot, the others wait in `pending` (last in, first out) and are read later."""
    if root.tag not in VOCABULARY:
        return []
    hits: list[Hit] = []
    unknown_attributes: dict[tuple[str, str], None] = {}
    _check_element(root, root.tag, hits, unknown_attributes)
    pending = [root]
    while pending:
        el = pending.pop()
        tag = el.tag
        if el is not root:
            _check_element(el, tag, hits, unknown_attributes)
        text_element = VOCABULARY[tag].text
        for c in el:
            ctag = c.tag
            if not text_element:
                tail = c.tail
                if tail and not tail.isspace():
                    hits.append(_stray_text(tail, c, el))
            if ctag in CDF_TAGS:
                if text_element or len(c):
                    pending.append(c)
                else:
                    _check_element(c, ctag, hits, unknown_attributes)
            elif isinstance(ctag, str):  # not a comment or processing instruction
                hits.append(Hit("CDF211", _line(c), owning_parameter(c), f"element <{ctag}> inside <{tag}> is not "
                                                                         "part of the format (ignored by QGC and MAVSDK)"))
    return hits + _unknown_attribute_hits(root, unknown_attributes)


def _check_element(el, tag: str, hits: list[Hit], unknown_attributes: dict) -> None:
    """Of one CDF element itself: its unknown attributes (noted, reported at the end) and stray text."""
    spec = VOCABULARY[tag]
    keys = el.keys()
    if not spec.attributes.issuperset(keys):
        for a in keys:
            if a not in spec.attributes and a.lower() != "decimalplaces":  # a misspelt decimalPlaces is CDF207
                unknown_attributes[(tag, a)] = None
    if not spec.text:
        text = el.text
        if text and not text.isspace():
            hits.append(_stray_text(text, el, el))


def _stray_text(text: str, at, inside) -> Hit:
    return Hit("CDF211", _line(at), owning_parameter(inside), f"stray text {text.strip()[:30]!r} inside "
                                                              f"<{inside.tag}> (ignored by all parsers)")


def _unknown_attribute_hits(root, pairs) -> list[Hit]:
    """One CDF211 per (tag, attribute), at the first element in document order that the walk reaches
    (every ancestor a CDF element), in document order."""
    wanted: dict[str, list[str]] = {}
    for tag, a in pairs:
        wanted.setdefault(tag, []).append(a)
    found = []  # (document position, attribute position, tag, attribute, element)
    if wanted:
        for i, el in enumerate(root.iter(*wanted)):
            attrs = wanted[el.tag]
            keys = el.keys()
            for a in [a for a in attrs if a in keys]:
                if all(x.tag in CDF_TAGS for x in el.iterancestors()):
                    found.append((i, keys.index(a), el.tag, a, el))
                    attrs.remove(a)
            if not any(wanted.values()):
                break
    found.sort(key=lambda f: f[:2])
    return [Hit("CDF211", _line(el), owning_parameter(el), f"attribute {tag}@{a} is not part of the format "
                                                           "(ignored by QGC and MAVSDK)") for _i, _k, tag, a, el in found]


# ---- against what the camera reports (CDF3xx) ---------------------------------------------------------

def check_camera(root, info: CameraInfo) -> Iterator[Hit]:
    definition = root.find("definition") if root.find("definition") is not None else next(root.iter("definition"), None)
    if definition is not None:
        version = definition.get("version")
        if info.cam_definition_version is not None:
            if info.cam_definition_version == 0:
                yield Hit("CDF300", _line(definition), None, "cam_definition_version is 0: GCSs never refresh "
                                                             "their cached copy")
            elif version is None or version.strip() != str(info.cam_definition_version):
                yield Hit("CDF300", _line(definition), None, f"file version {version!r} differs from "
                                                             f"cam_definition_version {info.cam_definition_version}")
        for tag, reported in (("model", info.model_name), ("vendor", info.vendor_name)):
            el = definition.find(tag)
            if reported is not None and el is not None and (el.text or "").strip() != reported:
                yield Hit("CDF301", _line(el), None, f"<{tag}> {el.text!r} differs from CAMERA_INFORMATION "
                                                     f"{tag}_name {reported!r}")
    if info.cam_definition_uri is not None:
        for msg in uri_problems(info.cam_definition_uri):
            yield Hit("CDF302", None, None, msg)
    params = next(root.iter("parameters"), None)
    elements = params.findall("parameter") if params is not None else []
    if info.param_types is not None:
        for p in elements:
            n, t = p.get("name"), (p.get("type") or "").lower()
            if n in info.param_types:
                got = info.param_types[n].lower()
                if wire_name(t) != wire_name(got):
                    yield Hit("CDF303", _line(p), n, f"file says {t}, the camera answers {got}")
    if info.answered is not None:
        for p in elements:
            n = p.get("name")
            if n is not None and p.get("writeonly") != "1" and n not in info.answered:
                yield Hit("CDF304", _line(p), n, "the camera does not answer this parameter")


def uri_problems(uri: str) -> list[str]:
    """Why a cam_definition_uri would trouble a GCS (rule CDF302); empty when fine."""
    out = []
    if len(uri.encode()) > 139:
        out.append(f"URI is {len(uri.encode())} bytes; cam_definition_uri holds 139 + NUL")
    scheme = uri.split("://", 1)[0].lower() if "://" in uri else ""
    if scheme not in ("http", "https", "mftp"):
        out.append(f"scheme {scheme or '(none)'}:// is not http, https or mftp (QGC knows only mftp for MAVLink FTP)")
    if "comp=" in uri:
        out.append("comp= part: QGC and MAVSDK parse it differently; host the file on the camera component")
    if scheme in ("http", "https") and uri.lower().split("?")[0].endswith(".xz"):
        out.append(".xml.xz over HTTP is not inflated by QGC or MAVSDK 4.1.0; serve plain XML over HTTP")
    return out
