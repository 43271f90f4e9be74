"""Area reading and validation: every bad input gets a PlanError with where and a hint."""

from __future__ import annotations

from pathlib import Path

import pytest

from missions.geometry.area import load_area
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
    with pytest.raises(PlanError, match="DTD or entities is refused"):
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
    with pytest.raises(PlanError, match="is a directory, not a file"):
        load_area(tmp_path / "dir.geojson")


def test_oversized_file_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import dataclasses

    import missions.geometry.area as area_mod
    monkeypatch.setattr(area_mod, "AREA_FILE", dataclasses.replace(area_mod.AREA_FILE, cap=100))
    big = tmp_path / "big.geojson"
    big.write_text(" " * 200 + "{}")
    with pytest.raises(PlanError, match="area file is larger than 100 bytes") as e:
        load_area(big)
    assert "simplify" in e.value.hint


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
    with pytest.raises(PlanError) as e:
        load_area(f)
    # named by the hole and placed in lat/lon (not in the local metres of the projection)
    assert e.value.message == ("hole 0 is not inside the polygon's outer boundary (it reaches out near lat "
                               "50.1000000, lon 14.6000000)")
    assert e.value.where == f"{f}: $.coordinates[1]" and "must lie within it" in e.value.hint


def test_holes_that_touch_are_placed_in_lat_lon(tmp_path: Path) -> None:
    f = tmp_path / "h.geojson"
    f.write_text('{"type": "Polygon", "coordinates": [[[14.5, 50.1], [14.506, 50.1], [14.506, 50.104], [14.5, 50.104]],'
                 ' [[14.501, 50.101], [14.503, 50.101], [14.503, 50.103], [14.501, 50.103]],'
                 ' [[14.502, 50.102], [14.505, 50.102], [14.505, 50.1035], [14.502, 50.1035]]]}')
    with pytest.raises(PlanError) as e:
        load_area(f)
    assert e.value.message == "polygon is invalid: Self-intersection near lat 50.1020000, lon 14.5030000"


def test_a_five_megabyte_coordinate_token_is_not_echoed_whole(tmp_path: Path) -> None:
    f = tmp_path / "big.kml"
    f.write_text(_kml_ring("14.5,50.1 14.6,50.1 " + "7" * 5_000_000))
    with pytest.raises(PlanError) as e:
        load_area(f)
    assert e.value.message == f"bad KML coordinate '{'7' * 59}… (5000002 characters); expected lon,lat[,alt]"


