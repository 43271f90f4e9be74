"""The speed work on the validator (fast paths, single passes, memoised values) changes no finding.

Independent slow path: xmlschema applying cdf/schema/mavlinkcamera.xsd to every document instead of the
conservative pre-check (schema.conforms_fast). Whole reports (rules, severities, lines, parameters,
messages, order) must be identical, on every corpus file in every profile and on hypothesis-mutated
documents. No timing is asserted here: bench/bench_validate.py measures speed.
"""

from __future__ import annotations

import lzma
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from cdf.validation import engine, schema, semantic, vocabulary
from cdf.validation.rules import PROFILES
from cdf.validate import validate_bytes
from cdf.xmlsafe import parse_xml

def _sibling(name: str):
    """The mutation strategy of test_validate_schema.py (tests/cdf is not a package, so load it by path)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_cdf_{name}", Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_schema_tests = _sibling("test_validate_schema")
BASE, mutation, mutate = _schema_tests.BASE, _schema_tests.mutation, _schema_tests.mutate
CORPUS = Path(__file__).resolve().parents[3] / "shared" / "corpus" / "cdf"
FILES = sorted(CORPUS.rglob("*.xml")) + sorted(CORPUS.rglob("*.xml.xz"))


def _report(data: bytes, name: str, profile: str, monkeypatch, **engine_attrs):
    """validate_bytes with these attributes of cdf.validation.engine replaced for the call."""
    with monkeypatch.context() as m:
        for attr, value in engine_attrs.items():
            m.setattr(engine, attr, value)
        return validate_bytes(data, name, profile)


def _both(data: bytes, name: str, profile: str, monkeypatch):
    # the slow side has no fast path: xmlschema on every document
    return (_report(data, name, profile, monkeypatch),
            _report(data, name, profile, monkeypatch, schema_hits=lambda root, *_known, as_written=None:
                    schema.xmlschema_hits(root if as_written is None else as_written())))


def test_corpus_is_present():
    assert len(FILES) >= 20


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_corpus_reports_equal_the_xmlschema_path(path, monkeypatch):
    data = path.read_bytes()
    for profile in PROFILES:
        fast, slow = _both(data, path.name, profile, monkeypatch)
        assert fast == slow


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(ops=st.lists(mutation, min_size=0, max_size=6), declare=st.booleans())
def test_mutated_reports_equal_the_xmlschema_path(ops, declare, monkeypatch):
    root = mutate(etree.fromstring(BASE), ops)
    data = (b'<?xml version="1.0" encoding="UTF-8"?>\n' if declare else b"") + etree.tostring(root)
    fast, slow = _both(data, "m.xml", "strict", monkeypatch)
    assert fast == slow, data


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(mutation, min_size=0, max_size=6))
def test_scan_structure_verdict_equals_the_xpath(ops):
    # two independent statements of the XSD's structure (scan_tree's walk, schema.py's XPath) agree
    root = mutate(etree.fromstring(BASE), ops)
    scan = semantic.scan_tree(root)
    assert schema.conforms_fast(root, scan.xsd_structure_ok) == schema.conforms_fast(root), etree.tostring(root)
    assert list(scan.vocabulary) == list(semantic._vocabulary_walk(root))
    # the parameters' attributes as check_document read them serve conforms_fast like its own reading
    attributes: list[tuple] = []
    list(semantic.check_document(root, etree.tostring(root), scan, attributes))
    assert schema.conforms_fast(root, scan.xsd_structure_ok, attributes) == schema.conforms_fast(root)


def test_scan_structure_verdict_on_the_corpus():
    for path in FILES:
        root = parse_xml(path.read_bytes() if path.suffix == ".xml" else lzma.decompress(path.read_bytes()),
                         path.name)[0]
        assert schema.conforms_fast(root, semantic.scan_tree(root).xsd_structure_ok) == schema.conforms_fast(root)


@pytest.mark.parametrize("doc", [
    BASE.replace(b"<description>p</description>", b"<description>p<?pi x?></description>"),
    BASE.replace(b"</mavlinkcamera>", b"</mavlinkcamera><?pi x?>"),
    BASE.replace(b"<updates>", b"<x><option/></x><updates>"),
    BASE.replace(b"<model>m</model>", b"<model>m</model><model>n</model>"),
    BASE.replace(b"<exclusions>", b"<exclusions><exclusions/>"),
])
def test_scan_structure_doubts(doc):
    root = etree.fromstring(doc)
    assert not semantic.scan_tree(root).xsd_structure_ok
    assert not schema.conforms_fast(root)


def test_values_memoised_across_files_change_no_report():
    # typed values are memoised for the process: a file validated after others (warm) gets the report it
    # gets alone (cold), in every profile
    for f in FILES[:8]:
        data = f.read_bytes()
        warm = [validate_bytes(data, f.name, p) for p in PROFILES]
        engine.clear_caches()
        cold = [validate_bytes(data, f.name, p) for p in PROFILES]
        assert warm == cold, f.name


# ---- libxml2's proof of the vocabulary (cdf/validation/vocabulary.py) answers like the Python walk ----------

XSI = "http://www.w3.org/2001/XMLSchema-instance"
proof_mutation = st.one_of(
    mutation,
    st.tuples(st.just("pi"), st.integers(0, 10**6), st.just(""), st.integers(0, 10)),
    st.tuples(st.just("nsattr"), st.integers(0, 10**6),
              st.sampled_from([f"{{{XSI}}}type", f"{{{XSI}}}nil", "{urn:x}a", "{http://www.w3.org/XML/1998/namespace}lang"]),
              st.sampled_from(["xs:anyType", "true", "1"])),
    st.tuples(st.just("text"), st.integers(0, 10**6), st.sampled_from(["\u00a0", "\u2003x", "\t"]), st.booleans()),
)


def _proof_mutate(root, ops):
    for op in ops:
        kind, where, what, extra = op
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        el = elements[where % len(elements)]
        if kind == "pi":
            el.insert(extra % (len(el) + 1), etree.ProcessingInstruction("pi", "x"))
        elif kind == "nsattr":
            el.set(what, extra)
        else:
            root = mutate(root, [op])
    return root


def _walk(root):
    hits = list(semantic._vocabulary_walk(root, structure := []))
    return hits, not structure


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(proof_mutation, min_size=0, max_size=6),
       declaration=st.sampled_from([b"", b'<?xml version="1.0" encoding="UTF-8"?>\n',
                                    b'<?xml version="1.0" encoding="ISO-8859-1"?>\n']))
def test_vocabulary_proof_answers_like_the_walk(ops, declaration):
    data = declaration + etree.tostring(_proof_mutate(etree.fromstring(BASE), ops))
    root = parse_xml(data, "m.xml")[0]
    hits, sound = _walk(root)
    for given_bytes in (data, None):  # the byte shortcut and the XPath checks
        scan = semantic.scan_tree(root, given_bytes)
        assert (list(scan.vocabulary), scan.xsd_structure_ok) == (hits, sound), data


@pytest.mark.parametrize("doc", [
    # what libxml2's XSD does not judge like the walk: each must send the file to the walk
    BASE.replace(b"<description>p</description>", b"<description>p<!-- c --></description>"),
    BASE.replace(b"<description>p</description>", b"<description>p<?pi x?></description>"),
    # comments in text elements past what the byte test reads: after a CDATA section holding "<", after
    # a start tag with a line break or an unknown attribute holding ">", in each kind of text element
    BASE.replace(b"<description>p</description>", b"<description><![CDATA[a<b]]><!-- c --></description>"),
    BASE.replace(b"<description>p</description>", b'<description\n z=">">p<!-- c --></description>'),
    BASE.replace(b"<exclude>P</exclude>", b"<exclude>P<!-- c --></exclude>"),
    BASE.replace(b"<update>CAM_MODE</update>", b"<update><!-- c -->CAM_MODE</update>"),
    BASE.replace(b"<model>m</model>", b"<model>m<!-- c --><!-- d --></model>"),
    BASE.replace(b"<vendor>v</vendor>", b"<vendor>\n<!-- c -->v</vendor>"),
    BASE.replace(b"</mavlinkcamera>", b"</mavlinkcamera><?pi x?>"),
    BASE.replace(b"<parameter name=\"P\"", f'<parameter xmlns:i="{XSI}" i:type="xs:anyType" '
                 'xmlns:xs="http://www.w3.org/2001/XMLSchema" name="P"'.encode()),
    # the XSI namespace spelled with character references: not in the bytes as such
    BASE.replace(b"<model>m</model>", b'<model xmlns:i="&#104;ttp://www.w3.org/2001/XMLSchema-instance" '
                                      b'i:nil="true">m</model>'),
    BASE.replace(b"<mavlinkcamera>", b'<!DOCTYPE mavlinkcamera [<!ENTITY e "x">]><mavlinkcamera>'),
    BASE.replace(b"<localization>", b"<localization>\xc2\xa0"),
    BASE.replace(b"<description>Mode</description>", b"<description>Mode</description><option name='s' value='2'/>"),
])
def test_vocabulary_proof_leaves_what_it_cannot_see_to_the_walk(doc):
    data = b'<?xml version="1.0" encoding="UTF-8"?>\n' + doc
    root = parse_xml(data, "m.xml")[0]
    assert vocabulary.unknown_attributes(root, data) is None
    assert vocabulary.unknown_attributes(root) is None
    scan = semantic.scan_tree(root, data)
    assert (list(scan.vocabulary), scan.xsd_structure_ok) == _walk(root)


def test_comments_outside_text_elements_need_no_look_at_the_tree():
    # the byte test clears comments between elements, after end tags and after self-closing tags of
    # other elements, so files with comments (most of the corpus) skip the text-element scan
    doc = (BASE.replace(b"<parameters>", b"<parameters><!-- a -->")
           .replace(b"</description>", b"</description><!-- b -->")
           .replace(b'<roption name="a" value="1"/>', b'<roption name="a" value="1"/><!-- c -->'))
    assert not vocabulary._comment_may_follow_text_start(doc)
    commented = [d for d in (f.read_bytes() for f in FILES if f.suffix == ".xml") if b"<!--" in d]
    assert len(commented) >= 15
    assert not any(vocabulary._comment_may_follow_text_start(d) for d in commented)


@pytest.mark.parametrize("data, needle, rare, start, found", [
    (b"a?b?>c", b"?>", b"?", 0, True),  # the first "?" is not the needle's: search on from there
    (b"a?b?c>", b"?>", b"?", 0, False),
    (b"<?xml?>x", b"?>", b"?", 7, False),  # only the declaration's, before start
    (b"<?xml?>x?>", b"?>", b"?", 7, True),
    (b"a:b xmlns:i=", b"xmlns:", b":", 0, True),  # the needle's rare byte is not its first
    (b"xmlns", b"xmlns:", b":", 0, False),
    (b"", b"?>", b"?", 0, False),
])
def test_has_finds_exactly_what_find_finds(data, needle, rare, start, found):
    assert vocabulary._has(data, needle, rare, start) is found is (data.find(needle, start) >= 0)


@pytest.mark.parametrize("doc, may", [
    (b"<!-- a --><m/>", False),  # a comment at the very start
    (b"<m>Hi! there<!-- a --></m>", False),  # "!" in text, then a comment not in a text element
    (b"<model>Hi!<!-- a --></model>", True),
    (b"<m><![CDATA[x]]></m><!-- a -->", True),  # CDATA anywhere: not sure, in either order
    (b"<!-- a --><m><![CDATA[x]]></m>", True),
    (b"<m><![CDATA[x]]></m>", False),  # no comment at all
    (b"<m>" + b"!" * 5000 + b"</m><!-- a --><model>!!<!-- b --></model>", True),  # "!"s in text skipped
    (b"<m>" + b"!" * 5000 + b"</m><!-- a -->", False),
])
def test_comment_byte_test_reads_every_bang(doc, may):
    assert vocabulary._comment_may_follow_text_start(doc) is may


def test_attribute_rules_are_a_pure_function_of_the_attribute_values():
    # memoised across parameters and files: the same values give the same answer wherever they stand
    # (values in the order of schema.TYPED_ATTRS: control, readonly, writeonly, decimalPlaces, type, default,
    # min, max, step)
    rules = semantic._attribute_rules
    assert rules(("0", None, None, None, "uint32", "0", None, None, None), True) == ("uint32", True, 0, ())
    ptype, numeric, default, findings = rules((None, "1", "1", None, "UINT16", "70000", "5", "1", "0"), False)
    assert (ptype, numeric, default) == ("uint16", False, None)
    assert [r for r, _m in findings] == ["CDF111", "CDF115", "CDF131"]
    _p, _n, default, findings = rules((None, None, None, None, "int32", "3000000000", "5", "1", "0"), False)
    assert default is None and [r for r, _m in findings] == ["CDF128", "CDF128"]  # invalid default: the XSD's
    _p, _n, default, findings = rules((None, None, None, None, "uint32", "7", "0", "10", "2"), False)
    assert default == 7 and [m for _r, m in findings] == ["default 7 is not on the step grid 0 + n*2"]
    assert rules((None, None, None, None, "uint32", "7", "0", "10", "2"), True)[3][0][0] == "CDF129"  # range + options


def test_vocabulary_proof_reports_unknown_attributes_once_in_document_order():
    doc = (BASE.replace(b'<option name="Photo" value="0">', b'<option name="Photo" value="0" z="1" y="2">')
           .replace(b'<option name="Video" value="1">', b'<option name="Video" value="1" y="3">')
           .replace(b"<model>m</model>", b'<model lang="en">m</model>'))
    root = etree.fromstring(doc)
    assert vocabulary.unknown_attributes(root, doc) == [("model", "lang"), ("option", "z"), ("option", "y")]
    hits = semantic.scan_tree(root, doc).vocabulary
    assert [(h.line, h.parameter, h.message.split()[1]) for h in hits] == [
        (1, None, "model@lang"), (3, "CAM_MODE", "option@z"), (3, "CAM_MODE", "option@y")]
    assert list(hits) == _walk(root)[0]


def test_vocabulary_proof_settles_most_of_the_corpus_like_the_walk():
    settled = 0
    for path in FILES:
        data = path.read_bytes() if path.suffix == ".xml" else lzma.decompress(path.read_bytes())
        root = parse_xml(data, path.name)[0]
        settled += vocabulary.unknown_attributes(root, data) is not None
        scan = semantic.scan_tree(root, data)
        assert (list(scan.vocabulary), scan.xsd_structure_ok) == _walk(root), path.name
    assert settled >= len(FILES) - 3  # measured: all but hist_e30z (stray text) and siyi_a8_mini (stray <option>)


# ---- the tree without blank text (engine._hits) ---------------------------------------------------------

def _lean_and_as_written(data: bytes, profile: str, monkeypatch, lean=None):
    """The report as validate_bytes gives it, and with every document parsed as written (blank text
    kept). `lean`: force engine._lean's answer for the first (None: its own)."""
    forced = {} if lean is None else {"_lean": lambda _data: lean}
    return (_report(data, "m.xml", profile, monkeypatch, **forced),
            _report(data, "m.xml", profile, monkeypatch, _lean=lambda _data: False))


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_corpus_reports_without_blank_text_equal_those_as_written(path, monkeypatch):
    for profile in PROFILES:
        got, written = _lean_and_as_written(path.read_bytes(), profile, monkeypatch)
        assert got == written


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(ops=st.lists(mutation, min_size=0, max_size=6), pretty=st.booleans())
def test_mutated_reports_without_blank_text_equal_those_as_written(ops, pretty, monkeypatch):
    # the mutations put blank and non-blank text, comments and unknown elements anywhere, text elements
    # included; pretty printing adds blank text between all elements
    root = mutate(etree.fromstring(BASE), ops)
    data = b'<?xml version="1.0" encoding="UTF-8"?>\n' + etree.tostring(root, pretty_print=pretty)
    got, written = _lean_and_as_written(data, "strict", monkeypatch)
    assert got == written, data


