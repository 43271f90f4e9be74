"""The CDF vocabulary: which elements and attributes the format knows, and where the XSD lets each stand.

QGC's constant list (VehicleCameraControl.h) plus the spec; anything else is ignored by every parser
(rule CDF211). cdf/schema/mavlinkcamera.xsd states the same shape for xmlschema; schema.conforms_fast
restates its structure from this table.
"""

from __future__ import annotations

from typing import Mapping, NamedTuple

UNBOUNDED = 1 << 30


class ElementSpec(NamedTuple):
    children: Mapping[str, int]  # child element -> its maxOccurs where the XSD allows it
    attributes: frozenset[str]
    text: bool = False  # a text element: its content is text, never children


def _spec(children: Mapping[str, int] | None = None, attributes: str = "", text: bool = False) -> ElementSpec:
    return ElementSpec(dict(children or {}), frozenset(attributes.split()), text)


VOCABULARY: dict[str, ElementSpec] = {
    "mavlinkcamera": _spec({"definition": 1, "parameters": 1, "localization": 1}),
    "definition": _spec({"model": 1, "vendor": 1}, "version"),
    "model": _spec(text=True),
    "vendor": _spec(text=True),
    "parameters": _spec({"parameter": UNBOUNDED}),
    # an <option> directly under <parameter> is no part of the format, but the Python rule CDF122 owns it:
    # the structure test lets it stand there (schema._map drops xmlschema's error for it)
    "parameter": _spec({"description": 1, "updates": 1, "options": 1, "option": UNBOUNDED},
                       "name type default control readonly writeonly min max step decimalPlaces unit"),
    "description": _spec(text=True),
    "updates": _spec({"update": UNBOUNDED}),
    "update": _spec(text=True),
    "options": _spec({"option": UNBOUNDED}),
    "option": _spec({"exclusions": 1, "parameterranges": 1}, "name value"),
    "exclusions": _spec({"exclude": UNBOUNDED}),
    "exclude": _spec(text=True),
    "parameterranges": _spec({"parameterrange": UNBOUNDED}),
    "parameterrange": _spec({"roption": UNBOUNDED}, "parameter condition"),
    "roption": _spec(attributes="name value"),
    "localization": _spec({"locale": UNBOUNDED}),
    "locale": _spec({"strings": UNBOUNDED}, "name"),
    "strings": _spec(attributes="original translated"),
}
CDF_TAGS = frozenset(VOCABULARY)
TEXT_ELEMENTS = frozenset(t for t, spec in VOCABULARY.items() if spec.text)


def canonical_paths() -> list[str]:
    """Absolute paths of every place the XSD allows a CDF element (the tree has a fixed depth)."""
    out, stack = [], [("/mavlinkcamera", "mavlinkcamera")]
    while stack:
        path, tag = stack.pop()
        out.append(path)
        for child in VOCABULARY[tag].children:
            stack.append((f"{path}/{child}", child))
    return sorted(out)


def owning_parameter(el) -> str | None:
    """The name of the <parameter> that holds `el` (or is it), if any: where a finding is reported."""
    while el is not None:
        if el.tag == "parameter":
            return el.get("name")
        el = el.getparent()
    return None
