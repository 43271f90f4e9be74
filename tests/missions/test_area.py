"""Area reading and validation: every bad input gets a PlanError with where and a hint."""

from __future__ import annotations

from pathlib import Path

import pytest

from missions.area import load_area
from missions.errors import PlanError

DATA = Path(__file__).parent / "data"
SQUARE = [[50.100, 14.500], [50.100, 14.505], [50.103, 14.505], [50.103, 14.500]]


def test_inline_square_has_the_geodesic_area() -> None:
    from pyproj import Geod
    a = load_area(SQUARE)
    lats = [p[0] for p in SQUARE]
    lons = [p[1] for p in SQUARE]
    geo_area, _ = Geod(ellps="WGS84").polygon_area_perimeter(lons, lats)
    assert a.area_m2 == pytest.approx(abs(geo_area), rel=1e-4)
    assert a.geometry.exterior.is_ccw


def test_geojson_feature_collection_equals_inline() -> None:
    a = load_area("square.geojson", base_dir=DATA)
    b = load_area(SQUARE)
    assert a.area_m2 == pytest.approx(b.area_m2, rel=1e-9)


def test_geojson_and_kml_holes_are_kept() -> None:
    for name in ("holes.geojson", "field_with_hole.kml"):
        a = load_area(DATA / name)
        assert a.geometry.geom_type == "Polygon"
        assert len(a.geometry.interiors) == 1
        outer_only = a.geometry.exterior.convex_hull.area
        assert a.area_m2 < outer_only * 0.9


def test_multipolygons_from_geojson_and_kml_multigeometry() -> None:
    a = load_area(DATA / "multi.geojson")
    b = load_area(DATA / "multigeometry.kml")
    assert a.geometry.geom_type == b.geometry.geom_type == "MultiPolygon"
    assert a.area_m2 == pytest.approx(b.area_m2, rel=1e-9)


def test_duplicate_and_closing_vertices_are_removed() -> None:
    a = load_area(DATA / "duplicates.geojson")
    assert len(a.geometry.exterior.coords) == 5          # 4 corners + closing point
    assert a.area_m2 == pytest.approx(load_area(SQUARE).area_m2, rel=1e-6)


def test_clockwise_input_is_oriented() -> None:
    assert load_area(SQUARE[::-1]).geometry.exterior.is_ccw


def test_exclusion_is_subtracted() -> None:
    a = load_area(DATA / "square.geojson", exclude=[DATA / "substation.geojson"])
    b = load_area(DATA / "square.geojson")
    assert 0 < b.area_m2 - a.area_m2 < b.area_m2
    assert len(a.geometry.interiors) == 1


def test_empty_after_exclusions() -> None:
    with pytest.raises(PlanError, match="empty once the exclusion") as e:
        load_area(DATA / "square.geojson", exclude=[DATA / "whole_cover.geojson"])
    assert e.value.hint


def test_antimeridian_geojson() -> None:
    a = load_area(DATA / "antimeridian.geojson")
    # 0.007° of longitude at 16.5° S ≈ 747 m by 0.005° of latitude ≈ 553 m
    assert a.area_m2 == pytest.approx(747 * 553, rel=0.01)


def test_self_intersecting_polygon_says_where_it_crosses() -> None:
    with pytest.raises(PlanError) as e:
        load_area(DATA / "self_intersecting.kml")
    msg = str(e.value)
    assert "intersects itself" in msg and "edge 0→1 crosses edge 2→3" in msg
    assert "lat 50.102" in msg and "lon 14.503" in msg
    assert e.value.where.endswith("self_intersecting.kml:7")          # line of its <coordinates>


def test_zero_area() -> None:
    with pytest.raises(PlanError, match="zero area"):
        load_area([[50.1, 14.5], [50.101, 14.501], [50.102, 14.502]])


@pytest.mark.parametrize("pts", [[[50.1, 14.5], [50.1, 14.501]], [[50.1, 14.5], [50.1, 14.5], [50.1, 14.5]], []])
def test_fewer_than_three_points(pts) -> None:
    with pytest.raises(PlanError, match="fewer than 3|no polygon"):
        load_area(pts)


def test_kml_without_polygon() -> None:
    with pytest.raises(PlanError, match="no Polygon") as e:
        load_area(DATA / "no_polygon.kml")
    assert "polygon" in e.value.hint


@pytest.mark.parametrize("name", ["projected_crs.geojson", "projected_nocrs.geojson"])
def test_geojson_in_a_projected_crs(name: str) -> None:
    with pytest.raises(PlanError) as e:
        load_area(DATA / name)
    assert "EPSG:4326" in e.value.hint
    assert name in e.value.where


def test_kml_with_doctype_is_refused_and_entity_not_expanded() -> None:
    with pytest.raises(PlanError, match="DOCTYPE"):
        load_area(DATA / "doctype_entity.kml")


def test_malformed_files_say_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.kml"
    bad.write_text("<kml>\n<Placemark>\n</kml>\n")
    with pytest.raises(PlanError, match="well-formed") as e:
        load_area(bad)
    assert e.value.where.startswith(str(bad) + ":")
    badj = tmp_path / "bad.geojson"
    badj.write_text('{"type": "Polygon",\n "coordinates": [[[1, 2], }\n')
    with pytest.raises(PlanError, match="invalid JSON") as e:
        load_area(badj)
    assert e.value.where == f"{badj}:2:27"


