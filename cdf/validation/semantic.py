"""Checks beyond the XSD: structure as each parser finds it, typed values, cross-references, semantics.

Each check names the rule it implements (cdf/validation/rules.py); severities come from the profile later.
Parser behaviour cited in the messages is from ../shared/reference/camera-definition-files.md and was
measured with MAVSDK 4.1.0 and MAVProxy 1.8.75 where §D says so.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from typing import Iterator, Mapping

from cdf.validation import vocabulary
from cdf.validation.schema import TYPED_ATTRS, Hit
from cdf.validation.values import (INT_RANGES, KNOWN_TYPES, NUMERIC_TYPES, STOI_MAX, STOI_TYPES,
                                   canonical_int, parse_typed)
from cdf.validation.vocabulary import CDF_TAGS, TEXT_ELEMENTS, VOCABULARY

# camera_def.md §Common Parameters (devguide PR #395)
RESERVED = frozenset("""CAM_APERTURE CAM_EV CAM_VIDEV CAM_PHOTOEV CAM_EXPMODE CAM_ISO CAM_VIDISO CAM_PHOTOISO
CAM_METERING CAM_SHUTTERSPD CAM_VIDSHUTSPD CAM_PHOTOSHUTSPD CAM_VIDRES CAM_WBMODE CAM_VIDSTREAM CAM_VIDFPS
CAM_VIDFOV CAM_VIDFMT CAM_PHOTORATIO CAM_PHOTOFMT CAM_PHOTOSIZE CAM_PHOTOQUAL CAM_MODE""".split())

_PARAM_ATTRS = VOCABULARY["parameter"][1]

# set versions of values.py's type tuples: membership is tested per parameter, option and roption
_NUMERIC, _KNOWN, _STOI = frozenset(NUMERIC_TYPES), frozenset(KNOWN_TYPES), frozenset(STOI_TYPES)
_NAME_OK = re.compile(r"[ -~]{1,16}")
_NAME_STYLE = re.compile(r"[A-Z0-9_]+")
_COND_TEST = re.compile(r"([A-Za-z0-9_\-]+)(!=|=|>|<)(\S+)")
_LOCALE = re.compile(r"[a-z]{2}_[A-Z]{2}")
_MARKUP = re.compile(r'[&<>"]')
# option values repeat (0, 1, 2, ... in every parameter of every file): parse each (text, type) once per
# process; the results are immutable (engine.clear_caches forgets them). Only numeric types are parsed,
# so the outer dict has at most their dozen keys.
_PARSED: dict[str, dict[str, tuple]] = {}  # type -> text -> parse_typed(text, type)


def _parse(text: str, ptype: str) -> tuple:
    """parse_typed, memoised per type (the options loop reads the type's dict directly: a lookup by a str,
    whose hash is cached, where a cache keyed by (text, type) builds and hashes a tuple on every call)."""
    cache = _PARSED.setdefault(ptype, {})
    parsed = cache.get(text)
    if parsed is None:
        if len(cache) >= 8192:  # bounded across the files of a long run
            cache.clear()
        parsed = cache[text] = parse_typed(text, ptype)
    return parsed


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


# Children are read as el[:], a list built in C, and filtered by tag in Python: el.find(tag) parses its
# path in Python on every call (~3 us), and el.iterchildren(tag) builds a tag matcher on every call
# (~1 us, more than filtering the few children of a CDF element); comments and processing instructions
# have a function as .tag, never equal to a tag name.

def _first(el, tag: str):
    """el.find(tag): the first child with that tag."""
    for c in el[:]:
        if c.tag == tag:
            return c
    return None


def _children(el, tag: str) -> list:
    """el.findall(tag): the children with that tag."""
    return [c for c in el[:] if c.tag == tag]


def _text_empty(el) -> bool:
    return el.text is None or el.text == ""


def _line(el) -> int | None:
    return getattr(el, "sourceline", None)


class _Params:
    """The parameters as MAVSDK sees them: direct children of <parameters>, by name."""

    def __init__(self, elements) -> None:
        self.elements = elements
        # (texts, structural): the strings the localization rule compares with, gathered while the
        # parameter checks read them anyway; None when not gathered (see check_document)
        self.strings: tuple[set[str], set[str]] | None = None
        self.attributes: list[tuple] | None = None  # see check_document
        self._targets: dict[str, tuple] = {}
        # the first parameter of each name: built backwards, so that the first one is written last
        self.by_name: dict[str, object] = dict(zip(reversed([p.get("name") for p in elements]), reversed(elements)))
        self.by_name.pop(None, None)

    def range_target(self, name: str) -> tuple:
        """What a <parameterrange> needs of its target, worked out once per target (many ranges point at
        one): (type, option value texts or None without <options>, the options' typed values, whether the
        type is numeric, the texts of options that parse by the type)."""
        target = self._targets.get(name)
        if target is None:
            p = self.by_name.get(name)
            ttype = (p.get("type") or "").lower() if p is not None else None
            opts = _first(p, "options") if p is not None else None
            values = None if opts is None else [v for v in (o.get("value") for o in _children(opts, "option"))
                                                if v is not None]
            numeric = ttype in _NUMERIC
            parsed = {v: _parse(v, ttype) for v in values} if numeric and values is not None else {}
            typed = frozenset(v for v, why in parsed.values() if why is None)
            good = frozenset(t for t, (_v, why) in parsed.items() if why is None)
            target = self._targets[name] = (ttype, values, typed, numeric, good)
        return target


def check_document(root, data: bytes, scan: TreeScan | None = None,
                   attributes: list[tuple] | None = None) -> Iterator[Hit]:
    """All Python checks of one parsed document; `scan` is scan_tree(root) when the caller has it.
    `attributes`: a list to receive each parameter's schema.TYPED_ATTRS values (for schema.conforms_fast)."""
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
    elements = _children(parameters, "parameter")
    if not elements:
        yield Hit("CDF108", _line(parameters), None, "no <parameter> (QGC rejects a file where none loads)")
    if len(elements) > 65535:
        yield Hit("CDF212", _line(parameters), None, f"{len(elements)} parameters; PARAM_EXT counts are uint16")
    params = _Params(elements)
    params.attributes = attributes
    if scan is not None and scan.xsd_structure_ok and _first(root, "localization") is not None:
        # the structure is sound, so the parameter checks read every string the localization rule
        # needs, at the places its XPaths would look: gather them there instead of reading them twice
        params.strings = (set(), set())
    seen: dict[str, int | None] = {}
    for p in elements:
        yield from _check_parameter(p, params, seen)
    yield from _check_localization(root, params, definition, scan is not None and scan.xsd_structure_ok)
    if scan is not None:
        yield from scan.vocabulary
    else:
        yield from _check_vocabulary(root)


