"""How ArduPilot's distance trigger measures: at what rate it checks, and in which metres.

    ardupilot_metre(50.16).along(278.0)     # 1.0019 true metres per metre of ArduPilot's
"""

from __future__ import annotations

import math
from typing import NamedTuple

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
