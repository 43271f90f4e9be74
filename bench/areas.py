"""The survey-quality benchmark's areas, generated deterministically (no randomness, no files).

Each area is drawn in metres around a site and converted to [lat, lon] rings through the site's local
projection, so the benchmark exercises the whole reader path (`missions.geometry.area.build_area`) at three
latitudes — Prague (50° N), Sydney (34° S, southern hemisphere), Reykjavík (64° N) — and at Fiji, across
the 180° meridian. Kinds: convex, concave (L, U, comb, star), holes, thin strips, multipolygons, tiny
(smaller than one footprint) and large (> 1 km²).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

SITES = {
    "prague": (50.10, 14.50),
    "sydney": (-33.90, 151.10),
    "reykjavik": (64.10, -21.90),
    "fiji-180": (-16.50, 180.0),
}


@dataclass(frozen=True)
class BenchArea:
    name: str
    kind: str            # convex | concave | holes | strip | multi | tiny | large
    site: str
    convex: bool         # the ≤ 1.10 path-ratio target applies to convex areas
    polygons: tuple[Any, ...]   # shapely polygons in site metres (x east, y north)


def _rot(poly: Any, deg: float) -> Any:
    from shapely import affinity
    return affinity.rotate(poly, deg, origin="centroid")


def _star(r_out: float, r_in: float, n: int) -> Any:
    from shapely.geometry import Polygon
    pts = []
    for k in range(2 * n):
        r = r_out if k % 2 == 0 else r_in
        a = math.pi * k / n
        pts.append((r * math.sin(a), r * math.cos(a)))
    return Polygon(pts)


def _comb(teeth: int, tooth_w: float, gap: float, tooth_h: float, base_h: float) -> Any:
    from shapely.geometry import Polygon
    width = teeth * tooth_w + (teeth - 1) * gap
    top = base_h + tooth_h
    xs = [(t * (tooth_w + gap), t * (tooth_w + gap) + tooth_w) for t in range(teeth)]
    ring = [(0.0, 0.0), (width, 0.0)]
    for i, (x0, x1) in enumerate(reversed(xs)):
        ring.append((x1, top))
        ring.append((x0, top))
        if i < teeth - 1:
            ring.append((x0, base_h))
            ring.append((x0 - gap, base_h))
    return Polygon(ring)


def bench_areas() -> list[BenchArea]:
    from shapely.geometry import Polygon, box

    L = Polygon([(0, 0), (500, 0), (500, 180), (180, 180), (180, 450), (0, 450)])
    U = Polygon([(0, 0), (420, 0), (420, 400), (300, 400), (300, 130), (120, 130), (120, 400), (0, 400)])
    holed1 = box(0, 0, 500, 400).difference(box(180, 140, 320, 260))
    holed2 = box(0, 0, 600, 420).difference(box(90, 100, 210, 200)).difference(box(360, 220, 500, 330))
    c_with_hole = Polygon([(0, 0), (600, 0), (600, 150), (250, 150), (250, 300), (600, 300), (600, 450), (0, 450)]) \
        .difference(box(60, 180, 160, 280))
    areas = [
        BenchArea("square-400", "convex", "prague", True, (box(0, 0, 400, 400),)),
        BenchArea("rect-800x300-r30", "convex", "sydney", True, (_rot(box(0, 0, 800, 300), 30),)),
        BenchArea("pentagon", "convex", "reykjavik", True,
                  (Polygon([(0, 0), (520, -40), (650, 300), (330, 520), (-60, 330)]),)),
        BenchArea("triangle", "convex", "prague", True, (Polygon([(0, 0), (600, 0), (200, 450)]),)),
        BenchArea("hexagon-field", "convex", "reykjavik", True,
                  (Polygon([(0, 0), (300, -60), (560, 80), (600, 330), (330, 470), (40, 380)]),)),
        BenchArea("L-shape", "concave", "sydney", False, (L,)),
        BenchArea("U-shape", "concave", "reykjavik", False, (U,)),
        BenchArea("comb-4", "concave", "prague", False, (_comb(4, 70, 60, 300, 90),)),
        BenchArea("star-5", "concave", "sydney", False, (_star(350, 150, 5),)),
        BenchArea("square-1-hole", "holes", "prague", False, (holed1,)),
        BenchArea("rect-2-holes", "holes", "reykjavik", False, (holed2,)),
        BenchArea("C-with-hole", "holes", "sydney", False, (c_with_hole,)),
        BenchArea("strip-1500x40-r70", "strip", "prague", True, (_rot(box(0, 0, 1500, 40), 70),)),
        BenchArea("strip-1200x80-r-25", "strip", "sydney", True, (_rot(box(0, 0, 1200, 80), -25),)),
        BenchArea("two-fields", "multi", "prague", False, (box(0, 0, 300, 250), box(420, 40, 700, 300))),
        BenchArea("three-islands", "multi", "reykjavik", False,
                  (box(0, 0, 200, 200), _rot(box(300, 0, 520, 160), 20), Polygon([(0, 300), (250, 300), (120, 520)]))),
        BenchArea("tiny-triangle", "tiny", "prague", True, (Polygon([(0, 0), (25, 0), (10, 18)]),)),
        BenchArea("tiny-square-30", "tiny", "sydney", True, (box(0, 0, 30, 30),)),
        BenchArea("large-1500x1200", "large", "prague", True,
                  (Polygon([(0, 0), (1500, 60), (1460, 1200), (-40, 1150)]),)),
        BenchArea("large-L-1600", "large", "sydney", False,
                  (Polygon([(0, 0), (1600, 0), (1600, 600), (700, 600), (700, 1400), (0, 1400)]),)),
        BenchArea("antimeridian-rect", "convex", "fiji-180", True, (box(-350, -250, 350, 250),)),
        BenchArea("antimeridian-L", "concave", "fiji-180", False,
                  (Polygon([(-300, -300), (400, -300), (400, -100), (-100, -100), (-100, 350), (-300, 350)]),)),
    ]
    return areas


M_PER_DEG_LAT = 111_320.0      # metres per degree of latitude, flat-earth: enough for a bench's areas near home


def metres_per_degree(lat: float) -> tuple[float, float]:
    """(north, east) metres per degree of latitude and of longitude at latitude `lat`."""
    return M_PER_DEG_LAT, M_PER_DEG_LAT * math.cos(math.radians(lat))


def square_ring(home: tuple[float, float], side_m: float, offset_deg: float = 0.0005) -> list[list[float]]:
    """A plan's area: the [lat, lon] corners of a `side_m` square, its south-west corner `offset_deg` north and
    east of `home`."""
    m_lat, m_lon = metres_per_degree(home[0])
    dlat, dlon = side_m / m_lat, side_m / m_lon
    lat0, lon0 = home[0] + offset_deg, home[1] + offset_deg
    return [[lat0, lon0], [lat0, lon0 + dlon], [lat0 + dlat, lon0 + dlon], [lat0 + dlat, lon0]]


def built_area(a: BenchArea) -> Any:
    """The area as the plan reader builds it (missions.geometry.area.build_area), from its [lat, lon] rings."""
    from missions.geometry.area import build_area
    return build_area(to_latlon_polygons(a), source=a.name)


def to_latlon_polygons(a: BenchArea) -> list[Any]:
    """The area as missions.geometry.area.LatLonPolygon values (what a KML/GeoJSON file would give)."""
    import numpy as np
    from missions.geometry.area import LatLonPolygon
    from missions.geometry.geo import LocalProjection

    lat0, lon0 = SITES[a.site]
    proj = LocalProjection(lat0, lon0)
    out = []
    for i, p in enumerate(a.polygons):
        rings = []
        for ring in [p.exterior, *p.interiors]:
            xy = np.asarray(ring.coords)
            lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
            rings.append(tuple(zip(lat.tolist(), lon.tolist())))
        out.append(LatLonPolygon(rings[0], tuple(rings[1:]), f"{a.name}[{i}]"))
    return out