def _check_encoding(data: bytes) -> Iterator[Hit]:
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
    direct = _first(root, tag)
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
        el = _first(d, tag)
        if el is None:
            yield Hit("CDF104", _line(d), None, f"<definition> has no <{tag}> child (QGC and MAVSDK reject the file)")
        elif _text_empty(el):
            yield Hit("CDF105", _line(el), None, f"<{tag}> is empty (MAVSDK crashes on empty text)")
        else:
            text = el.text.strip()
            if len(text.encode()) > 31:
                yield Hit("CDF214", _line(el), None,
                          f"<{tag}> is {len(text.encode())} bytes; CAMERA_INFORMATION holds 31 + NUL")
            if "/" in text or "\\" in text:
                yield Hit("CDF214", _line(el), None, f"<{tag}> {text!r} contains a path separator "
                                                     "(GCSs build cache file names from it)")


def _check_parameter(p, params: _Params, seen: dict) -> Iterator[Hit]:
    a = dict(zip(p.keys(), p.values()))  # two C calls: 1.6x faster than dict(p.items()) or dict(p.attrib)
    typed_attrs = tuple(map(a.get, TYPED_ATTRS))  # for _attribute_rules and schema.conforms_fast
    if params.attributes is not None:
        params.attributes.append(typed_attrs)
    name, ptype_raw = a.get("name"), a.get("type")
    line = p.sourceline
    if name is None or ptype_raw is None:
        missing = " and ".join(a for a, v in (("name", name), ("type", ptype_raw)) if v is None)
        yield Hit("CDF109", line, name, f"<parameter> has no {missing} (QGC and MAVSDK reject the file)")
    if name is not None:
        if not _NAME_OK.fullmatch(name):
            yield Hit("CDF116", line, name, f"name {name!r} is not 1-16 printable ASCII characters "
                                            "(PARAM_EXT param_id is char[16])")
        elif not _NAME_STYLE.fullmatch(name):
            yield Hit("CDF118", line, name, f"name {name!r} uses characters outside [A-Z0-9_]")
        if name in seen:
            yield Hit("CDF117", line, name, f"duplicate parameter name (first at line {seen[name]})")
        else:
            seen[name] = line
    # one pass over the few children instead of a find()/findall() per tag: each costs a path lookup
    desc = options_el = updates_el = None
    stray: list = []
    for c in p[:]:
        ctag = c.tag
        if ctag == "description":
            if desc is None:
                desc = c
        elif ctag == "options":
            if options_el is None:
                options_el = c
        elif ctag == "updates":
            if updates_el is None:
                updates_el = c
        elif ctag == "option":
            stray.append(c)
    # before the options, whose CDF121s follow the attributes' (findings are sorted by line and rule later)
    ptype, numeric, default, findings = _attribute_rules(typed_attrs, options_el is not None)
    for rule, message in findings:
        yield Hit(rule, line, name, message)
    desc_text = desc.text if desc is not None else None  # each .text read builds a new str
    gather = params.strings
    if gather is not None:
        if stray:
            params.strings = gather = None  # stray <option>s hold strings too: the XPaths find them
        else:
            gather[1].update(filter(None, (name, ptype_raw, a.get("default"))))
            if desc_text:
                gather[0].add(desc_text)
    if desc is None:
        yield Hit("CDF114", line, name, "no <description> child (QGC and MAVSDK reject the file)")
    elif not desc_text:
        yield Hit("CDF105", desc.sourceline, name, "<description> is empty (MAVSDK crashes on empty text)")

    # only an attribute outside the vocabulary can be a misspelt decimalPlaces: skip the scan otherwise
    if not _PARAM_ATTRS.issuperset(a) and any(k.lower() == "decimalplaces" and k != "decimalPlaces" for k in a):
        yield Hit("CDF207", line, name, "attribute must be spelled decimalPlaces (QGC ignores other spellings)")

    if stray:
        yield Hit("CDF122", _line(stray[0]), name, f"{len(stray)} <option> element(s) directly under <parameter>, "
                                                    "not inside <options> (MAVSDK does not see them)")
    options = _children(options_el, "option") if options_el is not None else []
    with_refs = []  # options with children: the only ones _check_option_refs can report on
    stoi = numeric and ptype in _STOI
    values: list = []  # the options' typed values, for the duplicate and default checks
    parsed_values = _PARSED.setdefault(ptype, {}) if numeric else None
    for o in options:
        oname, oval = o.get("name"), o.get("value")
        if gather is not None:
            if oname:
                gather[0].add(oname)
            if oval:
                gather[1].add(oval)
        if oname is None or oval is None:
            what = " and ".join(a for a, v in (("name", oname), ("value", oval)) if v is None)
            yield Hit("CDF123", _line(o), name, f"<option> without {what} (QGC rejects the file, MAVSDK skips the parameter)")
        if oval is not None and numeric:
            parsed = parsed_values.get(oval)
            v, why = parsed if parsed is not None else _parse(oval, ptype)
            if why:
                yield Hit("CDF120", _line(o), name, f"option value: {why}")
            else:
                if stoi and v > STOI_MAX:
                    yield Hit("CDF121", _line(o), name, f"option value {v} exceeds 2147483647 (MAVSDK's std::stoi throws: crash)")
                values.append(v)
        if len(o):
            with_refs.append(o)

    if len(set(values)) < len(values):  # some value appears twice
        dups = sorted(repr(v) for v in set(values) if values.count(v) > 1)
        yield Hit("CDF124", _line(options_el), name, f"option value(s) {', '.join(dups)} appear more than once")
    if numeric and default is not None and options_el is not None:
        hits = values.count(default)
        if hits != 1:
            listed = ", ".join(o.get("value") or "?" for o in options)
            yield Hit("CDF125", line, name,
                      f"default {a['default']!r} matches {'no' if hits == 0 else hits} option value(s) [{listed}] "
                      "(MAVSDK rejects the whole file: 'No default found')")
    if ptype == "bool":
        for o in with_refs:
            if next(o.iter("exclude", "parameterrange"), None) is not None:
                yield Hit("CDF126", _line(o), name, "exclusions/ranges keyed on a bool option never fire in QGC "
                                                    "(it renders bools as true/false); use uint8 with options")
                break

    control = a.get("control")
    if options and a.get("readonly") == "1" and control != "0":
        yield Hit("CDF213", line, name, 'readonly="1" with options but not control="0": a control that never sends')
    if name == "CAM_MODE":
        vals = sorted(o.get("value") or "" for o in options)
        if control != "0" or vals != ["0", "1"]:
            yield Hit("CDF208", line, name, 'CAM_MODE should be control="0" with options 0 (photo) and 1 (video); '
                                            "QGC then sets modes via PARAM_EXT_SET, so the camera must serve it")
    elif name in RESERVED and ptype in ("bool", "custom", "string"):
        yield Hit("CDF209", line, name, f"reserved name {name} used with type {ptype}")

    if updates_el is not None:
        yield from _check_updates(updates_el, name, params, gather)
    for o in with_refs:
        yield from _check_option_refs(o, p, name, ptype, params, gather)


