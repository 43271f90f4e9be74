"""Clearance: how high above the DEM the re-flown path stays, every metre of it (transits, turnarounds and the
return included), sampled at the DEM's resolution.

    c = path_clearance(compiled, sim, dem)       # Clearance(min_m, lat, lon, item, ...)

Heights of the path: a vertex's altitude above home plus home's elevation, or for an item in the terrain frame
the ground below it plus its height (the autopilot holds that height over its own terrain data, assumed to be
this DEM); between two vertices the vehicle flies straight (in height above ground where the leg's target is a
terrain-frame item). Vertical segments (take-off, landing, the RTL descent) are left out: they start or end on
the ground by design.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from missions.emit.items import FRAME_GLOBAL_TERRAIN_ALT, mavlink

# Segments shorter than this horizontally are vertical moves over one point (take-off, landing).
VERTICAL_SEGMENT_M = 1.0
# Samples of the whole path at most: beyond it the step grows (a 100 km path at 1 m pixels).
MAX_SAMPLES = 2_000_000
_TERRAIN_FRAMES = (FRAME_GLOBAL_TERRAIN_ALT, mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT)


@dataclass(frozen=True)
class Clearance:
    """The lowest point of the path above the ground."""

    min_m: float
    lat: float
    lon: float
    item: int                 # index into compiled.items of the NAV item flown towards there (-1: none)
    amsl_m: float             # the vehicle's altitude there
    ground_m: float           # the ground's

    def to_json(self) -> dict[str, Any]:
        return {"min_m": round(self.min_m, 2), "at": [round(self.lat, 7), round(self.lon, 7)],
                "item": self.item, "altitude_amsl_m": round(self.amsl_m, 2), "ground_amsl_m": round(self.ground_m, 2)}


def is_terrain_item(compiled: Any, item: int) -> bool:
    return 0 <= item < len(compiled.items) and compiled.items[item].frame in _TERRAIN_FRAMES


def vertex_heights(compiled: Any, sim: Any, dem: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per path vertex: altitude above mean sea level, ground height, whether it is held above terrain."""
    home_amsl = compiled.home[2]
    lat = np.array([p[0] for p in sim.latlon])
    lon = np.array([p[1] for p in sim.latlon])
    ground = dem.ground_amsl(lat, lon)
    terrain = np.array([is_terrain_item(compiled, v.item) for v in sim.vertices], dtype=bool)
    alt = np.array([v.alt_m for v in sim.vertices], dtype=float)
    amsl = np.where(terrain, ground + alt, home_amsl + alt)
    return amsl, ground, terrain


def path_clearance(compiled: Any, sim: Any, dem: Any) -> Clearance | None:
    """The lowest clearance over the non-vertical segments of `sim`'s path; None when it has none. Positions
    without a DEM height raise the DEM's PlanError (`Dem.ground_at`)."""
    xy = sim.xy
    if len(xy) < 2:
        return None
    amsl, ground_v, terrain = vertex_heights(compiled, sim, dem)
    seg = np.hypot(*np.diff(xy, axis=0).T)
    flown = np.flatnonzero(seg >= VERTICAL_SEGMENT_M)
    if not len(flown):
        return None
    step = max(dem.resolution_m, float(seg[flown].sum()) / MAX_SAMPLES, 0.5)
    counts = np.maximum(1, np.ceil(seg[flown] / step).astype(int))
    k = np.repeat(flown, counts + 1)
    t = np.concatenate([np.linspace(0.0, 1.0, n + 1) for n in counts])
    pts = xy[k] + (xy[k + 1] - xy[k]) * t[:, None]
    lat, lon = sim.projection.to_latlon(pts[:, 0], pts[:, 1])
    g = dem.ground_at(lat, lon, "the flown path", None)
    end_terrain = terrain[k + 1]
    agl_a, agl_b = amsl[k] - ground_v[k], amsl[k + 1] - ground_v[k + 1]
    z = np.where(end_terrain, g + agl_a + (agl_b - agl_a) * t, amsl[k] + (amsl[k + 1] - amsl[k]) * t)
    c = z - g
    w = int(np.argmin(c))
    item = sim.vertices[int(k[w]) + 1].item
    return Clearance(float(c[w]), float(lat[w]), float(lon[w]), int(item), float(z[w]), float(g[w]))
