"""The validator's one fast path, the conservative XSD pre-check (schema.conforms_fast), changes no finding.

Independent slow path: xmlschema applying cdf/schema/mavlinkcamera.xsd to every document instead of the
pre-check. Whole reports (rules, severities, lines, parameters, messages, order) must be identical, on
every corpus file in every profile and on hypothesis-mutated documents. No timing is asserted here:
bench/bench_validate.py measures speed.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from cdf.validation import engine, schema, semantic
from cdf.validation.rules import PROFILES
from cdf.validate import validate_bytes
import corpus

def _sibling(name: str):
    """The mutation strategy of test_validate_schema.py (tests/cdf is not a package, so load it by path)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_cdf_{name}", Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_schema_tests = _sibling("test_validate_schema")
BASE, mutation, mutate = _schema_tests.BASE, _schema_tests.mutation, _schema_tests.mutate
FILES = corpus.cdf_files()


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


@pytest.mark.parametrize("doc", [
    BASE.replace(b"<description>p</description>", b"<description>p<?pi x?></description>"),
    BASE.replace(b"</mavlinkcamera>", b"</mavlinkcamera><?pi x?>"),
    BASE.replace(b"<updates>", b"<x><option/></x><updates>"),
    BASE.replace(b"<model>m</model>", b"<model>m</model><model>n</model>"),
    BASE.replace(b"<exclusions>", b"<exclusions><exclusions/>"),
])
def test_structure_doubts(doc):
    assert not schema.conforms_fast(etree.fromstring(doc))


def test_reports_do_not_depend_on_the_files_validated_before():
    # a file validated after others gets the report it gets before them, in every profile
    first = {f.name: [validate_bytes(f.read_bytes(), f.name, p) for p in PROFILES] for f in FILES[:8]}
    for f in reversed(FILES[:8]):
        assert [validate_bytes(f.read_bytes(), f.name, p) for p in PROFILES] == first[f.name], f.name


def test_attribute_rules_are_a_pure_function_of_the_attribute_values():
    # the same values give the same answer wherever they stand (values in the order of schema.TYPED_ATTRS:
    # control, readonly, writeonly, decimalPlaces, type, default, min, max, step)
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


def test_unknown_attributes_are_reported_once_in_document_order():
    doc = (BASE.replace(b'<option name="Photo" value="0">', b'<option name="Photo" value="0" z="1" y="2">')
           .replace(b'<option name="Video" value="1">', b'<option name="Video" value="1" y="3">')
           .replace(b"<model>m</model>", b'<model lang="en">m</model>'))
    hits = list(semantic._check_vocabulary(etree.fromstring(doc)))
    assert [(h.line, h.parameter, h.message.split()[1]) for h in hits] == [
        (1, None, "model@lang"), (3, "CAM_MODE", "option@z"), (3, "CAM_MODE", "option@y")]


_LOCALIZED = BASE.replace(b'original="p"', b'original="  p"')  # the description "p" with two blanks


def test_blanks_before_a_cdata_section_are_part_of_the_text():
    # the description "  <![CDATA[p]]>" reads "  p", which the localization string names
    data = b'<?xml version="1.0" encoding="UTF-8"?>\n' + _LOCALIZED.replace(
        b"<description>p</description>", b"<description>  <![CDATA[p]]></description>")
    report = validate_bytes(data, "m.xml", "strict")
    assert "match no description" not in " ".join(f.message for f in report.findings)