@functools.lru_cache(maxsize=4096)  # parameters repeat their attributes (type uint32, default 0, ...)
def _attribute_rules(values: tuple[str | None, ...], has_options: bool) -> tuple[str, bool, object, tuple]:
    """What a parameter's attributes (`values`: those of schema.TYPED_ATTRS) decide by themselves, with
    whether it has <options>: its type in lower case, whether its values are typed by it, its typed default
    (None when absent or invalid: CDF120 is the XSD's), and the findings as (rule, message) pairs, all at
    the parameter's line."""
    control, readonly, writeonly, _decimal_places, ptype_raw, default_text, lo_t, hi_t, st_t = values
    ptype = (ptype_raw or "").lower()
    out = []
    if ptype_raw is not None:
        if ptype == "elapsedseconds":
            out.append(("CDF133", f"type {ptype_raw!r} is known to QGC only (MAVSDK and MAVProxy reject "
                                  "the file); use uint32 with unit=\"s\""))
        elif ptype not in _KNOWN:
            out.append(("CDF110", f"unknown type {ptype_raw!r} (QGC and MAVSDK reject the file)"))
        elif ptype_raw != ptype:
            out.append(("CDF111", f"type {ptype_raw!r} is not lower case (MAVSDK rejects the file)"))
        if ptype == "string":
            out.append(("CDF112", "type string is not in the spec (MAVSDK skips it, MAVProxy rejects the file)"))
        elif ptype == "custom":
            out.append(("CDF113", "type custom is silently skipped by MAVSDK"))
        elif ptype == "uint16":
            out.append(("CDF115", "uint16 is broken in MAVSDK's camera plugin; use uint32 or int32"))
    if readonly == "1" and writeonly == "1":
        out.append(("CDF131", 'readonly="1" and writeonly="1" together (MAVSDK rejects the file)'))
    if ptype in ("custom", "string") and control != "0":
        out.append(("CDF132", f'{ptype} parameter without control="0"'))

    numeric = ptype in _NUMERIC and ptype_raw == ptype
    if default_text is None and ptype in _NUMERIC:
        out.append(("CDF119", "no default (MAVSDK silently skips the parameter: 'Default missing')"))
    typed = {}
    if numeric:
        for k, text in (("default", default_text), ("min", lo_t), ("max", hi_t), ("step", st_t)):
            if text is not None:
                typed[k] = _parse(text, ptype)[0]
    default = typed.get("default")
    if numeric and ptype in _STOI:
        for attr, v in typed.items():
            if isinstance(v, int) and v > STOI_MAX:
                out.append(("CDF121", f"{attr}={v} exceeds 2147483647 (MAVSDK's std::stoi throws: crash)"))

    # ranges (min/max/step) for parameters without options
    if numeric and ptype != "bool":
        if not has_options and (lo_t is None or hi_t is None):
            out.append(("CDF127", "no options and no min/max range "
                                  "(MAVSDK silently skips the parameter: 'Range not found')"))
        lo, hi, st = typed.get("min"), typed.get("max"), typed.get("step")
        if lo is not None and hi is not None and lo > hi:
            out.append(("CDF128", f"min {lo_t} > max {hi_t} (MAVProxy rejects the file)"))
        if st is not None and st <= 0:
            out.append(("CDF128", f"step {st_t} is not positive (MAVProxy rejects the file)"))
        if has_options and (lo_t is not None or hi_t is not None):
            out.append(("CDF129", "min/max combined with <options> (MAVSDK ignores the range, the spec "
                                  "forbids combining a range with exclusions or option ranges)"))
        if default is not None and not has_options:
            if (lo is not None and default < lo) or (hi is not None and default > hi):
                out.append(("CDF129", f"default {default_text} outside [{lo_t}, {hi_t}]"))
            elif lo is not None and st and st > 0 and ptype in INT_RANGES and (default - lo) % st:
                out.append(("CDF129", f"default {default_text} is not on the step grid {lo_t} + n*{st_t}"))
    return ptype, numeric, default, tuple(out)


