"""The XSD fast path (schema.conforms_fast) never hides an xmlschema finding: whenever it says a document
conforms, xmlschema applying cdf/schema/mavlinkcamera.xsd reports nothing the validator keeps."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from cdf.validation.schema import conforms_fast, xmlschema_hits
from cdf.xmlsafe import parse_xml
import corpus

CORPUS = corpus.CDF

BASE = b"""<mavlinkcamera><definition version="1"><model>m</model><vendor>v</vendor></definition><parameters>
<parameter name="CAM_MODE" type="uint32" default="0" control="0"><description>Mode</description>
<options><option name="Photo" value="0"><exclusions><exclude>P</exclude></exclusions></option>
<option name="Video" value="1"><parameterranges><parameterrange parameter="P"><roption name="a" value="1"/>
</parameterrange></parameterranges></option></options></parameter>
<parameter name="P" type="float" default="1.5" min="0" max="2" step="0.5"><description>p</description>
<updates><update>CAM_MODE</update></updates></parameter>
</parameters><localization><locale name="de_DE"><strings original="p" translated="q"/></locale></localization>
</mavlinkcamera>"""

TAGS = ["mavlinkcamera", "definition", "model", "vendor", "parameters", "parameter", "description", "updates",
        "update", "options", "option", "exclusions", "exclude", "parameterranges", "parameterrange", "roption",
        "localization", "locale", "strings", "videostreams", "foo", "{urn:x}ext"]
ATTRS = ["default", "min", "max", "step", "control", "readonly", "writeonly", "decimalPlaces", "type", "name",
         "value", "unit", "version", "v4l_id"]
VALUES = ["0", "1", "-1", "255", "256", "1.5", "1e3", "inf", "NaN", "abc", "", " 1", "+2", "01", "true",
          "4294967296", "-9223372036854775809", "uint8", "UINT8", "float", "bool", "int64", "custom"]

mutation = st.one_of(
    st.tuples(st.just("insert"), st.integers(0, 10**6), st.sampled_from(TAGS), st.integers(0, 10)),
    st.tuples(st.just("attr"), st.integers(0, 10**6), st.sampled_from(ATTRS), st.sampled_from(VALUES)),
    st.tuples(st.just("text"), st.integers(0, 10**6), st.sampled_from(["x", "  ", "\n"]), st.booleans()),
    st.tuples(st.just("comment"), st.integers(0, 10**6), st.just(""), st.integers(0, 10)),
    st.tuples(st.just("delete"), st.integers(0, 10**6), st.just(""), st.just(0)),
)


def mutate(root, ops):
    for kind, where, what, extra in ops:
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        el = elements[where % len(elements)]
        if kind == "insert":
            el.insert(extra % (len(el) + 1), etree.Element(what))
        elif kind == "attr":
            el.set(what, extra)
        elif kind == "text":
            if extra or el is root:
                el.text = (el.text or "") + what
            else:
                el.tail = (el.tail or "") + what
        elif kind == "comment":
            el.insert(extra % (len(el) + 1), etree.Comment("c"))
        elif kind == "delete" and el is not root:
            el.getparent().remove(el)
    return root


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(mutation, min_size=1, max_size=6))
def test_fast_path_never_hides_an_xsd_finding(ops):
    root = mutate(etree.fromstring(BASE), ops)
    if conforms_fast(root):
        assert xmlschema_hits(root) == [], etree.tostring(root)


def test_fast_path_is_not_vacuous():
    assert conforms_fast(etree.fromstring(BASE))
    assert xmlschema_hits(etree.fromstring(BASE)) == []
    bad = etree.fromstring(BASE.replace(b'default="1.5"', b'default="x"'))
    assert not conforms_fast(bad) and [h.rule for h in xmlschema_hits(bad)] == ["CDF120"]


def test_fast_path_on_the_corpus():
    for path in sorted(CORPUS.rglob("*.xml")):
        root = parse_xml(path.read_bytes(), path.name)[0]
        if conforms_fast(root):
            assert xmlschema_hits(root) == [], path.name


def test_vocabulary_rule_on_the_base_and_an_unknown_element():
    from cdf.validation import semantic

    assert list(semantic._check_vocabulary(etree.fromstring(BASE))) == []
    odd = etree.fromstring(BASE.replace(b"<description>p</description>", b"<description>p</description><x/>"))
    assert [h.rule for h in semantic._check_vocabulary(odd)] == ["CDF211"]
