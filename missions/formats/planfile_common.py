"""What the .plan writer (missions.formats.planfile) and reader (missions.formats.planfile_read) share: the
size limits, the fence and rally commands a .plan keeps in its own sections, the firmware, vehicle and altitude
mode codes QGC writes, how MISSION_ITEM_INT carries x/y per frame, and the hints of their errors.
"""

from __future__ import annotations

from missions.formats.itemcheck import GLOBAL_FRAMES
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, mavlink


Home = tuple[float, float, float]


# A 2000-item survey plan is about 1 MB; a vehicle can hold 65535 mission items (ArduPilot with its mission on
# the SD card), and their .plan as write_plan writes it is up to about 45 MB with every float at its longest.
# write_plan refuses anything larger, so every file this tool writes it can read again (a download too).
MAX_PLAN_BYTES = 64 * 1024 * 1024
MAX_ITEMS = 65535                     # MISSION_COUNT is 16 bits


# The fence and rally commands a .plan keeps in its geoFence and rallyPoints sections.
CMD_FENCE_RETURN_POINT = mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT
CMD_FENCE_POLYGON_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
CMD_FENCE_POLYGON_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
CMD_FENCE_CIRCLE_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
CMD_FENCE_CIRCLE_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
CMD_RALLY_POINT = mavlink.MAV_CMD_NAV_RALLY_POINT


# MAV_AUTOPILOT: what QGC writes as firmwareType (generic when the caller names none).
FIRMWARE_TYPES = {"generic": mavlink.MAV_AUTOPILOT_GENERIC, "ardupilot": mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                  "px4": mavlink.MAV_AUTOPILOT_PX4}
# MAV_TYPE: what QGC writes as vehicleType (generic when the caller names none).
VEHICLE_TYPES = {"generic": mavlink.MAV_TYPE_GENERIC, "fixedwing": mavlink.MAV_TYPE_FIXED_WING,
                 "plane": mavlink.MAV_TYPE_FIXED_WING, "copter": mavlink.MAV_TYPE_QUADROTOR,
                 "multirotor": mavlink.MAV_TYPE_QUADROTOR, "quadrotor": mavlink.MAV_TYPE_QUADROTOR,
                 "helicopter": mavlink.MAV_TYPE_HELICOPTER, "rover": mavlink.MAV_TYPE_GROUND_ROVER,
                 "boat": mavlink.MAV_TYPE_SURFACE_BOAT, "sub": mavlink.MAV_TYPE_SUBMARINE,
                 "hexarotor": mavlink.MAV_TYPE_HEXAROTOR, "octorotor": mavlink.MAV_TYPE_OCTOROTOR,
                 "vtol": mavlink.MAV_TYPE_VTOL_TILTROTOR}  # QGC treats every VTOL type alike


# QGC's AltMode enum (QGroundControlQmlGlobal.h) for globalPlanAltitudeMode / AltitudeMode.
ALT_MODE_MIXED, ALT_MODE_RELATIVE, ALT_MODE_ABSOLUTE, ALT_MODE_TERRAIN_FRAME = 0, 1, 2, 4
_FRAME_ALT_MODE = {FRAME_GLOBAL_RELATIVE_ALT: ALT_MODE_RELATIVE, FRAME_GLOBAL: ALT_MODE_ABSOLUTE,
                   FRAME_GLOBAL_TERRAIN_ALT: ALT_MODE_TERRAIN_FRAME}


# How MISSION_ITEM_INT carries x/y per MAV_FRAME (common.xml): global frames (itemcheck.GLOBAL_FRAMES) as
# degE7, local frames as metres * 1e4, anything else (MAV_FRAME_MISSION, BODY_FRD) as a plain integer.
# 22 and 23 are no MAV_FRAME (common.xml's end at 21, LOCAL_FLU): a file's item in them has its x/y read as
# a local frame's, then is refused by item_problem.
_LOCAL_FRAMES = frozenset({mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_LOCAL_ENU,
                           mavlink.MAV_FRAME_LOCAL_OFFSET_NED, mavlink.MAV_FRAME_BODY_NED,
                           mavlink.MAV_FRAME_BODY_OFFSET_NED, mavlink.MAV_FRAME_LOCAL_FRD, mavlink.MAV_FRAME_LOCAL_FLU,
                           22, 23})


QGC_DEFAULT_CRUISE_SPEED = 15.0   # QGC's application defaults, written when the caller gives none
QGC_DEFAULT_HOVER_SPEED = 5.0


def _scale(frame: int) -> int:
    if frame in GLOBAL_FRAMES:
        return 10**7
    if frame in _LOCAL_FRAMES:
        return 10**4
    return 1


def xy_hint(frame: int) -> str:
    """What x/y may hold in `frame` (the hint of a value that does not fit MISSION_ITEM_INT)."""
    s = _scale(frame)
    if s == 10**7:
        return "global frames carry lat/lon in degrees: latitude -90..90, longitude -180..180"
    if s == 10**4:
        return "local frames carry metres, at most ±214748 m (x/y travel as metres × 1e4 in 32 bits)"
    return f"frame {frame} carries x/y as 32-bit whole numbers (±2147483647)"


SIZE_HINT = "a 2000-item .plan is about 1 MB, a full 65535-item one up to 45 MB: is this the right file?"
READ_HINT = "check the path and that you may read the file"
FLOAT32_HINT = "params 1-4 and altitude travel as float32 (at most ±3.4e38); null means unset"
FLOAT32_METRES_HINT = "radii and altitudes travel as float32 (at most ±3.4e38): write the value in metres"
