"""Geofence polygons as the mission's fence items (pure).

    items = exclusion_polygon(ring)                              # a zone the vehicle must not enter
    items = inclusion_polygon(mission_items, home, margin_m=30)  # a polygon around the whole flight

Fence items are what the fence list carries on the wire (MISSION_TYPE_FENCE): one
NAV_FENCE_POLYGON_VERTEX_EXCLUSION / _INCLUSION per vertex, param1 = the polygon's vertex count, frame GLOBAL,
in order around the polygon, not closed (common.xml; QGC's geoFence and MAVSDK's importer read them so).
"""

from __future__ import annotations

import math
from typing import Sequence

from missions.emit.items import FRAME_GLOBAL, FRAME_MISSION, MISSION_TYPE_FENCE, MissionItem, deg_to_e7, mavlink
from missions.geometry.geo import LocalProjection

# Each place the flight goes is wrapped in a regular octagon whose inscribed circle has the margin as radius;
# the fence is the convex hull of all their corners: at least the margin from every place and from the straight
# legs between them (the hull of convex shapes holds their segments), with few vertices for the autopilot's small
# fence storage (at most 8 more than the hull of the places).
_SIDES = 8


def _polygon(ring: Sequence[tuple[float, float]], command: int) -> list[MissionItem]:
    n = float(len(ring))
    return [MissionItem(command=command, frame=FRAME_GLOBAL, param1=n, x=deg_to_e7(lat), y=deg_to_e7(lon),
                        mission_type=MISSION_TYPE_FENCE) for lat, lon in ring]


def exclusion_polygon(ring: Sequence[tuple[float, float]]) -> list[MissionItem]:
    """The fence items of one exclusion zone: its outline (lat, lon), not closed."""
    return _polygon(ring, mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION)


def _positions(items: Sequence[MissionItem]) -> list[tuple[int, float, float]]:
    """(item number from 1, lat, lon) of every item that is a place to fly to."""
    return [(k, it.lat, it.lon) for k, it in enumerate(items, 1) if it.frame != FRAME_MISSION and (it.x or it.y)]


def inclusion_polygon(items: Sequence[MissionItem], home: tuple[float, float], margin_m: float) -> list[MissionItem]:
    """An inclusion polygon at least `margin_m` around home and every position of `items` (see _SIDES)."""
    from shapely.geometry import MultiPoint

    proj = LocalProjection(home[0], home[1])
    places = [(0.0, 0.0)] + [proj.point_to_xy(lat, lon) for _, lat, lon in _positions(items)]
    r = margin_m / math.cos(math.pi / _SIDES)
    corners = [(x + r * math.cos(a), y + r * math.sin(a)) for x, y in places
               for a in (math.pi / _SIDES + 2 * math.pi * k / _SIDES for k in range(_SIDES))]
    hull = MultiPoint(corners).convex_hull
    xy = list(hull.exterior.coords)[:-1]
    if hull.exterior.is_ccw:            # clockwise, as QGC draws a fence
        xy.reverse()
    ring = [proj.point_to_latlon(x, y) for x, y in xy]
    return _polygon(ring, mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION)


__all__ = ["exclusion_polygon", "inclusion_polygon"]
