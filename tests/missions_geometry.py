"""Geometry strategies and helpers for tests/missions (importable: tests/ is on pytest's path)."""

from __future__ import annotations

import math

from hypothesis import strategies as st

from missions.geometry.area import Area
from missions.geometry.footprint import Footprint
from missions.geometry.geo import LocalProjection

# WIRIS Pro 640×512, 17 µm pixels, 13 mm lens at 60 m: the benchmark's thermal footprint.
GSD_M = 60 * 17e-6 / 13e-3
WIRIS_60M = Footprint(640 * GSD_M, 512 * GSD_M)


def area_from_xy(geom, lat0: float = 50.0, lon0: float = 14.0) -> Area:
    return Area(geom, LocalProjection(lat0, lon0), "test")


@st.composite
def star_polygons(draw, max_radius: float = 400.0):
    """Simple (non-self-intersecting) star-shaped polygons: concave in general."""
    from shapely.geometry import Polygon
    n = draw(st.integers(5, 12))
    angles = sorted(draw(st.lists(st.floats(0, 2 * math.pi, exclude_max=True), min_size=n, max_size=n,
                                  unique_by=lambda a: round(a, 2))))
    radii = draw(st.lists(st.floats(0.25 * max_radius, max_radius), min_size=n, max_size=n))
    pts = [(r * math.sin(a), r * math.cos(a)) for a, r in zip(angles, radii)]
    poly = Polygon(pts)
    if not poly.is_valid or poly.area < 1000:
        from hypothesis import assume
        assume(False)
    return poly


@st.composite
def convex_polygons(draw, max_size: float = 600.0):
    from hypothesis import assume
    from shapely.geometry import MultiPoint
    # on a 1 mm grid, as real areas are: projected from degrees (a double near 50 deg steps by 7e-15 deg,
    # 1e-9 m), a vertex is never 1e-300 m from another, which st.floats draws now and then and which
    # makes GEOS fail ("non-noded intersection") or numpy warn inside shapely's buffer
    coord = st.integers(0, round(max_size * 1000)).map(lambda mm: mm / 1000)
    pts = draw(st.lists(st.tuples(coord, coord), min_size=3, max_size=10))
    hull = MultiPoint(pts).convex_hull
    assume(hull.geom_type == "Polygon" and hull.area > 2000)
    # thin slivers are covered too, but keep the width sensible for a survey
    assume(hull.area / hull.length > 5)
    return hull


def leg_crossings(legs, geom) -> list[float]:
    """Lengths of outside pieces of legs that do not touch a leg end (a leg that leaves and re-enters)."""
    from shapely.geometry import LineString, Point
    bad = []
    inside = geom.buffer(1e-6)
    for l in legs:
        if l.length_m < 1e-9:
            continue
        seg = LineString([(l.x0, l.y0), (l.x1, l.y1)])
        out = seg.difference(inside)
        parts = getattr(out, "geoms", [out]) if not out.is_empty else []
        ends = [Point(l.x0, l.y0), Point(l.x1, l.y1)]
        for p in parts:
            if p.length > 1e-6 and min(p.distance(e) for e in ends) > 1e-6:
                bad.append(p.length)
    return bad