def test_an_entity_bomb_kml_is_refused_as_one(tmp_path: Path) -> None:
    ring = "<coordinates>&l9;</coordinates>"
    entities = '<!ENTITY l0 "lol">' + "".join(f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' for i in range(1, 10))
    bombs = {"laughs": f'<?xml version="1.0"?><!DOCTYPE kml [{entities}]><kml>{ring}</kml>',
             "loop": '<?xml version="1.0"?><!DOCTYPE kml [<!ENTITY a "&b;"><!ENTITY b "&a;">]><kml>&a;</kml>'}
    for name, text in bombs.items():
        f = tmp_path / f"{name}.kml"
        f.write_text(text)
        with pytest.raises(PlanError) as e:
            load_area(f)
        assert e.value.message == "KML with a DTD or entities is refused (entity expansion)", name
        assert "remove the <!DOCTYPE" in e.value.hint


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


# ------------------------------------------------------------------ every bad file: where, what, what to do
_RING = "[[14.500, 50.100], [14.505, 50.100], [14.505, 50.103], [14.500, 50.103], [14.500, 50.100]]"
_KML = '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark>\n{}\n</Placemark></kml>'


def _kml_ring(coordinates: str) -> str:
    return _KML.format("<Polygon><outerBoundaryIs><LinearRing>\n"
                       f"<coordinates>{coordinates}</coordinates>\n</LinearRing></outerBoundaryIs></Polygon>")


def _nested_collections(depth: int) -> str:
    doc = '{"type": "Polygon", "coordinates": [' + _RING + "]}"
    for _ in range(depth):
        doc = '{"type": "GeometryCollection", "geometries": [' + doc + "]}"
    return doc


BAD_AREA_FILES = [
    # (file name, content, message pattern, a fragment the hint must contain)
    ("utf16.geojson", '{"type": "Polygon"}'.encode("utf-16"), "not UTF-8", "UTF-8"),
    ("latin1.geojson", '{"type": "Polygon", "name": "Údolí"}'.encode("latin-1"), "not UTF-8", "UTF-8"),
    ("syntax.geojson", '{"type": "Polygon",\n "coordinates": [[[14.5, 50.1] [14.6, 50.1]]]}', "invalid JSON",
     "comma"),
    ("deep_json.geojson", "[" * 5000 + "]" * 5000, "JSON nested too deeply", "4 deep"),
    ("list.geojson", "[" + _RING + "]", "must be an object", '"type": "Polygon"'),
    ("lowercase.geojson", '{"type": "polygon", "coordinates": [' + _RING + "]}", "unknown GeoJSON type",
     "case matters"),
    ("no_type.geojson", '{"coordinates": [' + _RING + "]}", "unknown GeoJSON type None", "Polygon"),
    ("no_rings.geojson", '{"type": "Polygon", "coordinates": []}', "Polygon without rings", "[[[lon, lat]"),
    ("flat_ring.geojson", '{"type": "Polygon", "coordinates": [14.5, 50.1]}', "a ring must be a list",
     "three levels"),
    ("position.geojson", '{"type": "Polygon", "coordinates": [[[14.5], [14.505, 50.1], [14.505, 50.103]]]}',
     "position must be", "[lon, lat]"),
    ("string_position.geojson", '{"type": "Polygon", "coordinates": [[["14.5", "50.1"], [14.505, 50.1]]]}',
     "position must be", "e.g. [14.7263, 50.0696]"),
    ("metres.geojson", '{"type": "Polygon", "coordinates": [[[458000, 5550000], [458500, 5550000], '
                       '[458500, 5550400]]]}', "not a longitude/latitude", "EPSG:4326"),
    ("no_features.geojson", '{"type": "FeatureCollection"}', "without a 'features' list", '"features": [...]'),
    ("features_dict.geojson", '{"type": "FeatureCollection", "features": {"type": "Feature"}}',
     "without a 'features' list", "Feature objects"),
    ("feature_number.geojson", '{"type": "FeatureCollection", "features": [5]}', "expected a GeoJSON object",
     '"type"'),
    ("multi_empty.geojson", '{"type": "MultiPolygon"}', "MultiPolygon without coordinates", "[[[[lon, lat]"),
    ("nested.geojson", _nested_collections(40), "GeoJSON nested too deeply", "FeatureCollection"),
    ("points.geojson", '{"type": "Feature", "geometry": {"type": "Point", "coordinates": [14.5, 50.1]}}',
     "no Polygon or MultiPolygon", "polygon"),
    ("empty.kml", "", "not well-formed", "export the KML again"),
    ("unclosed.kml", "<kml>\n<Placemark>\n</kml>\n", "not well-formed", "unclosed"),
    ("root_only.kml", '<kml xmlns="http://www.opengis.net/kml/2.2"/>', "no Polygon", "Add Polygon"),
    ("path.kml", _KML.format("<LineString><coordinates>14.5,50.1 14.6,50.1</coordinates></LineString>"),
     "no Polygon", "paths"),
    ("no_outer.kml", _KML.format("<Polygon>\n</Polygon>"), "without <outerBoundaryIs>", "<outerBoundaryIs>"),
    ("no_coordinates.kml", _KML.format("<Polygon><outerBoundaryIs><LinearRing>\n</LinearRing></outerBoundaryIs>"
                                       "</Polygon>"), "without <coordinates>", "<coordinates>lon,lat"),
    ("empty_coordinates.kml", _kml_ring("  "), "without <coordinates>", "<LinearRing>"),
    ("spaced.kml", _kml_ring("14.500, 50.100 14.505, 50.100 14.505, 50.103"), "bad KML coordinate",
     "no spaces inside a tuple"),
    ("lon_only.kml", _kml_ring("14.500 14.505 14.505"), "bad KML coordinate", "14.7263,50.0696"),
    ("metres.kml", _kml_ring("458000,5550000 458500,5550000 458500,5550400"), "not lon,lat in degrees",
     "longitude first"),
    ("doctype.kml", '<?xml version="1.0"?>\n<!DOCTYPE kml>\n' + _kml_ring("14.5,50.1 14.6,50.1 14.6,50.2"),
     "DTD or entities is refused", "remove the <!DOCTYPE"),
    ("undefined_entity.kml", _kml_ring("14.5,50.1 14.6,50.1 &nope;"), "Entity 'nope' not defined", "&amp;"),
    ("inf.kml", _kml_ring("14.5,50.1 14.6,50.1 14.6,1e999"), "holds a number that is not finite", "14.7263,50.0696"),
    ("geometries_number.geojson", '{"type": "GeometryCollection", "geometries": 5}',
     "GeometryCollection without a 'geometries' list", '"geometries": [...]'),
    ("geometries_object.geojson", '{"type": "GeometryCollection", "geometries": {"type": "Polygon"}}',
     "GeometryCollection without a 'geometries' list", "RFC 7946"),
    ("huge_integer.geojson", '{"type": "Polygon", "coordinates": [[[1' + "0" * 5000 + ', 50.1], [14.6, 50.1], '
                             '[14.6, 50.2]]]}', r"position \[inf, 50.1\] holds a number that is not finite", "[lon, lat]"),
    ("long_integer.geojson", '{"type": "Polygon", "coordinates": [[[14.5, 50.1], [14.6, 1' + "0" * 400 + '], '
                             '[14.6, 50.2]]]}', "not finite", "GeoJSON order"),
    ("null_ring.geojson", '{"type": "Polygon", "coordinates": [null]}', "a ring must be a list", "three levels"),
    ("null_position.geojson", '{"type": "Polygon", "coordinates": [[null, null, null]]}', "position must be",
     "[lon, lat]"),
    ("too_deep_position.geojson", '{"type": "Polygon", "coordinates": [[[[14.5, 50.1]], [14.6, 50.1], '
                                  '[14.6, 50.2]]]}', "position must be", "[lon, lat]"),
    ("multi_nulls.geojson", '{"type": "MultiPolygon", "coordinates": [null, [null]]}', "Polygon without rings",
     "outer one first"),
    ("two_points.kml", _kml_ring("14.500,50.100 14.505,50.100 14.500,50.100"), "fewer than 3 distinct points",
     "3 corners"),
    ("area.kmz", b"PK\x03\x04", "KMZ", "doc.kml"),
    ("area.shp", b"\x00\x00\x27\x0a", "unknown area file type", ".geojson"),
]


@pytest.mark.parametrize("name,content,message,hint", BAD_AREA_FILES, ids=[c[0] for c in BAD_AREA_FILES])
def test_bad_area_files_say_where_and_what_to_do(tmp_path: Path, name: str, content: str | bytes, message: str,
                                                 hint: str) -> None:
    f = tmp_path / name
    if isinstance(content, bytes):
        f.write_bytes(content)
    else:
        f.write_text(content, encoding="utf-8")
    with pytest.raises(PlanError, match=message) as e:
        load_area(name, base_dir=tmp_path)
    err = e.value
    assert err.where and str(f) in err.where                # which file (and line or JSON path where known)
    assert err.hint and hint in err.hint, err.hint          # what to do about it
    assert err.hint != err.message
    assert f"\n  hint: {err.hint}" in str(err)              # what the CLI prints


def test_bad_area_file_errors_point_into_the_file(tmp_path: Path) -> None:
    kml = tmp_path / "spaced.kml"
    kml.write_text(_kml_ring("14.500, 50.100 14.505, 50.100 14.505, 50.103"))
    with pytest.raises(PlanError) as e:
        load_area(kml)
    assert e.value.where == f"{kml}:3"                       # the line of its <coordinates>
    gj = tmp_path / "position.geojson"
    gj.write_text('{"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": '
                  '{"type": "Polygon", "coordinates": [[[14.5, 50.1], [14.505]]]}}]}')
    with pytest.raises(PlanError) as e:
        load_area(gj)
    assert e.value.where == f"{gj}: $.features[0].geometry.coordinates[0][1]"


@pytest.mark.parametrize("source,where,message", [
    ([[50.1, 14.5], [50.1, "14.505"], [50.103, 14.505]], "area[1]", "point must be"),
    ([[50.1, 14.5], [50.1], [50.103, 14.505]], "area[1]", "point must be"),
    ([[50.1, 14.5], [float("nan"), 14.505], [50.103, 14.505]], "area[1]", "not finite"),
    (5, "area", "must be a file path or a list"),
])
def test_bad_inline_areas_say_where_and_what_to_do(source, where: str, message: str) -> None:
    with pytest.raises(PlanError, match=message) as e:
        load_area(source)
    assert e.value.where == where
    assert e.value.hint and e.value.hint != e.value.message
