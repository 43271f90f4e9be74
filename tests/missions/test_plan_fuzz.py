"""Property: any YAML document (any text) yields a Plan or a PlanError with a location — never another exception."""

from __future__ import annotations

from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings, strategies as st

from missions.errors import PlanError
from missions.plan import Plan, parse_plan

PLANS = Path(__file__).resolve().parent / "plans"
GOOD = (PLANS / "good.yaml").read_text()
NAME = "fuzz.yaml"

VOCAB = ["version", "name", "vehicle", "firmware", "frame", "speed_mps", "home", "lat", "lon", "alt_amsl_m",
         "payloads", "thermal", "camera", "wiris-pro", "rededge-mx", "settings", "layout", "capture", "mission",
         "takeoff", "alt_m", "survey", "area", "payloads", "altitude_m", "gsd_cm", "overlap", "front", "side",
         "trigger", "hover", "waypoint", "capture", "rtl", "land", "component_id", "imager", "lens_mm",
         "angle_deg", "auto", "corridor", "line", "width_m", "exclude", "refly_90", "off", "yes", "~"]


def check(text: str) -> None:
    try:
        result = parse_plan(text, NAME, PLANS)
    except PlanError as e:
        assert "internal" not in e.message, e.message
        probs = getattr(e, "problems", None)
        if probs is None:
            assert e.where and e.where.startswith(NAME)
        else:
            assert probs
            for p in probs:
                assert p.where.startswith(NAME), p
        return
    assert isinstance(result, Plan)


scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(VOCAB), st.text(max_size=8))
trees = st.recursive(scalars, lambda kids: st.one_of(
    st.lists(kids, max_size=5), st.dictionaries(st.sampled_from(VOCAB), kids, max_size=6)), max_leaves=30)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=300))
def test_any_text(text):
    check(text)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(trees)
def test_any_yaml_structure(tree):
    check(yaml.safe_dump(tree, allow_unicode=True))


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.sampled_from(VOCAB), trees, max_size=4), st.sampled_from(
    ["vehicle", "home", "payloads", "mission", "version"]))
def test_good_plan_with_a_part_replaced(extra, key):
    doc = yaml.safe_load(GOOD)
    doc[key] = extra if key != "mission" else [extra]
    check(yaml.safe_dump(doc, allow_unicode=True))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, len(GOOD)), st.integers(0, 6), st.text(max_size=4)), min_size=1, max_size=4))
def test_good_plan_mutated(edits):
    text = GOOD
    for pos, cut, ins in edits:
        pos = min(pos, len(text))
        text = text[:pos] + ins + text[pos + cut:]
    check(text)