_LOCALIZED = BASE.replace(b'original="p"', b'original="  p"')  # the description "p" with two blanks


@pytest.mark.parametrize("doc", [
    # blanks beside a child of a text element: libxml2 drops them, so these must not take the lean tree
    BASE.replace(b"<description>p</description>", b"<description>  <!-- c -->  </description>"),
    BASE.replace(b"<description>p</description>", b"<description>\n<?pi x?>\n</description>"),
    BASE.replace(b"<model>m</model>", b"<model> <!-- c --></model>"),
    BASE.replace(b"<update>CAM_MODE</update>", b"<update> <x/> </update>"),
    # blanks as an element's only content are kept; beside a comment in an element-only one, dropped
    BASE.replace(b"<description>p</description>", b"<description>  </description>"),
    BASE.replace(b'<roption name="a" value="1"/>', b'<roption name="a" value="1"> <!-- c --> </roption>'),
    BASE.replace(b'<roption name="a" value="1"/>', b'<roption name="a" value="1">  </roption>'),
    BASE.replace(b"<parameters>", b'<parameters xml:space="preserve">  '),
    _LOCALIZED.replace(b"<description>p</description>", b"<description>  <![CDATA[p]]></description>"),
    _LOCALIZED.replace(b"<description>p</description>", b"<description>&#32; p</description>"),
])
def test_blank_text_that_rules_read_is_read_as_written(doc, monkeypatch):
    data = b'<?xml version="1.0" encoding="UTF-8"?>\n' + doc
    for profile in PROFILES:
        got, written = _lean_and_as_written(data, profile, monkeypatch)
        assert got == written, profile


def test_cdata_keeps_the_tree_as_written(monkeypatch):
    # the guard is needed: without blank text, the description before a CDATA section loses its blanks
    # and the localization string that names it "  p" no longer matches
    data = _LOCALIZED.replace(b"<description>p</description>", b"<description>  <![CDATA[p]]></description>")
    assert not engine._lean(data)
    forced, written = _lean_and_as_written(data, "strict", monkeypatch, lean=True)
    assert "match no description" in " ".join(f.message for f in forced.findings)
    assert forced != written