def _check_updates(updates, name, params: _Params, gather) -> Iterator[Hit]:
    for u in _children(updates, "update"):
        text = u.text  # each .text read builds a new str: read once
        if not text:
            yield Hit("CDF105", _line(u), name, "<update> is empty (MAVSDK crashes on empty text)")
            continue
        target = text.strip()
        if gather is not None:
            gather[1].add(target)
        if target == name:
            yield Hit("CDF202", _line(u), name, "<update> names the parameter itself")
        elif target not in params.by_name:
            yield Hit("CDF202", _line(u), name, f"<update> names unknown parameter {target!r} "
                                                "(QGC dereferences a null pointer for it)")


def _check_option_refs(o, p, name, ptype, params: _Params, gather) -> Iterator[Hit]:
    """Exclusions and parameter ranges of one option (called only for options with children).
    `gather`: the localization rule's (texts, structural) sets to add the strings read here to, or None."""
    is_trigger = False
    for ex in o.iter("exclude"):  # recursive like QGC; nesting itself is CDF200 (XSD)
        is_trigger = True
        text = ex.text
        if not text:
            yield Hit("CDF105", _line(ex), name, "<exclude> is empty (MAVSDK crashes on empty text)")
            continue
        target = text.strip()
        if gather is not None:
            gather[1].add(target)
        if target not in params.by_name:
            yield Hit("CDF201", _line(ex), name, f"<exclude> names unknown parameter {target!r}")
    for pr in o.iter("parameterrange"):
        is_trigger = True
        target = pr.get("parameter")
        roptions = _children(pr, "roption")
        rnames = [r.get("name") for r in roptions]
        rvalues = [r.get("value") for r in roptions]
        if gather is not None:
            gather[0].update(filter(None, rnames))
            gather[1].update(filter(None, rvalues))
        if target is None or target == name or target not in params.by_name:
            if target is None:
                yield Hit("CDF123", _line(pr), name, "<parameterrange> without parameter "
                                                     "(QGC rejects the file, MAVSDK skips the parameter)")
            else:
                why = "its own parameter" if target == name else f"unknown parameter {target!r}"
                yield Hit("CDF203", _line(pr), name, f"<parameterrange> targets {why} "
                                                     "(MAVSDK skips the parameter: 'Unknown roption type')")
            continue
        ttype, tvalues, typed_targets, numeric_target, good = params.range_target(target)
        if tvalues is None:
            yield Hit("CDF204", _line(pr), name, f"range target {target} has no <options> to restrict")
        # one by one only when some roption is incomplete or its value is not the text of an option of the
        # target that parses (otherwise _check_roptions finds nothing)
        if None in rnames or None in rvalues or (numeric_target and not good.issuperset(rvalues)):
            yield from _check_roptions(zip(roptions, rnames, rvalues), name, target, ttype, tvalues, typed_targets,
                                       numeric_target)
        cond = pr.get("condition")
        if cond is not None:
            yield from _check_condition(cond, pr, name, params)
    if is_trigger:
        val = o.get("value")
        if val is not None and ptype in INT_RANGES and ptype != "bool" and not canonical_int(val):
            yield Hit("CDF206", _line(o), name, f"trigger option value {val!r} is not a canonical integer "
                                                "(QGC compares it as text with the current value)")
        elif val is not None and ptype in ("float", "double"):
            yield Hit("CDF206", _line(o), name, f"{ptype} option {val!r} triggers exclusions/ranges; QGC matches it "
                                                "only if written exactly as it renders the value")