def test_missing_and_unknown_files(tmp_path: Path) -> None:
    with pytest.raises(PlanError, match="cannot read"):
        load_area(tmp_path / "nope.kml")
    (tmp_path / "a.shp").write_bytes(b"x")
    with pytest.raises(PlanError, match="unknown area file type"):
        load_area(tmp_path / "a.shp")
    (tmp_path / "dir.geojson").mkdir()  # passes stat(), fails to read
    with pytest.raises(PlanError, match="cannot read area file: Is a directory"):
        load_area(tmp_path / "dir.geojson")


def test_oversized_file_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import missions.area as area_mod
    monkeypatch.setattr(area_mod, "MAX_AREA_FILE_BYTES", 100)
    big = tmp_path / "big.geojson"
    big.write_text(" " * 200 + "{}")
    with pytest.raises(PlanError, match="limit"):
        load_area(big)


def test_swapped_inline_coordinates_get_a_hint() -> None:
    with pytest.raises(PlanError) as e:
        load_area([[150.1, 14.5], [150.2, 14.5], [150.2, 14.6]])
    assert "[lat, lon]" in e.value.hint
    assert e.value.where == "area[0]"


def test_polar_area_is_refused() -> None:
    with pytest.raises(PlanError, match="pole"):
        load_area([[86.0, 0.0], [86.0, 1.0], [86.5, 1.0]])


def test_hole_outside_the_outer_ring(tmp_path: Path) -> None:
    f = tmp_path / "h.geojson"
    f.write_text('{"type": "Polygon", "coordinates": [[[14.5, 50.1], [14.501, 50.1], [14.501, 50.101], [14.5, 50.1]],'
                 ' [[14.6, 50.1], [14.601, 50.1], [14.601, 50.101], [14.6, 50.1]]]}')
    with pytest.raises(PlanError, match="invalid") as e:
        load_area(f)
    assert "holes must lie inside" in e.value.hint


# ------------------------------------------------------------------------------------ fuzzed inputs
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

_json = st.recursive(
    st.none() | st.booleans() | st.integers(-200, 200) | st.floats(allow_infinity=True, allow_nan=True) | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=5) | st.dictionaries(
        st.sampled_from(["type", "coordinates", "features", "geometry", "geometries", "crs", "properties"]), kids,
        max_size=4),
    max_leaves=30)


@given(_json, st.sampled_from(["Polygon", "MultiPolygon", "Feature", "FeatureCollection", "GeometryCollection"]))
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_geojson_gives_an_area_or_a_plan_error(tmp_path_factory, body, kind) -> None:
    import json
    doc = {"type": kind, "coordinates": body, "features": body if isinstance(body, list) else [body],
           "geometry": body, "geometries": body if isinstance(body, list) else [body]}
    f = tmp_path_factory.mktemp("gj") / "a.geojson"
    f.write_text(json.dumps(doc))
    try:
        load_area(f)
    except PlanError as e:
        assert e.where and str(f) in e.where


@given(st.text(max_size=300), st.sampled_from(["", "<kml><Polygon><outerBoundaryIs><coordinates>"]))
@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_any_kml_text_gives_an_area_or_a_plan_error(tmp_path_factory, text, prefix) -> None:
    f = tmp_path_factory.mktemp("kml") / "a.kml"
    f.write_text(prefix + text, encoding="utf-8")
    try:
        load_area(f)
    except PlanError as e:
        assert str(f) in (e.where or "")


def test_area_spanning_the_globe_is_refused() -> None:
    with pytest.raises(PlanError, match="more than 200 km") as e:
        load_area([[50.1, 14.5], [50.1, 14.51], [0.0, 0.0]])
    assert "0,0" in e.value.hint


def test_hole_errors_point_at_the_hole(tmp_path: Path) -> None:
    f = tmp_path / "h.kml"
    f.write_text("""<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><Polygon>
<outerBoundaryIs><LinearRing><coordinates>14.500,50.100 14.506,50.100 14.506,50.104 14.500,50.104</coordinates></LinearRing></outerBoundaryIs>
<innerBoundaryIs><LinearRing>
<coordinates>14.502,50.101 14.504,50.103 14.504,50.101 14.502,50.103</coordinates></LinearRing></innerBoundaryIs>
</Polygon></Placemark></kml>""")
    with pytest.raises(PlanError, match="hole 0 intersects itself") as e:
        load_area(f)
    assert e.value.where == f"{f}:4"          # the hole's <coordinates> line
    g = tmp_path / "h.geojson"
    g.write_text('{"type": "Polygon", "coordinates": [[[14.5, 50.1], [14.506, 50.1], [14.506, 50.104], [14.5, 50.104]],'
                 ' [[14.502, 50.101], [14.504, 50.103], [14.504, 50.101], [14.502, 50.103]]]}')
    with pytest.raises(PlanError, match="hole 0") as e:
        load_area(g)
    assert e.value.where == f"{g}: $.coordinates[1]"
