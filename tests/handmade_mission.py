"""A survey mission written out item by item, with no planner involved: the report, output and preview tests
measure it (tests/missions/test_report.py, test_outputs.py, test_preview.py)."""

from __future__ import annotations

import math

from missions.geometry.area import LatLonPolygon, build_area
from missions.compiled import AreaInfo, Compiled, PayloadInfo
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem, deg_to_e7, mavlink

HOME = (50.1102, 14.5031, 262.0)
THERMAL = PayloadInfo("thermal", "wiris-pro", "thermal", 100, 13.0, (10.88, 8.704), (640, 512), True, 1.0)


def _wp(proj, x, y, alt, hold=0.0):
    lat, lon = proj.point_to_latlon(x, y)
    return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, FRAME_GLOBAL_RELATIVE_ALT, hold, 0, 0, math.nan,
                       deg_to_e7(lat), deg_to_e7(lon), alt)


def _trig(d, once=1):
    return MissionItem(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST, FRAME_MISSION, d, 0, once)


def handmade(size_m=200.0, alt=40.0, front=0.8, side=0.7, hover=False, speed=6.0, hole_m=0.0):
    """A square survey flown as a lawn-mower written out item by item (no planner involved)."""
    half = size_m / 2
    # a square centred 150 m north-east of home
    from missions.geometry.geo import LocalProjection
    p0 = LocalProjection(HOME[0], HOME[1])
    corners = [(150 - half, 150 - half), (150 + half, 150 - half), (150 + half, 150 + half), (150 - half, 150 + half)]
    ll = [p0.point_to_latlon(x, y) for x, y in corners]
    holes = ()
    if hole_m:
        h = hole_m / 2
        holes = (tuple(p0.point_to_latlon(150 + dx, 150 + dy) for dx, dy in ((-h, -h), (h, -h), (h, h), (-h, h))),)
    area = build_area([LatLonPolygon(tuple(ll), holes, "square")])
    proj = area.projection
    hx, hy = proj.point_to_xy(HOME[0], HOME[1])
    across, along = THERMAL.footprint_m(alt)
    spacing = across * (1 - side)
    trig = along * (1 - front)
    n_lines = math.ceil((size_m - across) / spacing) + 1
    x0 = -(n_lines - 1) * spacing / 2
    y_lo, y_hi = -half, half
    n_ph = math.ceil((y_hi - y_lo) / trig)
    y_hi2 = y_lo + n_ph * trig
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, FRAME_GLOBAL_RELATIVE_ALT, z=alt)]
    for k in range(n_lines):
        x = x0 + k * spacing
        ys = (y_lo, y_hi2) if k % 2 == 0 else (y_hi2, y_lo)
        if hover:
            pts = [y_lo + j * trig for j in range(n_ph + 1)]
            if k % 2:
                pts = pts[::-1]
            for yy in pts:
                items.append(_wp(proj, x, yy, alt, hold=2))
                items.append(MissionItem(mavlink.MAV_CMD_IMAGE_START_CAPTURE, FRAME_MISSION, 0, 0, 1))
        else:
            sgn = 1 if k % 2 == 0 else -1
            items.append(_wp(proj, x, ys[0] - sgn * 10, alt))
            items.append(_wp(proj, x, ys[0], alt))
            items.append(_trig(trig))
            items.append(_wp(proj, x, ys[1], alt))
            items.append(_trig(0))
            items.append(_wp(proj, x, ys[1] + sgn * 10, alt))
    items.append(MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, FRAME_MISSION))
    ainfo = AreaInfo(1, "survey", ("thermal",), area, alt, front, side, "hover" if hover else "distance", trig)
    return Compiled("handmade", "ardupilot", "copter", HOME, speed, tuple(items), (tuple(items),), 700,
                    (THERMAL,), (ainfo,), ())