def _check_roptions(roptions, name, target, ttype, tvalues, typed_targets, numeric_target) -> Iterator[Hit]:
    """`roptions`: (element, name, value) of each <roption>, as _check_option_refs read them."""
    for r, rname, rval in roptions:
        if rname is None or rval is None:
            what = " and ".join(a for a, v in (("name", rname), ("value", rval)) if v is None)
            yield Hit("CDF123", _line(r), name, f"<roption> without {what} "
                                                "(QGC rejects the file, MAVSDK skips the parameter)")
            continue
        if numeric_target:
            v, why = _parse(rval, ttype)
            if why:
                yield Hit("CDF120", _line(r), name, f"roption value for {target} ({ttype}): {why}")
            elif tvalues is not None and v not in typed_targets:
                yield Hit("CDF204", _line(r), name, f"roption value {rval} is not an option of {target}")


def _check_condition(cond: str, pr, name, params: _Params) -> Iterator[Hit]:
    problems = [f"unknown parameter {pname}" if message is None else message
                for pname, message in _condition_parts(cond) if message is not None or pname not in params.by_name]
    if problems:
        yield Hit("CDF205", _line(pr), name, f"condition {cond!r}: " + "; ".join(problems))


@functools.lru_cache(maxsize=1024)  # a file repeats its few conditions in many ranges (engine.clear_caches)
def _condition_parts(cond: str) -> tuple[tuple[str | None, str | None], ...]:
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
    return tuple(parts)


