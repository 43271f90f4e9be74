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
                   altitudes=tuple(float(z) for z in prof.amsl_m), over_tolerance_m=prof.over_tolerance_m)
