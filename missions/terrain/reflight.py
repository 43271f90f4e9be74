"""The re-flight measured over the DEM: each photo's height above the ground below it, its footprint cut by the
terrain, and from those coverage and the minimum front and side overlap (missions.measure.report calls it when
the compiled mission carries a DEM).

Footprint on the ground: the camera looks straight down (nadir, heading = the photo's); the rays through the
image's four corners and four edge midpoints are followed down to where they meet the DEM (a damped fixed-point
iteration: the drop d along a ray with ground offset u per metre solves d = camera altitude - ground(c + u d)),
so a footprint on a slope is wider downhill than uphill, as the view cone cut by the ground is. A ray that leaves
the DEM lands at the height below the camera.

  coverage       area(area ∩ ⋃ footprints) / area(area)
  front overlap  consecutive photos of one camera-on stretch: area(F_i ∩ F_i+1) / mean area of the two
  side overlap   for each photo, its nearest photo of another stretch on each side, parallel within 20° and
                 within half a footprint along track: the overlap of the two footprints' across-track extents
                 through their centres (the edge midpoints' rays), over the photo's own; a neighbour whose
                 extent does not reach is a gap, which coverage measures instead
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from missions.terrain.clearance import Clearance, is_terrain_item, path_clearance
from missions.terrain.dem import PlaneGround

if TYPE_CHECKING:
    from missions.compiled import PayloadInfo

GROUND_FLAT = "ground assumed flat at home elevation"
_RAY_ITERATIONS = 24
_PARALLEL_SIN = math.sin(math.radians(20.0))
# Multipliers (along, across) of the footprint's half extents, in ring order: corners and edge midpoints.
_RING = np.array([(-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0)], dtype=float)
_LEFT_MID, _RIGHT_MID = 1, 5           # the across-track edge midpoints through the centre


@dataclass(frozen=True)
class GroundPhotos:
    """One payload's photos over the DEM, aligned with the photo list they were made from."""

    hag_m: np.ndarray               # camera height above the ground directly below
    ring: np.ndarray                # (n, 8, 2) footprint outline on the ground, simulation metres
    polygons: np.ndarray            # shapely Polygons of `ring`


@dataclass(frozen=True)
class StepGround:
    """One step's photos' heights above ground against its target and tolerance."""

    step: int
    target_m: float
    tolerance_m: float
    hag_min_m: float | None
    hag_max_m: float | None
    outside_tolerance: int          # photos below the target or above target + tolerance (by more than 5 cm)

    def to_json(self) -> dict[str, Any]:
        r = lambda v: None if v is None else round(v, 2)   # noqa: E731
        return {"step": self.step, "target_m": r(self.target_m), "tolerance_m": r(self.tolerance_m),
                "height_above_ground_m": [r(self.hag_min_m), r(self.hag_max_m)],
                "photos_outside_tolerance": self.outside_tolerance}


@dataclass(frozen=True)
class GroundReport:
    """What the report says about the ground: the DEM, the clearance, each step's heights above ground."""

    dem: tuple[Any, ...]            # missions.terrain.dem.DemInfo
    frame: str
    clearance_m: float
    clearance: Clearance | None
    steps: tuple[StepGround, ...]

    @property
    def ground(self) -> str:
        files = ", ".join(f"{f.path.rsplit('/', 1)[-1]} ({f.vertical}, {f.resolution_m:.1f} m)" for f in self.dem)
        return f"from the DEM: {files}"

    def to_json(self) -> dict[str, Any]:
        return {"dem": [f.to_json() for f in self.dem], "frame": self.frame, "clearance_m": self.clearance_m,
                "min_clearance": None if self.clearance is None else self.clearance.to_json(),
                "steps": [s.to_json() for s in self.steps]}