@functools.lru_cache(maxsize=2)
def _localization_xpaths(canonical: bool):
    """XPaths over the <parameter> children of a <parameters> section: (first <description> elements,
    (option names, roption names), (option values, roption values, the parameters' name/type/default),
    (exclude elements, update elements)); each tuple's results together form one set.

    canonical=False finds the elements at any depth below a parameter; canonical=True only at the places
    the XSD allows them (the same nodes when scan_tree found the structure sound, and cheaper: libxml2
    follows child steps instead of visiting every descendant)."""
    from lxml import etree

    from cdf.validation.schema import _canonical_paths

    def compile_(*exprs: str):
        # no unions of big node sets: libxml2 sorts a union into document order, which costs more than
        # finding the nodes, and the results only go into sets. smart_strings=False: plain str results
        return tuple(etree.XPath(e, smart_strings=False) for e in exprs)

    section = "/mavlinkcamera/parameters/"
    below = [p[len(section):] for p in _canonical_paths() if p.startswith(section + "parameter/")]

    def at(tag: str, step: str = "") -> tuple[str, ...]:
        if not canonical:
            return (f"parameter//{tag}{step}",)
        return tuple(p + step for p in below if p.rsplit("/", 1)[-1] == tag)

    return (compile_("parameter/description[1]"),
            compile_(*at("option", "/@name"), *at("roption", "/@name")),
            compile_(*at("option", "/@value"), *at("roption", "/@value"),
                     "parameter/@name | parameter/@type | parameter/@default"),
            compile_(*at("exclude"), *at("update")))


def _check_localization(root, params: _Params, definition, structure_ok: bool = False) -> Iterator[Hit]:
    locs = _children(root, "localization")
    if not locs:
        return
    if len(locs) > 1:
        yield Hit("CDF210", _line(locs[1]), None, "more than one <localization> (QGC uses the first)")
    if params.strings is not None:
        texts, structural = params.strings  # gathered by the parameter checks (see check_document)
    else:
        texts, structural = set(), set()
    if params.strings is None and params.elements:
        # not gathered (structure unsound, stray options): each parameter's first <description>, its
        # attributes and its option/roption/exclude/update descendants, by XPath in C
        section = params.elements[0].getparent()
        descriptions, names, values, refs = _localization_xpaths(structure_ok)
        for xpath in descriptions:
            texts.update(d.text for d in xpath(section) if d.text)
        for xpath in names:
            texts.update(v for v in xpath(section) if v)
        for xpath in values:
            structural.update(v for v in xpath(section) if v)
        for xpath in refs:
            structural.update(e.text.strip() for e in xpath(section) if e.text)
    if definition is not None:
        for tag in ("model", "vendor"):
            el = _first(definition, tag)
            if el is not None and el.text:
                structural.add(el.text.strip())
    for loc in _children(locs[0], "locale"):
        lname = loc.get("name")
        if lname is None:
            yield Hit("CDF210", _line(loc), None, "<locale> without name")
        elif not _LOCALE.fullmatch(lname):
            yield Hit("CDF210", _line(loc), None, f"locale name {lname!r} is not ll_CC (e.g. de_DE): "
                                                  "QGC matches the full name or its first 3 characters")
        unmatched: list[tuple[object, str]] = []  # (element, original); only the first one's line is used
        for s in _children(loc, "strings"):
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


def _vocabulary_xpath_text() -> str:
    """True when every CDF element sits at a canonical path with only known children and attributes and
    no stray text: then _vocabulary_walk finds nothing (an independent statement the tests hold it to)."""
    from cdf.validation.schema import _canonical_paths

    paths = [(p, p.rsplit("/", 1)[1]) for p in _canonical_paths()]
    all_children = " + ".join(f"count({p}/*)" for p, _t in paths)
    known_children = " + ".join(f"count({p}/{c})" for p, t in paths for c in sorted(VOCABULARY[t][0])) or "0"
    all_attrs = " + ".join(f"count({p}/@*)" for p, _t in paths)
    known_attrs = " + ".join(f"count({p}/@{a})" for p, t in paths for a in sorted(VOCABULARY[t][1])) or "0"
    stray = " | ".join(f"{p}/text()[normalize-space()]" for p, t in paths if t not in TEXT_ELEMENTS)
    return f"({all_children}) = ({known_children}) and ({all_attrs}) = ({known_attrs}) and not({stray})"


