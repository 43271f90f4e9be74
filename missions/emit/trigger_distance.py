"""The DO_SET_CAM_TRIGG_DIST a firmware is given for a planned photo spacing: shorter than the spacing, so that
the distance its trigger really flies (it checks the distance at a fixed rate and fires at the first check at
or past it) is never longer than planned and the requested front overlap holds.

    commanded_trigger_distance("ardupilot", "copter", 10.043, 5.0, lat_deg=50.16)   # 9.85 m: flies 9.9 (9.92 true)
"""

from __future__ import annotations

import math
from typing import NamedTuple

from missions.emit.firmware import px4_commanded_distance

# AP_Camera_Backend::update runs at 50 Hz in the vehicles' scheduler tables ("should be called at 50hz"): it
# fires when the straight-line distance from the last photo is no longer `< CAMn_TRIGG_DIST`, and measures the
# next one from where it fired.
AP_CAMERA_UPDATE_HZ = 50.0

# ArduPilot measures distances between locations on a sphere: Location::get_distance scales 1e-7° of latitude by
# LOCATION_SCALING_FACTOR (RADIUS_OF_EARTH 6378100 m) and of longitude by that times cos(latitude); its EKF's
# north/east metres, and so the speed it flies, are the same. On the WGS84 ellipsoid a metre of ArduPilot's is
# longer east-west (by N(φ)/R, 1.0020 at 50°) and shorter north-south (by M(φ)/R, 0.9992 at 50°): the distance
# trigger flies its spacing in these metres (measured in SITL at 50.16° N on field-multispectral's lines heading
# 278°: 10.117 m true between photos for 101 checks of 0.1 m).
AP_EARTH_RADIUS_M = 6378100.0
WGS84_A_M = 6378137.0
WGS84_E2 = 0.00669437999014


class ApMetre(NamedTuple):
    """True (WGS84) metres per metre of ArduPilot's location arithmetic, east and north, at one latitude."""

    east: float
    north: float

    def along(self, heading_deg: float) -> float:
        """True metres per ArduPilot metre along `heading_deg` (clockwise from north)."""
        h = math.radians(heading_deg)
        return math.hypot(self.east * math.sin(h), self.north * math.cos(h))


def ardupilot_metre(lat_deg: float) -> ApMetre:
    """ArduPilot's metre in true metres at `lat_deg` (see AP_EARTH_RADIUS_M)."""
    s2 = math.sin(math.radians(lat_deg)) ** 2
    w = 1.0 - WGS84_E2 * s2
    prime_vertical = WGS84_A_M / math.sqrt(w)
    meridian = WGS84_A_M * (1.0 - WGS84_E2) / w ** 1.5
    return ApMetre(prime_vertical / AP_EARTH_RADIUS_M, meridian / AP_EARTH_RADIUS_M)


def ardupilot_check_step_m(speed_mps: float) -> float:
    """Travel between two of ArduPilot's distance checks at `speed_mps`."""
    return speed_mps / AP_CAMERA_UPDATE_HZ


def ardupilot_commanded_distance(spacing_m: float, speed_mps: float, lat_deg: float) -> float:
    """The trigger distance that makes ArduPilot fly at most `spacing_m` (true metres, in any direction at
    `lat_deg`) less half a check's travel between photos at `speed_mps`: n whole checks of travel in its metres,
    commanded half a check short of them. Exactly n checks would be a tie at the n-th (positions are 1e-7°
    integers, the speed never exactly the plan's), lost about half the time to n + 1; the half check of slack
    keeps n for speeds within ±1/(2n) of the plan's, and the half check shorter than the spacing keeps a line's
    last photo, planned on its end, at least that much before it, where the trigger is switched off."""
    step = ardupilot_check_step_m(speed_mps)
    if step <= 0:
        return spacing_m
    longest = max(ardupilot_metre(lat_deg))
    steps = math.floor((spacing_m / longest - step / 2) / step + 1e-9)
    if steps < 2:
        return spacing_m
    return (steps - 0.5) * step


def commanded_trigger_distance(firmware: str, frame: str, spacing_m: float, speed_mps: float,
                               lat_deg: float) -> float:
    """DO_SET_CAM_TRIGG_DIST's distance for `spacing_m` between photos at `speed_mps` near `lat_deg` on
    `firmware`/`frame`. ArduPilot's fixed-wing frames get the spacing itself (their photos against arduplane
    SITL are measured apart from the copter's)."""
    if firmware == "px4":
        return px4_commanded_distance(spacing_m, speed_mps)
    if firmware == "ardupilot" and frame == "copter":
        return ardupilot_commanded_distance(spacing_m, speed_mps, lat_deg)
    return spacing_m
