"""Property: any YAML document (any text) yields a Plan or a PlanError with a location and a hint — never another
exception."""

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
            assert e.hint, e
        else:
            assert probs
            for p in probs:
                assert p.where.startswith(NAME), p
                assert p.hint, p  # every answer says what to do, not only what is wrong
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


# Every leaf of the bundled examples, replaced by a value of the wrong kind or size, or removed: the
# shapes a user's edit produces (this found `exclude: 0.5` crashing the area-file lookup).
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
EXAMPLE_DOCS = {p.name: yaml.safe_load(p.read_text()) for p in sorted(EXAMPLES.glob("*.yaml"))}
ODD = [0, -1, 0.5, 1e308, -1e308, float("nan"), float("inf"), "", [], {}, True, None, "x" * 300, 2**64, [0],
       [[0, 0]], {"a": 1}, 100, 360, "auto"]


def _leaf_paths(node, path=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaf_paths(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaf_paths(v, path + (i,))
    if path:
        yield path


EXAMPLE_PATHS = sorted((name, path) for name, doc in EXAMPLE_DOCS.items() for path in _leaf_paths(doc))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(EXAMPLE_PATHS), st.one_of(st.sampled_from(ODD), st.just(KeyError)))
def test_example_with_one_part_replaced_or_removed(where, value):
    import copy

    name, path = where
    doc = copy.deepcopy(EXAMPLE_DOCS[name])
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    if value is KeyError:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    try:
        result = parse_plan(yaml.safe_dump(doc, allow_unicode=True), NAME, EXAMPLES)
    except PlanError as e:
        for p in getattr(e, "problems", None) or [e]:
            assert p.where and p.where.startswith(NAME), p
            assert p.hint, p
        return
    assert isinstance(result, Plan)


# ------------------------------------------------------------------------------------------------ area files
# Property: any GeoJSON or KML area file yields an Area or a PlanError naming the file, with a hint — never
# another exception ("internal error" at the CLI). The documents are GeoJSON- and KML-shaped, with every member
# free to hold any JSON value (`"geometries": 5`), positions of any depth, and numbers of any length.

import json  # noqa: E402
import tempfile  # noqa: E402

from missions.geometry.area import Area, load_area  # noqa: E402

GEOJSON_TYPES = ["Polygon", "MultiPolygon", "Feature", "FeatureCollection", "GeometryCollection", "Point",
                 "LineString", "polygon", ""]
MEMBERS = ["type", "coordinates", "geometries", "features", "geometry", "crs", "properties", "bbox"]

numbers = st.one_of(st.floats(-200, 200), st.integers(-200, 200), st.sampled_from([1e308, -1e308, 0, 90, 180]),
                    st.integers(1, 5000).map(lambda n: _BigNumber("9" * n)))
positions = st.lists(numbers, min_size=0, max_size=4)
rings = st.lists(positions, min_size=0, max_size=6)
json_values = st.recursive(st.none() | st.booleans() | numbers | st.text(max_size=6) | st.sampled_from(GEOJSON_TYPES),
                           lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.sampled_from(MEMBERS), kids,
                                                                                     max_size=4), max_leaves=20)


class _BigNumber(str):
    """A number literal written as digits into the JSON text (json.dumps cannot write an int of 5000 digits
    without Python refusing to convert it)."""


def _geojson_objects(depth: int):
    inner = (st.deferred(lambda: _geojson_objects(depth - 1)) if depth > 0 else json_values)
    member_values = st.one_of(json_values, rings, st.lists(rings, max_size=3), st.lists(st.lists(rings, max_size=2),
                                                                                           max_size=2),
                              st.lists(inner, max_size=3), inner)
    return st.builds(lambda kind, members: {"type": kind, **members}, st.sampled_from(GEOJSON_TYPES),
                     st.dictionaries(st.sampled_from(MEMBERS[1:]), member_values, max_size=4))


def _dumps(value) -> str:
    if isinstance(value, _BigNumber):
        return str(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)}: {_dumps(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_dumps(v) for v in value) + "]"
    return json.dumps(value)


def check_area(name: str, content: str) -> None:
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / name
        path.write_text(content, encoding="utf-8")
        try:
            result = load_area(path)
        except PlanError as e:
            assert "internal" not in e.message, e.message
            assert e.where and str(path) in e.where, e
            assert e.hint, e
            assert len(e.message) < 400, e.message       # echoed values are cut, whatever the input's size
            return
    assert isinstance(result, Area)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_geojson_objects(2))
def test_any_geojson_area_file(doc):
    check_area("area.geojson", _dumps(doc))


KML_TOKENS = st.one_of(st.builds(lambda a, b: f"{a},{b}", numbers.map(str), numbers.map(str)),
                       st.sampled_from(["14.5,50.1", "14.6,50.1,0", "14.6,50.2", "x", ",", "1e999,1", "nan,nan",
                                        "&amp;", "&lt;", " "]),
                       st.text(alphabet="0123456789.,-e ", max_size=12))
KML_ELEMENTS = ["Placemark", "Polygon", "MultiGeometry", "outerBoundaryIs", "innerBoundaryIs", "LinearRing",
                "coordinates", "Document", "Folder"]
kml_trees = st.recursive(st.lists(KML_TOKENS, max_size=6).map(" ".join),
                         lambda kids: st.builds(lambda tag, body: f"<{tag}>{''.join(body)}</{tag}>",
                                                st.sampled_from(KML_ELEMENTS), st.lists(kids, max_size=3)),
                         max_leaves=15)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kml_trees)
def test_any_kml_area_file(body):
    check_area("area.kml", f'<kml xmlns="http://www.opengis.net/kml/2.2">{body}</kml>')