@functools.lru_cache(maxsize=1)
def _vocabulary_clean():
    """Compiled _vocabulary_xpath_text(): an independent XPath statement of the vocabulary, used by the
    tests to cross-check _vocabulary_walk (not on the validation path: see _check_vocabulary)."""
    from lxml import etree

    return etree.XPath(_vocabulary_xpath_text())


def _check_vocabulary(root) -> Iterator[Hit]:
    """Unknown elements (reported once, at the top of the unknown subtree) and unknown attributes."""
    # The walk is as fast as the XPath proof above (measured on the corpus), and most real files fail the
    # proof anyway (options@default), so the walk runs alone; the proof stays as the tests' independent
    # statement of the vocabulary (tests/cdf/test_validate_schema.py).
    yield from _vocabulary_walk(root)


# element -> (known attributes, whether its text is content): one dict lookup per element in the walk
_WALK_ENTRY: dict[str, tuple[frozenset[str], bool]] = {t: (v[1], t in TEXT_ELEMENTS) for t, v in VOCABULARY.items()}


@dataclass(frozen=True)
class TreeScan:
    """What scan_tree found (libxml2's proof or the walk): the vocabulary findings (CDF211) and whether
    the structure is one mavlinkcamera.xsd accepts (every CDF element where the XSD allows it, within
    maxOccurs, nothing inside text elements, no processing instruction). xsd_structure_ok=True lets
    schema.conforms_fast skip its structural XPath; False only means "not sure"."""

    vocabulary: tuple[Hit, ...]
    xsd_structure_ok: bool
    # settled by libxml2's proof: every element is a known one where the XSD allows it, so the tree is
    # at most 8 deep (the walk's sound structure may still hold deep unknown elements)
    proved: bool = False


def scan_tree(root, data: bytes | None = None) -> TreeScan:
    """The vocabulary rule and the XSD fast path's structure test in one look at the tree: libxml2's proof
    (vocabulary.unknown_attributes) when it settles the document, else one Python walk serving both.
    `data`: the bytes `root` was parsed from, if at hand (the proof's shortcut). tests/cdf/
    test_validate_speed.py holds proof and walk to the same answers, and the walk's structure verdict to
    the XPath statement in schema.py. (engine._hits takes the two steps apart: before the walk it parses the
    document again with its blank text.)"""
    return prove_tree(root, data) or walk_tree(root)


def prove_tree(root, data: bytes | None = None) -> TreeScan | None:
    """scan_tree's answer when libxml2's proof settles the document, else None."""
    pairs = vocabulary.unknown_attributes(root, data)
    if pairs is None:
        return None
    return TreeScan(tuple(_unknown_attribute_hits(root, pairs)), True, proved=True)


def walk_tree(root) -> TreeScan:
    """scan_tree's answer from the Python walk alone."""
    hits = list(_vocabulary_walk(root, structure := []))
    return TreeScan(tuple(hits), not structure)


