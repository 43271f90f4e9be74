"""A local metric projection centred on the survey area: lat/lon <-> x/y in metres.

Azimuthal equidistant (pyproj `+proj=aeqd`) centred on the area: distances from the centre are exact and
the scale error elsewhere grows as (d/R)^2/6 — 1e-5 at 50 km, i.e. 0.5 m over 50 km — so footprints,
spacings and trigger distances keep their meaning anywhere on Earth. x = east, y = north at the centre.

Longitudes wrap: the centre is taken on the unwrapped longitudes (so an area across the 180° meridian is
centred on it, not on the opposite side of the globe) and pyproj computes longitude differences modulo 360.
`to_latlon` returns longitudes normalised to [-180, 180).

Near the poles "north–south lines" and a planar grid stop making sense (all meridians converge); areas with
any vertex beyond ±MAX_ABS_LAT_DEG are refused with a PlanError, as are areas wider than MAX_EXTENT_M.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

from missions.errors import PlanError

# Beyond this, meridian convergence makes "angle from north" ambiguous across one survey block
# (at 85° a 2 km wide area already sees ~1.3° of convergence) and multirotor compasses are unreliable.
MAX_ABS_LAT_DEG = 85.0
# An aeqd plane is accurate to 1e-5 within 50 km of its centre; a single survey larger than this is
# certainly a unit mistake (a projected CRS read as degrees) or should be split into several plans.
MAX_EXTENT_M = 200_000.0
EARTH_RADIUS_M = 6371008.8   # mean radius (IUGG)


def great_circle_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Distance in metres between two points in degrees (haversine on the mean sphere): what a glide slope
    or a camera's own trigger spacing needs over a few kilometres, without a projection."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    h = math.sin((p2 - p1) / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lon2 - lon1) / 2) ** 2
    return 2 * EARTH_RADIUS_M * math.asin(min(1.0, math.sqrt(h)))


def leaf_parts(g: Any, geom_type: str) -> Iterator[Any]:
    """The non-empty parts of type `geom_type` ("Polygon", "LineString") of a shapely result, however
    deeply nested in multi-geometries and collections (clipping and differences return any mix)."""
    stack = [g]
    while stack:
        h = stack.pop()
        if h.is_empty:
            continue
        if h.geom_type == geom_type:
            yield h
        elif hasattr(h, "geoms"):
            stack.extend(h.geoms)


def unwrap_lons(lons: Sequence[float], ref: float | None = None) -> np.ndarray:
    """Shift longitudes by multiples of 360 so that each lies within 180° of `ref` (default: the first)."""
    arr = np.asarray(lons, dtype=float)
    if arr.size == 0:
        return arr
    r = arr[0] if ref is None else ref
    return r + ((arr - r + 180.0) % 360.0) - 180.0


def normalise_lon(lon: np.ndarray | float) -> np.ndarray | float:
    """Longitude(s) in [-180, 180)."""
    return ((np.asarray(lon, dtype=float) + 180.0) % 360.0) - 180.0 if isinstance(lon, np.ndarray) \
        else ((float(lon) + 180.0) % 360.0) - 180.0


@dataclass(frozen=True)
class LocalProjection:
    """Azimuthal-equidistant plane centred at (lat0, lon0); immutable and safe to share."""

    lat0: float
    lon0: float
    _fwd: object = field(init=False, repr=False, compare=False)
    _inv: object = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        from pyproj import CRS, Transformer

        if not (math.isfinite(self.lat0) and math.isfinite(self.lon0)):
            raise PlanError("projection centre is not a finite coordinate",
                            hint="check the area's coordinates for NaN/inf values")
        if abs(self.lat0) > MAX_ABS_LAT_DEG:
            raise PlanError(f"area centre at latitude {self.lat0:.4f}° is too close to a pole",
                            hint=f"areas must lie within ±{MAX_ABS_LAT_DEG:g}° latitude")
        lon0 = normalise_lon(self.lon0)
        local = CRS.from_proj4(f"+proj=aeqd +lat_0={self.lat0!r} +lon_0={lon0!r} +datum=WGS84 +units=m +no_defs")
        wgs84 = CRS.from_epsg(4326)
        object.__setattr__(self, "_fwd", Transformer.from_crs(wgs84, local, always_xy=True))
        object.__setattr__(self, "_inv", Transformer.from_crs(local, wgs84, always_xy=True))

    @classmethod
    def centred_on(cls, lats: Iterable[float], lons: Iterable[float]) -> "LocalProjection":
        """Projection centred on the bounding box of the points, wrap-aware; refuses polar points."""
        la = np.asarray(list(lats), dtype=float)
        lo = np.asarray(list(lons), dtype=float)
        if la.size == 0:
            raise PlanError("no coordinates to centre a projection on",
                            hint="a bug in wiris-tools (its callers always pass points): please report it with "
                                 "the plan")
        bad = np.abs(la) > MAX_ABS_LAT_DEG
        if bad.any():
            i = int(np.argmax(bad))
            raise PlanError(f"point {i} at latitude {la[i]:.5f}° is too close to a pole",
                            hint=f"survey areas must lie within ±{MAX_ABS_LAT_DEG:g}° latitude; "
                                 "near the poles a north-referenced grid is meaningless")
        u = unwrap_lons(lo)
        lat0 = 0.5 * (la.min() + la.max())
        lon0 = 0.5 * (u.min() + u.max())
        return cls(float(lat0), float(normalise_lon(lon0)))

    def to_xy(self, lats: Sequence[float] | np.ndarray, lons: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Degrees -> metres (x east, y north)."""
        x, y = self._fwd.transform(np.asarray(lons, dtype=float), np.asarray(lats, dtype=float))  # type: ignore[attr-defined]
        return np.asarray(x, dtype=float), np.asarray(y, dtype=float)

    def to_latlon(self, xs: Sequence[float] | np.ndarray, ys: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Metres -> degrees (lat, lon), lon in [-180, 180)."""
        lon, lat = self._inv.transform(np.asarray(xs, dtype=float), np.asarray(ys, dtype=float))  # type: ignore[attr-defined]
        return np.asarray(lat, dtype=float), np.asarray(normalise_lon(np.asarray(lon, dtype=float)))

    # Headings are measured along 100 m: far enough that the projection's rounding (~1e-6 m) turns none.
    def true_azimuths(self, xs: Sequence[float] | np.ndarray, ys: Sequence[float] | np.ndarray,
                      headings_deg: Sequence[float] | np.ndarray) -> np.ndarray:
        """Headings in this plane (degrees clockwise from its y axis) at (xs, ys) as azimuths from true north,
        what a vehicle's yaw is: the plane's north turns away from true north away from its centre."""
        from pyproj import Geod

        x, y, h = (np.asarray(v, dtype=float) for v in (xs, ys, np.radians(headings_deg)))
        lat, lon = self.to_latlon(x, y)
        lat2, lon2 = self.to_latlon(x + 100.0 * np.sin(h), y + 100.0 * np.cos(h))
        return np.asarray(Geod(ellps="WGS84").inv(lon, lat, lon2, lat2)[0], dtype=float) % 360.0

    def plane_headings(self, xs: Sequence[float] | np.ndarray, ys: Sequence[float] | np.ndarray,
                       azimuths_deg: Sequence[float] | np.ndarray) -> np.ndarray:
        """Azimuths from true north at (xs, ys) as headings in this plane: the inverse of true_azimuths."""
        from pyproj import Geod

        x, y = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
        lat, lon = self.to_latlon(x, y)
        lon2, lat2, _ = Geod(ellps="WGS84").fwd(lon, lat, np.asarray(azimuths_deg, dtype=float), np.full(len(x), 100.0))
        x2, y2 = self.to_xy(lat2, lon2)
        return np.degrees(np.arctan2(x2 - x, y2 - y)) % 360.0

    def point_to_xy(self, lat: float, lon: float) -> tuple[float, float]:
        x, y = self.to_xy([lat], [lon])
        return float(x[0]), float(y[0])

    def point_to_latlon(self, x: float, y: float) -> tuple[float, float]:
        lat, lon = self.to_latlon([x], [y])
        return float(lat[0]), float(lon[0])
