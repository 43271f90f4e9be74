"""The CDF vocabulary, and a proof of it that libxml2 checks in C.

VOCABULARY says which elements and attributes the format knows; schema._COMPLEX says where the XSD lets
each element stand and how often. Checking both is a look at every element (semantic._vocabulary_walk),
which in Python costs more than parsing the file. Most files break neither, or only with unknown
attributes (QGC's own example puts default= on <options>), so `unknown_attributes` first asks libxml2:
an XSD 1.0 generated from those two tables, applied in C. When its only complaints are unknown
attributes, the walk would report exactly those and find the structure sound; on anything else, or
anything the XSD cannot see, it answers None and the walk runs. tests/cdf/test_validate_speed.py holds
the two to the same answers on the corpus and on generated mutations.
"""

from __future__ import annotations

import functools
import re
import threading

from cdf.validation.schema import _COMPLEX, _SIMPLE

# The CDF vocabulary: element -> (known child elements, known attributes). QGC's constant list
# (VehicleCameraControl.h) plus the spec; anything else is ignored by every parser (rule CDF211).
VOCABULARY: dict[str, tuple[frozenset[str], frozenset[str]]] = {
    "mavlinkcamera": (frozenset({"definition", "parameters", "localization"}), frozenset()),
    "definition": (frozenset({"model", "vendor"}), frozenset({"version"})),
    "model": (frozenset(), frozenset()),
    "vendor": (frozenset(), frozenset()),
    "parameters": (frozenset({"parameter"}), frozenset()),
    "parameter": (frozenset({"description", "updates", "options"}),
                  frozenset({"name", "type", "default", "control", "readonly", "writeonly", "min", "max", "step",
                             "decimalPlaces", "unit"})),
    "description": (frozenset(), frozenset()),
    "updates": (frozenset({"update"}), frozenset()),
    "update": (frozenset(), frozenset()),
    "options": (frozenset({"option"}), frozenset()),
    "option": (frozenset({"exclusions", "parameterranges"}), frozenset({"name", "value"})),
    "exclusions": (frozenset({"exclude"}), frozenset()),
    "exclude": (frozenset(), frozenset()),
    "parameterranges": (frozenset({"parameterrange"}), frozenset()),
    "parameterrange": (frozenset({"roption"}), frozenset({"parameter", "condition"})),
    "roption": (frozenset(), frozenset({"name", "value"})),
    "localization": (frozenset({"locale"}), frozenset()),
    "locale": (frozenset({"strings"}), frozenset({"name"})),
    "strings": (frozenset(), frozenset({"original", "translated"})),
}
CDF_TAGS = frozenset(VOCABULARY)
TEXT_ELEMENTS = frozenset({"model", "vendor", "description", "update", "exclude"})

_XSI = "http://www.w3.org/2001/XMLSchema-instance"
# libxml2's error types for an attribute the schema does not declare (on a complex / a simple type)
_ATTRIBUTE_ERRORS = frozenset({"SCHEMAV_CVC_COMPLEX_TYPE_3_2_1", "SCHEMAV_CVC_TYPE_3_1_1"})
_UNKNOWN_ATTRIBUTE = re.compile(r"Element '([^']+)', attribute '([^']+)': The attribute '[^']+' is not allowed\.")
_XML_DECLARATION = re.compile(rb"(\xef\xbb\xbf)?<\?xml\s[^>]*\?>")


def _xsd_text() -> str:
    """An XSD 1.0 that a document passes iff every element is a known one at a place schema._COMPLEX
    allows, within its maxOccurs, with known attributes only and no text outside the text elements.
    (XSD 1.0's xs:all holds only children that occur at most once: where an element also allows a
    repeated child, <parameter> with a stray <option>, the repeated one is left out, so such a file
    fails here and the walk judges it.)"""
    assert TEXT_ELEMENTS == _SIMPLE and CDF_TAGS == frozenset(_COMPLEX) | _SIMPLE

    def declare(tag: str, occurs: str) -> str:
        attrs = "".join(f'<xs:attribute name="{a}"/>' for a in sorted(VOCABULARY[tag][1]))
        if tag in TEXT_ELEMENTS:
            if not attrs:
                return f'<xs:element name="{tag}" type="xs:string"{occurs}/>'
            body = f'<xs:simpleContent><xs:extension base="xs:string">{attrs}</xs:extension></xs:simpleContent>'
            return f'<xs:element name="{tag}"{occurs}><xs:complexType>{body}</xs:complexType></xs:element>'
        children = _COMPLEX[tag]
        once = sorted(c for c, n in children.items() if n == 1)
        repeated = sorted(c for c, n in children.items() if n > 1)
        if once:
            model = "<xs:all>" + "".join(declare(c, ' minOccurs="0"') for c in once) + "</xs:all>"
        elif repeated:
            model = ('<xs:choice minOccurs="0" maxOccurs="unbounded">' + "".join(declare(c, "") for c in repeated)
                     + "</xs:choice>")
        else:
            model = ""
        return f'<xs:element name="{tag}"{occurs}><xs:complexType>{model}{attrs}</xs:complexType></xs:element>'

    return ('<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">' + declare("mavlinkcamera", "")
            + "</xs:schema>")


