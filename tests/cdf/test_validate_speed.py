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

from cdf.validation import engine, schema, semantic
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


def _both(data: bytes, name: str, profile: str, monkeypatch):
    fast = validate_bytes(data, name, profile)
    with monkeypatch.context() as m:
        # no fast path: xmlschema on every document
        m.setattr(engine, "schema_hits", lambda root, _structure_ok=None: schema.xmlschema_hits(root))
        slow = validate_bytes(data, name, profile)
    return fast, slow


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
