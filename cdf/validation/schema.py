"""Apply cdf/schema/mavlinkcamera.xsd with xmlschema and turn its errors into findings with rule ids.

Division of labour with semantic.py (so one problem yields one finding): the Python checks own
everything that must also work when the document is not a <mavlinkcamera> (QGC reads such files):
root, sections, required elements and attributes, empty texts, types, <option> outside <options>.
The XSD owns the lexical types of parameter attributes (default/min/max/step typed by @type, flags,
decimalPlaces), the placement of exclusions/updates/parameterranges, and anything else that deviates
from the documented shape (CDF100). Errors in the first group are dropped here.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any, Callable, NamedTuple

XSD_PATH = Path(__file__).resolve().parents[1] / "schema" / "mavlinkcamera.xsd"

_ATTR_VALUE = re.compile(r"attribute ([\w:.-]+)=")
_MISSING_ATTR = re.compile(r"missing required attribute '([\w:.-]+)'")
_UNEXPECTED = re.compile(r"Unexpected child with tag '([^']+)'")
PLACEMENT_TAGS = {"exclusions", "exclude", "updates", "update", "parameterranges", "parameterrange", "roption"}
# owned by semantic.py (see module docstring)
PY_OWNED_ELEMENTS = {"mavlinkcamera", "definition", "model", "vendor"}
# xmlschema's error objects are expensive; a file this broken gains nothing from more of them
MAX_SCHEMA_HITS = 200


class Hit(NamedTuple):
    """A finding before the profile gives it a severity. (A named tuple: built in C, where a frozen
    dataclass sets each field through object.__setattr__; the corpus yields a few hundred.)"""

    rule: str
    line: int | None
    parameter: str | None
    message: str


@functools.lru_cache(maxsize=1)
def compiled_schema():
    """The compiled XSD (about 0.3 s to build; built once per process)."""
    import xmlschema

    return xmlschema.XMLSchema11(str(XSD_PATH))


def _param_of(elem) -> str | None:
    while elem is not None:
        if elem.tag == "parameter":
            return elem.get("name")
        elem = elem.getparent()
    return None


def _map(err) -> tuple[str, str] | None:
    """(rule id, message) for one xmlschema error, or None when a Python rule owns it."""
    elem = err.elem
    tag = elem.tag if elem is not None and isinstance(elem.tag, str) else ""
    reason = (err.reason or err.message or "").strip()
    if tag in PY_OWNED_ELEMENTS:
        return None
    m = _UNEXPECTED.search(reason)
    if m:
        child = m.group(1)
        if child == "option":
            return None  # CDF122, semantic.py
        if child in PLACEMENT_TAGS:
            return "CDF200", f"<{child}> is not allowed inside <{tag}> (MAVSDK reads it only where the spec puts it)"
        if child == "localization":
            return "CDF210", "more than one <localization>"
        if child == "description":
            return "CDF100", "more than one <description>"
        return "CDF100", f"<{child}> is not allowed inside <{tag}>"
    if "is not complete" in reason:
        return None  # missing required children: CDF103/104/114, semantic.py
    if "character data between child elements" in reason:
        return None  # CDF211, semantic.py (it reports the exact line)
    m = _MISSING_ATTR.search(reason)
    if m:
        return None  # CDF109/123/210, semantic.py
    m = _ATTR_VALUE.search(reason)
    if m:
        attr = m.group(1)
        detail = reason.split(":", 1)[1].strip() if ":" in reason else reason
        if tag == "parameter":
            if attr in ("name", "type"):
                return None  # CDF110/111/116, semantic.py
            if attr in ("default", "min", "max", "step"):
                return "CDF120", f"{attr}={elem.get(attr)!r} is not a valid {elem.get('type')}: {detail}"
            if attr in ("control", "readonly", "writeonly"):
                return "CDF130", f'{attr}="{elem.get(attr)}" must be "0" or "1"'
            if attr == "decimalPlaces":
                return "CDF207", f'decimalPlaces="{elem.get(attr)}" must be a non-negative integer'
        return "CDF100", f"<{tag}> {reason}"
    if "length cannot be lesser than 1" in reason:
        return None  # CDF105, semantic.py
    return "CDF100", f"<{tag}>: {reason}"


# ---- fast path ---------------------------------------------------------------------------------------------
# xmlschema costs ~80 us per element (90% of a validation). Most files conform, so a conservative Python
# restatement of the XSD's mapped checks (one compiled XPath plus typed attribute checks) runs first: when it
# says "conforms", xmlschema would report
# nothing that _map keeps (tests/cdf/test_validate_schema.py checks this on the corpus and on hypothesis-
# generated mutations); on any doubt xmlschema runs and produces the findings.
_COMPLEX: dict[str, dict[str, int]] = {  # element -> allowed CDF children and their maxOccurs
    "mavlinkcamera": {"definition": 1, "parameters": 1, "localization": 1},
    "definition": {"model": 1, "vendor": 1},
    "parameters": {"parameter": 1 << 30},
    # <option> directly under <parameter> is an XSD error that _map drops (CDF122 is semantic.py's)
    "parameter": {"description": 1, "updates": 1, "options": 1, "option": 1 << 30},
    "updates": {"update": 1 << 30},
    "options": {"option": 1 << 30},
    "option": {"exclusions": 1, "parameterranges": 1},
    "exclusions": {"exclude": 1 << 30},
    "parameterranges": {"parameterrange": 1 << 30},
    "parameterrange": {"roption": 1 << 30},
    "roption": {},
    "localization": {"locale": 1 << 30},
    "locale": {"strings": 1 << 30},
    "strings": {},
}
_SIMPLE = frozenset({"model", "vendor", "description", "update", "exclude"})
_CDF_TAGS = frozenset(_COMPLEX) | _SIMPLE
_INT_LEX = re.compile(r"-?[0-9]+")
_FLOAT_LEX = re.compile(r"[-+]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]+)?")
_INT_RANGE = {"bool": (0, 1), "uint8": (0, 255), "int8": (-128, 127), "uint16": (0, 65535),
              "int16": (-32768, 32767), "uint32": (0, 2**32 - 1), "int32": (-2**31, 2**31 - 1),
              "uint64": (0, 2**64 - 1), "int64": (-2**63, 2**63 - 1)}


@functools.lru_cache(maxsize=8192)  # the same few values in every parameter of every file
def _lexical_ok(value: str, ptype: str) -> bool:
    if ptype in _INT_RANGE:
        if not _INT_LEX.fullmatch(value):
            return False
        lo, hi = _INT_RANGE[ptype]
        return lo <= int(value) <= hi
    if ptype in ("float", "double"):
        return _FLOAT_LEX.fullmatch(value) is not None
    return True  # other types: the XSD types these attributes as xs:string


def _canonical_paths() -> list[str]:
    """Absolute paths of every place the XSD allows a CDF element (the tree has a fixed depth)."""
    out, stack = [], [("/mavlinkcamera", "mavlinkcamera")]
    while stack:
        path, tag = stack.pop()
        out.append(path)
        for child in _COMPLEX.get(tag, {}):
            stack.append((f"{path}/{child}", child))
    return sorted(out)


def _build_violation_xpath() -> str:
    """One XPath 1.0 expression, evaluated in C by libxml2, that is true when the document may break the
    XSD: fewer CDF elements at canonical paths than `cdf_count` (the number of CDF elements anywhere,
    passed in as $cdf_count: a CDF element elsewhere, even inside an unknown element, where the XSD would
    skip it, counts as misplaced, which is stricter and so still safe), a child over its maxOccurs, a text
    element with non-text children, a bad parameter flag or decimalPlaces, or a processing instruction.

    Written for libxml2's speed: absolute paths touch only the nodes on them, while each //name walks the
    whole document; a sum of count()s avoids merging and sorting one big node set (measured: the union
    of the misplaced paths costs twice the sum; for the small node sets below a union is cheaper)."""
    paths = _canonical_paths()
    misplaced = f"$cdf_count != {' + '.join(f'count({p})' for p in paths)}"
    too_many = []
    for path in paths:
        capped = [c for c, n in sorted(_COMPLEX.get(path.rsplit("/", 1)[1], {}).items()) if n == 1]
        if capped:
            too_many.append(f"{path}[" + " or ".join(f"count({c}) > 1" for c in capped) + "]")
    text_with_children = [f"{p}[* or comment() or processing-instruction()]"
                          for p in paths if p.rsplit("/", 1)[1] in _SIMPLE]
    flag = " or ".join(f"(@{f} and @{f} != '0' and @{f} != '1')" for f in ("control", "readonly", "writeonly"))
    bad_attrs = (f"/mavlinkcamera/parameters/parameter[{flag} or (@decimalPlaces and (@decimalPlaces = '' or "
                 "translate(@decimalPlaces, '0123456789', '') != ''))]")
    nodes = " | ".join([*too_many, *text_with_children, bad_attrs, "//processing-instruction()"])
    return f"({misplaced}) or boolean({nodes})"


@functools.lru_cache(maxsize=1)
def _violation_xpath():
    from lxml import etree

    return etree.XPath(_build_violation_xpath())


_DIGITS = re.compile(r"[0-9]+")


def conforms_fast(root, structure_ok: bool | None = None, attributes: list[tuple] | None = None) -> bool:
    """True only if the XSD would report nothing that _map keeps. False means "not sure": run xmlschema.

    Structure is checked by one compiled XPath (C speed; it also looks inside unknown elements, which the
    XSD skips: stricter, so still safe), unless the caller already knows it from semantic.scan_tree
    (`structure_ok`: libxml2's proof of the vocabulary, or the walk's structure test in Python); typed
    attribute values by Python on the parameters only, from `attributes` when the caller has read them
    (semantic.check_document does: one tuple of TYPED_ATTRS values per parameter of the <parameters>
    section, which is the root's only one whenever the structure is sound, the only case that reads them).
    """
    if root.tag != "mavlinkcamera":
        return True  # schema_hits does not run on other roots
    tree = root.getroottree()
    if tree.docinfo.internalDTD is not None or tree.docinfo.doctype:
        return False  # entity reference nodes are invisible to XPath: let xmlschema judge
    if structure_ok is None:
        # lxml's tag-filtered iter() counts in C, 3x faster than XPath's count(//a) + count(//b) + ...
        cdf_count = sum(1 for _ in root.iter(*_CDF_TAGS))
        structure_ok = not _violation_xpath()(root, cdf_count=cdf_count)
    if not structure_ok:
        return False
    if attributes is None:
        # root.iterfind("parameters/parameter") without ElementPath's Python-level path handling
        attributes = [tuple(map(p.get, TYPED_ATTRS)) for section in root.iterchildren("parameters")
                      for p in section.iterchildren("parameter")]
    # parameters repeat these values (type uint32, default 0, ...): each distinct tuple is judged once
    # (and memoised across files, like _lexical_ok)
    return all(map(_attributes_conform, set(attributes)))


# A parameter's attributes that the XSD types, in the order of the tuples conforms_fast takes; semantic.py's
# attribute rules read the same tuple, so one read per parameter serves both.
TYPED_ATTRS = ("control", "readonly", "writeonly", "decimalPlaces", "type", "default", "min", "max", "step")


@functools.lru_cache(maxsize=4096)
def _attributes_conform(values: tuple[str | None, ...]) -> bool:
    """Whether a parameter with these values of TYPED_ATTRS passes the XSD's attribute types."""
    *flags, decimal_places, ptype, default, lo, hi, step = values
    if any(v is not None and v != "0" and v != "1" for v in flags):  # also in the XPath: scan_tree leaves them here
        return False
    if decimal_places is not None and not _DIGITS.fullmatch(decimal_places):
        return False
    return ptype is None or all(v is None or _lexical_ok(v, ptype) for v in (default, lo, hi, step))


def schema_hits(root, structure_ok: bool | None = None, attributes: list[tuple] | None = None, *,
                as_written: Callable[[], Any] | None = None) -> list[Hit]:
    """XSD findings for a document whose root is <mavlinkcamera> (other roots: CDF101, semantic.py).
    `structure_ok`, `attributes`: see conforms_fast. `as_written`: when `root` was parsed without its
    blank text (engine._hits), a function giving the tree as written, which xmlschema judges."""
    if root.tag != "mavlinkcamera" or conforms_fast(root, structure_ok, attributes):
        return []
    return xmlschema_hits(root if as_written is None else as_written())


def xmlschema_hits(root) -> list[Hit]:
    """The XSD applied by xmlschema, errors mapped to rule ids (no fast path)."""
    if root.tag != "mavlinkcamera":
        return []
    hits = []
    for err in compiled_schema().iter_errors(root):
        mapped = _map(err)
        if mapped is None:
            continue
        rule_id, message = mapped
        elem = err.elem
        # for a misplaced child, point at the child, not at its parent
        culprit = getattr(err, "invalid_child", None)
        line = getattr(culprit if culprit is not None else elem, "sourceline", None) if elem is not None else None
        hits.append(Hit(rule_id, line, _param_of(elem) if elem is not None else None, message))
        if len(hits) >= MAX_SCHEMA_HITS:
            hits.append(Hit("CDF100", None, None, f"more than {MAX_SCHEMA_HITS} schema errors; "
                                                  "the rest are not reported"))
            break
    return hits