def _vocabulary_walk(root, structure: list | None = None) -> Iterator[Hit]:
    """CDF211 findings; when `structure` is a list, appends to it a reason whenever the structure may
    break the XSD (see TreeScan), following schema._COMPLEX along the canonical paths."""
    # Hot loop over every element: each lxml property read costs a C call, so the common case (known
    # attributes, whitespace-only text) is settled with one subset test and str.isspace (which, unlike
    # strip(), allocates nothing); the messages are built only when a finding fires. Children come as
    # one slice (el[:] builds the list in C, about 3x cheaper than iterating the element); text
    # elements rarely have children, and len() says so without building anything.
    from lxml.etree import PI

    from cdf.validation.schema import _COMPLEX

    track = structure is not None
    if track:
        if root.tag != "mavlinkcamera":
            structure.append("root")
        elif next(root.itersiblings(PI), None) is not None or \
                next(root.itersiblings(PI, preceding=True), None) is not None:
            structure.append("processing instruction outside the root")
    # (tag, unknown attribute) pairs, each reported once, at its first element in document order
    unknown_attrs: dict[tuple[str, str], None] = {}
    # (element, its tag, at a path the XSD allows): the parent already read the tag, and every .tag read
    # is a C call that builds a new str
    stack = [(root, root.tag, track and not structure)]
    while stack:
        el, tag, canonical = stack.pop()
        entry = _WALK_ENTRY.get(tag)
        if entry is None:
            continue
        attrs, simple = entry
        keys = el.keys()
        if keys and not attrs.issuperset(keys):
            _note_unknown_attributes(el, tag, keys, attrs, unknown_attrs)
        if simple:
            if not len(el):
                continue
            if canonical:
                structure.append(f"<{tag}> has children")
            for c in el[:]:
                ctag = c.tag
                if ctag in CDF_TAGS:
                    stack.append((c, ctag, False))
                elif isinstance(ctag, str):
                    if track:
                        _check_unknown_subtree(c, structure, PI)
                    yield _unknown_element(c, el)
            continue
        text = el.text
        if text and not text.isspace():
            yield Hit("CDF211", _line(el), _param_name(el), f"stray text {text.strip()[:30]!r} inside <{tag}> "
                                                            "(ignored by all parsers)")
        children = el[:]
        if not children:
            continue  # a leaf reached through the stack (the root, or a child of a text element)
        allowed = _COMPLEX.get(tag, _NOTHING) if canonical else _NOTHING
        capped_seen: set[str] = set()
        for c in children:
            tail = c.tail
            if tail and not tail.isspace():
                yield Hit("CDF211", _line(c), _param_name(el), f"stray text {tail.strip()[:30]!r} inside "
                                                               f"<{tag}> (ignored by all parsers)")
            ctag = c.tag
            if ctag in CDF_TAGS:
                max_occurs = allowed.get(ctag)
                if track:
                    if max_occurs is None:
                        structure.append(f"<{ctag}> misplaced")
                    elif max_occurs == 1:
                        if ctag in capped_seen:
                            structure.append(f"<{ctag}> more than once")
                        capped_seen.add(ctag)
                if len(c):
                    stack.append((c, ctag, max_occurs is not None))
                    continue
                # a leaf (most options, roptions, strings): what the stack loop would check for it,
                # without the trip over the stack
                c_attrs, c_simple = _WALK_ENTRY[ctag]
                keys = c.keys()
                if keys and not c_attrs.issuperset(keys):
                    _note_unknown_attributes(c, ctag, keys, c_attrs, unknown_attrs)
                if not c_simple:
                    text = c.text
                    if text and not text.isspace():
                        yield Hit("CDF211", _line(c), _param_name(c), f"stray text {text.strip()[:30]!r} inside "
                                                                      f"<{ctag}> (ignored by all parsers)")
            elif isinstance(ctag, str):  # not a comment or processing instruction
                if track:
                    _check_unknown_subtree(c, structure, PI)
                yield _unknown_element(c, el)
            elif track and ctag is PI:
                structure.append("processing instruction")
    yield from _unknown_attribute_hits(root, unknown_attrs)


_NOTHING: dict[str, int] = {}


def _note_unknown_attributes(el, tag: str, keys: list[str], known: frozenset[str], pairs: dict) -> None:
    for a in keys:
        if a not in known and a.lower() != "decimalplaces":  # a misspelt decimalPlaces is CDF207
            pairs[(tag, a)] = None


def _unknown_attribute_hits(root, pairs) -> list[Hit]:
    """One CDF211 per (tag, attribute), at the first element in document order that the walk reaches
    (every ancestor a CDF element), in document order: the same whichever way the pairs were found."""
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
    return [Hit("CDF211", _line(el), _param_name(el), f"attribute {tag}@{a} is not part of the format "
                                                      "(ignored by QGC and MAVSDK)") for _i, _k, tag, a, el in found]


def _check_unknown_subtree(el, structure: list, PI) -> None:
    # the walk does not enter unknown elements; a CDF element or processing instruction inside one
    # still makes the structure doubtful (the XPath version counts them too)
    if next(el.iter(PI, *CDF_TAGS), None) is not None:
        structure.append(f"CDF element or processing instruction inside <{el.tag}>")


def _unknown_element(c, parent) -> Hit:
    return Hit("CDF211", _line(c), _param_name(c), f"element <{c.tag}> inside <{parent.tag}> is not part of "
                                                   "the format (ignored by QGC and MAVSDK)")


def _param_name(el) -> str | None:
    while el is not None:
        if el.tag == "parameter":
            return el.get("name")
        el = el.getparent()
    return None


# ---- against what the camera reports (CDF3xx) ---------------------------------------------------------

_EXT_EQUIV = {"bool": "uint8", "string": "custom"}


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
                if _EXT_EQUIV.get(t, t) != _EXT_EQUIV.get(got, got):
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
