"""The speed work on the validator (fast paths, single passes, per-document caches) changes no finding.

Independent slow path: xmlschema applying cdf/schema/mavlinkcamera.xsd to every document instead of the
conservative pre-check (schema.conforms_fast). Whole reports (rules, severities, lines, parameters,
messages, order) must be identical, on every corpus file in every profile and on hypothesis-mutated
documents. No timing is asserted here: bench/bench_validate.py measures speed.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from cdf.validation import engine, schema
from cdf.validation.rules import PROFILES
from cdf.validate import validate_bytes

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
        m.setattr(engine, "schema_hits", schema.xmlschema_hits)  # no fast path: xmlschema on every document
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
