"""A survey's or corridor's track (missions.emit.emitter.Track) made to follow the ground: the compiler's one call.

    track = terrain_track(track, terrain, speed_mps, where)

frame amsl: the track's points keep their order and kinds, points of kind "terrain" are added where the ground
asks (missions.terrain.follow), every point gets its altitude above mean sea level, and the camera spans are
re-indexed onto the new points. frame terrain: the points stay as they are at the target height in
MAV_FRAME_GLOBAL_TERRAIN_ALT; the autopilot follows its own terrain data between them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from missions.emit.emitter import Track, TrackPoint
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_TERRAIN_ALT
from missions.errors import PlanError
from missions.geometry.geo import LocalProjection
from missions.terrain.follow import FollowSettings, follow_path
from missions.terrain.model import Terrain

KIND_TERRAIN = "terrain"      # a waypoint added to follow the ground
# Samples along the path: half the DEM's pixel (bilinear heights change slope only at pixel lines), at least
# every 10 m and no finer than 0.5 m.
MAX_STEP_M, MIN_STEP_M = 10.0, 0.5


def check_altitude(terrain: Terrain, altitude_m: float, where: str | None) -> None:
    if altitude_m < terrain.clearance_m:
        raise PlanError(f"the lines fly {altitude_m:g} m above the ground, below terrain.clearance_m "
                        f"{terrain.clearance_m:g} m", where=where,
                        hint="fly higher, or lower terrain.clearance_m if obstacles allow")


def terrain_track(track: Track, terrain: Terrain, speed_mps: float, where: str | None) -> Track:
    check_altitude(terrain, track.altitude_m, where)
    if terrain.frame == "terrain":
        return replace(track, frame=FRAME_GLOBAL_TERRAIN_ALT)
    pts = track.points
    proj = LocalProjection.centred_on([p.lat for p in pts], [p.lon for p in pts])
    x, y = proj.to_xy([p.lat for p in pts], [p.lon for p in pts])

    def ground(xy: np.ndarray) -> np.ndarray:
        lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
        return terrain.dem.ground_at(lat, lon, "the lines", where)

    settings = FollowSettings(track.altitude_m, terrain.tolerance_for(track.altitude_m),
                              terrain.climb_mps / speed_mps, terrain.descent_mps / speed_mps)
    step = min(MAX_STEP_M, max(MIN_STEP_M, terrain.dem.resolution_m / 2.0))
    prof = follow_path(np.column_stack([x, y]), ground, settings, step)
    lat, lon = proj.to_latlon(prof.xy[:, 0], prof.xy[:, 1])
    new_points: list[TrackPoint] = []
    index_of: dict[int, int] = {}
    for k, v in enumerate(prof.vertex.tolist()):
        if v >= 0:
            index_of[v] = k
            new_points.append(pts[v])
        else:
            new_points.append(TrackPoint(float(lat[k]), float(lon[k]), KIND_TERRAIN))
    spans = tuple((index_of[a], index_of[b]) for a, b in track.spans)
    return replace(track, points=tuple(new_points), spans=spans, frame=FRAME_GLOBAL,
                   altitudes=tuple(float(z) for z in prof.amsl_m), over_tolerance_m=prof.over_tolerance_m,
                   highest_agl_m=prof.highest_agl_m)


def _photo_runs(track: Track) -> tuple[tuple[int, int], ...]:
    """Hover lines: each run of consecutive photo stops, as (first, last) point indices."""
    runs, start = [], None
    for i, p in enumerate((*track.points, None)):
        if p is not None and p.kind == "photo":
            start = i if start is None else start
        elif start is not None:
            if i - 1 > start:
                runs.append((start, i - 1))
            start = None
    return tuple(runs)


def front_overlap_scale(track: Track, terrain: Terrain, along_m: float, altitude_m: float) -> float:
    """The factor (<= 1) for the trigger distance that holds the front overlap on the steepest camera-on stretch.

    A footprint on ground sloping by s along the track, seen from h above its nadir, reaches b·h/(1 + s·b) uphill
    and b·h/(1 - s·b) downhill (b = along_m / (2 h): the half-angle's tangent), so it is a trapezoid wider
    downhill; the next photo's footprint is the same trapezoid moved on by the trigger distance d, and the strip
    the pair does not share is the wide end: the overlap of their areas is 1 - (d / L)(1 + s·b)(1 - s²b²) instead
    of 1 - d / L (L the flat footprint's length; at 30 % and b = 0.33, 1.4 points less). Scaling d by 1 / (1 + s·b)
    holds it. The slope is the ground's mean over one footprint length, the steepest along any camera-on span."""
    spans = track.spans or _photo_runs(track)
    if not spans:
        return 1.0
    pts = track.points
    proj = LocalProjection.centred_on([p.lat for p in pts], [p.lon for p in pts])
    x, y = proj.to_xy([p.lat for p in pts], [p.lon for p in pts])
    step = min(MAX_STEP_M, max(MIN_STEP_M, terrain.dem.resolution_m / 2.0))
    steepest = 0.0
    for a, b in spans:
        xy = np.column_stack([x[a:b + 1], y[a:b + 1]])
        seg = np.hypot(*np.diff(xy, axis=0).T)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        if s[-1] <= along_m:
            continue
        at = np.arange(0.0, s[-1] + 1e-9, step)
        px, py = np.interp(at, s, xy[:, 0]), np.interp(at, s, xy[:, 1])
        lat, lon = proj.to_latlon(px, py)
        g = terrain.dem.ground_amsl(lat, lon)
        k = max(1, int(round(along_m / step)))
        if len(g) > k:
            steepest = max(steepest, float(np.nanmax(np.abs(g[k:] - g[:-k]) / (at[k:] - at[:-k]), initial=0.0)))
    tan_half = along_m / (2.0 * altitude_m)
    return 1.0 / (1.0 + steepest * tan_half)


def side_overlap_scale(side_pct: float, altitude_m: float, highest_agl_m: float | None) -> float:
    """The factor (<= 1) for the line spacing that holds the side overlap when the lines fly anywhere between the
    target and `highest_agl_m` above the ground: a photo taken (1 + τ) times higher than its neighbour on the next
    line shares with it [1 + τ/2 - spacing / W] / (1 + τ) of its width (W the target's footprint width), which
    is the requested f when spacing = W (1 - f - τ (f - 1/2)). Above 50 % only; 1 when the band is unused."""
    f = side_pct / 100.0
    if highest_agl_m is None or f <= 0.5:
        return 1.0
    tau = max(0.0, highest_agl_m / altitude_m - 1.0)
    return max(0.05, 1.0 - tau * (f - 0.5) / (1.0 - f))
