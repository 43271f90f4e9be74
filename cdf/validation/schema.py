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

from cdf.validation.report import Hit
from cdf.validation.values import lexically_valid
from cdf.validation.vocabulary import CDF_TAGS, TEXT_ELEMENTS, VOCABULARY, canonical_paths, owning_parameter

XSD_PATH = Path(__file__).resolve().parents[1] / "schema" / "mavlinkcamera.xsd"

_ATTR_VALUE = re.compile(r"attribute ([\w:.-]+)=")
_MISSING_ATTR = re.compile(r"missing required attribute '([\w:.-]+)'")
_UNEXPECTED = re.compile(r"Unexpected child with tag '([^']+)'")
PLACEMENT_TAGS = {"exclusions", "exclude", "updates", "update", "parameterranges", "parameterrange", "roption"}
# owned by semantic.py (see module docstring)
PY_OWNED_ELEMENTS = {"mavlinkcamera", "definition", "model", "vendor"}
# xmlschema's error objects are expensive; a file this broken gains nothing from more of them
MAX_SCHEMA_HITS = 200


@functools.lru_cache(maxsize=1)
def compiled_schema():
    """The compiled XSD (about 0.3 s to build; built once per process)."""
    import xmlschema

    return xmlschema.XMLSchema11(str(XSD_PATH))


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
# xmlschema costs ~80 us per element, some 20 times a parse of the document, and most files conform. So a
# conservative restatement of the XSD's mapped checks runs first (one XPath for the structure, Python for the
# typed attributes): when it says "conforms", xmlschema would report nothing that _map keeps
# (tests/cdf/test_validate_schema.py and test_validate_speed.py hold it to that on the corpus and on
# generated mutations); on any doubt xmlschema runs and produces the findings.

# A parameter's attributes that the XSD types
TYPED_ATTRS = ("control", "readonly", "writeonly", "decimalPlaces", "type", "default", "min", "max", "step")
_DIGITS = re.compile(r"[0-9]+")
# `$cdf_count` for the XPath's first try, which assumes every element is a CDF element
NOT_COUNTED = -1


def _build_violation_xpath() -> str:
    """One XPath 1.0 expression that is true when the document may break the XSD's structure: fewer CDF
    elements at canonical paths than `$cdf_count`, the number of CDF elements anywhere (a CDF element
    elsewhere, even inside an unknown element, where the XSD would skip it, counts as misplaced: stricter,
    so still safe), a child over its maxOccurs, a text element with non-text children, or a processing
    instruction. Absolute paths, not //name: libxml2 then visits only the nodes on them.

    A document of CDF elements only has `count(//*)` CDF elements, which libxml2 counts far faster than
    Python iterates them; `$cdf_count` is asked for only when the two counts differ (see conforms_fast)."""
    paths = canonical_paths()
    placed = " + ".join(f"count({p})" for p in paths)
    misplaced = f"count(//*) != {placed} and $cdf_count != {placed}"
    too_many = []
    for path in paths:
        children = VOCABULARY[path.rsplit("/", 1)[1]].children
        capped = [c for c, n in sorted(children.items()) if n == 1]
        if capped:
            too_many.append(f"{path}[" + " or ".join(f"count({c}) > 1" for c in capped) + "]")
    text_with_children = [f"{p}[* or comment() or processing-instruction()]"
                          for p in paths if p.rsplit("/", 1)[1] in TEXT_ELEMENTS]
    nodes = " | ".join([*too_many, *text_with_children, "//processing-instruction()"])
    return f"({misplaced}) or boolean({nodes})"


@functools.lru_cache(maxsize=1)
def _violation_xpath():
    """Compiled once per process, like the XSD."""
    from lxml import etree

    return etree.XPath(_build_violation_xpath())


def conforms_fast(root) -> bool:
    """True only if the XSD would report nothing that _map keeps. False means "not sure": run xmlschema.

    Structure by one XPath (which also looks inside unknown elements, where the XSD skips them: stricter,
    so still safe), then the typed attributes of the parameters."""
    if root.tag != "mavlinkcamera":
        return True  # schema_hits does not run on other roots
    info = root.getroottree().docinfo
    if info.internalDTD is not None or info.doctype:
        return False  # entity reference nodes are invisible to XPath: let xmlschema judge
    # first as if every element were a CDF element (the count is then not needed), then with the count
    if _violation_xpath()(root, cdf_count=NOT_COUNTED) and _violation_xpath()(root, cdf_count=_cdf_count(root)):
        return False
    # parameters repeat their attributes (type uint32, default 0, ...): each distinct tuple is judged once
    distinct = {tuple(map(p.get, TYPED_ATTRS)) for section in root.iterchildren("parameters")
                for p in section.iterchildren("parameter")}
    return all(map(_attributes_conform, distinct))


def _cdf_count(root) -> int:
    return sum(1 for _ in root.iter(*CDF_TAGS))


def _attributes_conform(values: tuple[str | None, ...]) -> bool:
    """Whether a parameter with these values of TYPED_ATTRS passes the XSD's attribute types."""
    *flags, decimal_places, ptype, default, lo, hi, step = values
    if any(v is not None and v != "0" and v != "1" for v in flags):
        return False
    if decimal_places is not None and not _DIGITS.fullmatch(decimal_places):
        return False
    return ptype is None or all(v is None or lexically_valid(v, ptype) for v in (default, lo, hi, step))


def schema_hits(root) -> list[Hit]:
    """XSD findings for a document whose root is <mavlinkcamera> (other roots: CDF101, semantic.py)."""
    if root.tag != "mavlinkcamera" or conforms_fast(root):
        return []
    return xmlschema_hits(root)


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
        hits.append(Hit(rule_id, line, owning_parameter(elem) if elem is not None else None, message))
        if len(hits) >= MAX_SCHEMA_HITS:
            hits.append(Hit("CDF100", None, None, f"more than {MAX_SCHEMA_HITS} schema errors; "
                                                  "the rest are not reported"))
            break
    return hits