def _ground_xy(dem: Any, proj: Any, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    lat, lon = proj.to_latlon(x, y)
    return dem.ground_amsl(lat, lon)


def camera_amsl(compiled: Any, photos: Sequence[Any], ground_below: np.ndarray) -> np.ndarray:
    """Each photo's camera altitude above mean sea level: above home's elevation, or above the ground below it
    for a photo taken flying to a terrain-frame item."""
    alt = np.array([p.alt_m for p in photos], dtype=float)
    terrain = np.array([is_terrain_item(compiled, p.item) for p in photos], dtype=bool)
    return np.where(terrain, ground_below + alt, compiled.home[2] + alt)



def footprint_ring(heading_deg: np.ndarray, payload: PayloadInfo) -> np.ndarray:
    """Each photo's footprint outline per metre of height above the ground, (n, 8, 2) in the ring order of
    _RING (corners and edge midpoints), turned to its heading."""
    h = np.radians(heading_deg)
    d = np.column_stack([np.sin(h), np.cos(h)])
    nrm = np.column_stack([np.cos(h), -np.sin(h)])
    across, along = payload.footprint_m(1.0)
    return d[:, None, :] * (_RING[None, :, 0:1] * along / 2) + nrm[:, None, :] * (_RING[None, :, 1:2] * across / 2)


def flat_ground_photos(centres: np.ndarray, alt_m: np.ndarray, heading_deg: np.ndarray,
                       payload: PayloadInfo) -> GroundPhotos:
    """Footprints on flat ground: each photo's rectangle at its own height, as GroundPhotos, so that one set of
    overlap measures serves flat ground and a DEM."""
    import shapely

    ring = centres[:, None, :] + footprint_ring(heading_deg, payload) * np.maximum(alt_m, 0.0)[:, None, None]
    closed = np.concatenate([ring, ring[:, :1]], axis=1)
    return GroundPhotos(alt_m.astype(float), ring, shapely.polygons(closed) if len(alt_m) else np.zeros(0, object))


def ground_photos(compiled: Any, sim: Any, photos: Sequence[Any], payload: Any) -> GroundPhotos:
    import shapely

    dem, proj = compiled.terrain.dem, sim.projection
    n = len(photos)
    if n == 0:
        return GroundPhotos(np.zeros(0), np.zeros((0, 8, 2)), np.zeros(0, dtype=object))
    c = np.array([(p.x, p.y) for p in photos], dtype=float)
    below = _ground_xy(dem, proj, c[:, 0], c[:, 1])
    z = camera_amsl(compiled, photos, below)
    hag = z - below
    u = footprint_ring(np.array([p.heading_deg for p in photos], dtype=float), payload)
    drop = np.repeat(np.maximum(hag, 0.0)[:, None], len(_RING), axis=1)
    # the rays land within a footprint of their photo, 1.5 times its reach covers every iteration's guess
    reach = 1.5 * float(np.max(np.abs(u))) * float(np.nanmax(np.maximum(hag, 0.0)) if len(hag) else 0.0) + 1.0
    grid = PlaneGround(dem, proj, (c[:, 0].min() - reach, c[:, 1].min() - reach, c[:, 0].max() + reach,
                                   c[:, 1].max() + reach), max(0.5, dem.resolution_m / 2.0))
    for _ in range(_RAY_ITERATIONS):
        pos = c[:, None, :] + u * drop[:, :, None]
        g = grid.at(pos[..., 0].ravel(), pos[..., 1].ravel()).reshape(drop.shape)
        g = np.where(np.isfinite(g), g, below[:, None])
        drop = np.maximum(0.5 * drop + 0.5 * (z[:, None] - g), 0.0)
    ring = c[:, None, :] + u * drop[:, :, None]
    closed = np.concatenate([ring, ring[:, :1]], axis=1)
    return GroundPhotos(hag, ring, shapely.polygons(closed))


def coverage_on_ground(geom: Any, gp: GroundPhotos, idx: np.ndarray) -> float:
    import shapely

    if geom.area <= 0 or not len(idx):
        return 0.0
    ok = idx[gp.hag_m[idx] > 0]
    union = shapely.union_all(gp.polygons[ok])
    return float(shapely.intersection(geom, union).area / geom.area)


def min_front_overlap(photos: Sequence[Any], gp: GroundPhotos, idx: np.ndarray) -> float | None:
    import shapely

    ks = [int(k) for k in idx]
    pairs = [(a, b) for a, b in zip(ks[:-1], ks[1:]) if photos[a].span == photos[b].span and b == a + 1]
    if not pairs:
        return None
    a = np.array([p[0] for p in pairs])
    b = np.array([p[1] for p in pairs])
    inter = shapely.area(shapely.intersection(gp.polygons[a], gp.polygons[b]))
    mean = 0.5 * (shapely.area(gp.polygons[a]) + shapely.area(gp.polygons[b]))
    return float(np.min(inter / np.maximum(mean, 1e-9)))


def min_side_overlap(photos: Sequence[Any], gp: GroundPhotos, idx: np.ndarray, payload: Any) -> float | None:
    import shapely

    if len(idx) < 2:
        return None
    c = np.array([(photos[k].x, photos[k].y) for k in idx], dtype=float)
    h = np.radians([photos[k].heading_deg for k in idx])
    span = np.array([photos[k].span for k in idx])
    d = np.column_stack([np.sin(h), np.cos(h)])
    nrm = np.column_stack([np.cos(h), -np.sin(h)])
    mids = gp.ring[idx][:, [_LEFT_MID, _RIGHT_MID], :]                     # (m, 2, 2)
    hag = np.maximum(gp.hag_m[idx], 0.0)
    across, along = payload.footprint_m(1.0)
    # candidate neighbours: photos within one (widest) footprint width of each other, found with a tree
    i, j = shapely.STRtree(shapely.points(c)).query(shapely.points(c), predicate="dwithin",
                                                     distance=float(across * hag.max()) if len(hag) else 0.0)
    rel = c[j] - c[i]
    lat = np.einsum("pk,pk->p", rel, nrm[i])
    keep = ((span[i] != span[j]) & (np.abs(np.sin(h[j] - h[i])) < _PARALLEL_SIN)
            & (np.abs(np.einsum("pk,pk->p", rel, d[i])) <= along / 2 * hag[i]) & (np.abs(lat) > 1e-6))
    i, j, lat = i[keep], j[keep], lat[keep]
    if not len(i):
        return None
    # across-track extents through the centres, on photo i's own across axis
    base = np.einsum("pk,pk->p", c[i], nrm[i])
    ext_i = np.einsum("pqk,pk->pq", mids[i], nrm[i]) - base[:, None]
    ext_j = np.einsum("pqk,pk->pq", mids[j], nrm[i]) - base[:, None]
    lo_i, hi_i = ext_i.min(axis=1), ext_i.max(axis=1)
    lo_j, hi_j = ext_j.min(axis=1), ext_j.max(axis=1)
    ov = (np.minimum(hi_i, hi_j) - np.maximum(lo_i, lo_j)) / np.maximum(hi_i - lo_i, 1e-9)
    best = math.inf
    for side in (1.0, -1.0):
        m = side * lat > 0
        if not m.any():
            continue
        # each photo's nearest neighbour on this side: sort by (photo, distance), take the first of each photo
        ii, dist, vals = i[m], np.abs(lat[m]), ov[m]
        order = np.lexsort((dist, ii))
        first = order[np.r_[True, ii[order][1:] != ii[order][:-1]]]
        v = vals[first]
        v = v[v > 0]                                  # no overlap at all is a gap: coverage shows it
        if len(v):
            best = min(best, float(v.min()))
    return None if math.isinf(best) else best


def step_ground(area_info: Any, tolerance_m: float, gp: GroundPhotos, idx: np.ndarray) -> StepGround:
    hag = gp.hag_m[idx] if len(idx) else np.zeros(0)
    target = float(area_info.altitude_m)
    out = int(np.sum((hag < target - 0.05) | (hag > target + tolerance_m + 0.05)))
    return StepGround(area_info.step, target, tolerance_m, float(hag.min()) if len(hag) else None,
                      float(hag.max()) if len(hag) else None, out)


def ground_report(compiled: Any, sim: Any, steps: Sequence[StepGround]) -> GroundReport:
    t = compiled.terrain
    return GroundReport(t.dem.files, t.frame, t.clearance_m, path_clearance(compiled, sim, t.dem), tuple(steps))


def footprint_rings(compiled: Any, sim: Any, owners: Sequence[tuple[int, str]]) -> np.ndarray:
    """Closed ground footprint rings (m, 9, 2), simulation metres, of (photo index, payload name) pairs: the
    GeoJSON/KML footprints and the preview's, cut by the DEM as the report measures them."""
    out = np.zeros((len(owners), len(_RING) + 1, 2))
    for name in dict.fromkeys(n for _, n in owners):
        rows = [r for r, (_, n) in enumerate(owners) if n == name]
        photos = [sim.photos[owners[r][0]] for r in rows]
        ring = ground_photos(compiled, sim, photos, compiled.payload(name)).ring
        out[rows] = np.concatenate([ring, ring[:, :1]], axis=1)
    return out