@functools.lru_cache(maxsize=1)
def _schema():
    from lxml import etree

    return etree.XMLSchema(etree.fromstring(_xsd_text())), threading.Lock()


@functools.lru_cache(maxsize=1)
def _hidden_xpaths():
    from lxml import etree

    return (etree.XPath("boolean(//processing-instruction())"),
            etree.XPath(f"boolean(//@*[namespace-uri() = '{_XSI}'])"))


def _hidden_from_xsd(root, data: bytes | None, info) -> bool:
    """For a document that passed the XSD but for unknown attributes: True when it may hold what the XSD
    does not judge the way the walk does: a comment or processing instruction inside a text element or
    a processing instruction anywhere (the walk counts them as children or doubts the structure), an
    attribute in the XSI namespace (a validator obeys xsi:type and xsi:nil instead of rejecting them).
    `info`: the document's docinfo."""
    pi, xsi = _hidden_xpaths()
    # the bytes answer first where they can (the tree checks reach every text element, the XPaths walk
    # the whole tree): in UTF-8 comments and processing instructions are spelled out, and an attribute
    # can be in a namespace only through a prefix that an xmlns: attribute binds (names take no
    # character references; entities need a DTD, and a document with one never gets here)
    if data is None or (info.encoding or "").upper() not in ("UTF-8", "UTF8"):
        return _text_element_has_children(root) or pi(root) or xsi(root)
    declaration = _XML_DECLARATION.match(data)
    return ((_has(data, b"?>", b"?", declaration.end() if declaration else 0) and pi(root))
            or (_has(data, b"xmlns:", b":") and xsi(root))
            or (_comment_may_follow_text_start(data) and _text_element_has_children(root)))


def _has(data: bytes, needle: bytes, rare: bytes, start: int = 0) -> bool:
    """needle in data[start:], asked first of `rare`, a byte of needle that camera definitions seldom hold:
    bytes.find of one byte is a memchr, 30x faster on these files than of a longer needle (CPython steps
    through the data by the needle's last byte, and ">" is everywhere in XML)."""
    at = data.find(rare, start)
    # needle's first occurrence at q >= start holds `rare` at q + k, a position >= at
    return at >= 0 and data.find(needle, max(start, at - needle.index(rare))) >= 0


def _text_element_has_children(root) -> bool:
    # an element child has failed the XSD already: what is left are comments and processing instructions
    return any(len(el) for el in root.iter(*TEXT_ELEMENTS))


_TEXT_START = re.compile(rb"<(?:" + b"|".join(t.encode() for t in sorted(TEXT_ELEMENTS)) + rb")[\s>]")


def _comment_may_follow_text_start(data: bytes) -> bool:
    """False when no comment in these UTF-8 bytes can be inside a text element: the markup before each
    comment is not a text element's start tag. (The first comment inside a text element follows its start
    tag and character data, which holds no "<" outside CDATA sections; entities need a DTD. With a CDATA
    section anywhere the answer is True: not sure.)"""
    comment = cdata = False
    at = data.find(b"!", 1)  # every comment and CDATA section holds a "!", which is rare elsewhere (see _has)
    while at >= 0:
        if data[at - 1] != 0x3C:  # a "!" in text: on to the next "<!" (so a text full of "!" costs no loop)
            at = data.find(b"<!", at) + 1
            if not at:
                break
        if data.startswith(b"<!--", at - 1):
            if cdata:
                return True
            comment = True
            before = data.rfind(b"<", 0, at - 1)
            if before >= 0 and _TEXT_START.match(data, before):
                return True
        elif data.startswith(b"<![CDATA[", at - 1):
            if comment:
                return True
            cdata = True
        at = data.find(b"!", at + 1)
    return False


def unknown_attributes(root, data: bytes | None = None) -> list[tuple[str, str]] | None:
    """When the document breaks the vocabulary and the XSD's structure in no way but unknown attributes:
    those, as (element tag, attribute name) in document order, each pair once. None when not sure (the
    walk must judge). `data`: the bytes `root` was parsed from, when the caller has them (a shortcut)."""
    if root.tag != "mavlinkcamera":
        return None
    info = root.getroottree().docinfo
    if info.internalDTD is not None or info.doctype:
        return None  # entity references: the walk judges them
    schema, lock = _schema()
    with lock:  # the error log lives on the schema object
        errors = [] if schema.validate(root) else [(e.type_name, e.message) for e in schema.error_log]
    pairs: dict[tuple[str, str], None] = {}
    for kind, message in errors:
        m = _UNKNOWN_ATTRIBUTE.fullmatch(message) if kind in _ATTRIBUTE_ERRORS else None
        if m is None or m.group(1) not in CDF_TAGS:
            return None
        if m.group(2).lower() != "decimalplaces":  # a misspelt decimalPlaces is CDF207, semantic.py
            pairs[(m.group(1), m.group(2))] = None
    return None if _hidden_from_xsd(root, data, info) else list(pairs)
