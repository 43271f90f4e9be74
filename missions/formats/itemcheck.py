"""Whether a mission item's values are ones that a file, the wire and a vehicle all agree on.

    problem = item_problem(item, unset=frozenset({"x"}))   # None, or Problem(field, message, hint)

One table (POSITIONS) says which commands carry a position in x/y/z (latitude, longitude, altitude in a
global frame), from common.xml's param descriptions; item_problem applies it and the limits of the file
forms. The .plan and WPL readers call it with the place in the file (and which of x/y the file left null or
NaN), the writers before writing - so what a download writes, an upload reads, and a vehicle's nonsense
(latitude 214.7°, frame 255) is refused with the item and field named instead of written silently.

Commands missing from the table are not judged by position: they may be newer or vendor commands, and x/y of
an unknown command need not be a place. Their frame and autocontinue are still checked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink   # missions.emit.items imports it already

from missions.errors import PlanError

_C = mavlink


@dataclass(frozen=True)
class Takes:
    """What x/y/z hold for one command."""

    latlon: bool           # x/y are a latitude and a longitude (when the frame is a global one)
    altitude: bool         # z is an altitude (in any frame that carries a position)
    zero_means: str = ""   # lat/lon 0, 0 means this rather than a place, so an unset one (null/NaN) reads as 0


PLACE = Takes(latlon=True, altitude=True)
GROUND_POINT = Takes(latlon=True, altitude=False)    # fence vertices and circles: z is "Reserved"
ALTITUDE_ONLY = Takes(latlon=False, altitude=True)   # lat/lon "Empty"
# ArduCopter takes off straight up from where it is: ModeAuto::takeoff_start sets the horizontal target to
# current_loc whatever the item says, so ground stations leave a takeoff's lat/lon at 0.
_TAKEOFF = Takes(latlon=True, altitude=True, zero_means="take off where the vehicle is")

POSITIONS: dict[int, Takes] = {
    _C.MAV_CMD_NAV_WAYPOINT: PLACE,
    _C.MAV_CMD_NAV_LOITER_UNLIM: PLACE,
    _C.MAV_CMD_NAV_LOITER_TURNS: PLACE,
    _C.MAV_CMD_NAV_LOITER_TIME: PLACE,
    _C.MAV_CMD_NAV_LOITER_TO_ALT: PLACE,
    _C.MAV_CMD_NAV_SPLINE_WAYPOINT: PLACE,
    _C.MAV_CMD_NAV_PAYLOAD_PLACE: PLACE,
    _C.MAV_CMD_NAV_LAND: PLACE,
    _C.MAV_CMD_NAV_VTOL_LAND: PLACE,
    _C.MAV_CMD_NAV_TAKEOFF: _TAKEOFF,
    _C.MAV_CMD_NAV_VTOL_TAKEOFF: _TAKEOFF,
    _C.MAV_CMD_NAV_CONTINUE_AND_CHANGE_ALT: ALTITUDE_ONLY,
    # common.xml: "Latitude for landing sequence selection, or 0"
    _C.MAV_CMD_DO_LAND_START: Takes(True, True, zero_means="no position to choose the landing sequence by"),
    _C.MAV_CMD_DO_SET_ROI_LOCATION: PLACE,
    # ArduPilot (mode_auto.cpp do_roi) cancels the region of interest when its location is 0
    _C.MAV_CMD_DO_SET_ROI: Takes(True, True, zero_means="no region of interest"),
    _C.MAV_CMD_NAV_ROI: Takes(True, True, zero_means="no region of interest"),
    _C.MAV_CMD_DO_SET_HOME: PLACE,   # unless param1 = 1: "use current location" (takes_of)
    _C.MAV_CMD_NAV_FENCE_RETURN_POINT: PLACE,
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION: GROUND_POINT,
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION: GROUND_POINT,
    _C.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION: GROUND_POINT,
    _C.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION: GROUND_POINT,
    _C.MAV_CMD_NAV_RALLY_POINT: PLACE,
}

# A fence circle is nothing without its radius (param1): NaN or 0 would be written to a .plan as a radius
# its reader, like QGC's, refuses.
_RADIUS_COMMANDS = frozenset({_C.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, _C.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION})

# x/y are degE7 in these frames; z is a distance in these and in the local ones (MAV_FRAME_MISSION: params).
GLOBAL_FRAMES = frozenset({_C.MAV_FRAME_GLOBAL, _C.MAV_FRAME_GLOBAL_INT, _C.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                           _C.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, _C.MAV_FRAME_GLOBAL_TERRAIN_ALT,
                           _C.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})
FRAMES = frozenset(v for v, e in _C.enums["MAV_FRAME"].items() if not e.name.endswith("_ENUM_END"))

# An altitude beyond ±100 km is no altitude a MAVLink vehicle flies or dives to (the Kármán line; balloons
# reach about 50 km, the deepest sea is 11 km) but a corrupted or unset value - such as float32's largest,
# 3.4e38, which a vehicle answers with for "no value". Far inside what ArduPilot's int32 centimetres hold.
MAX_ALTITUDE_M = 100_000.0


class Problem(NamedTuple):
    field: str      # the MissionItem field: "x", "z", "frame", "autocontinue", "command"
    message: str    # what is wrong, naming the field as people know it ("latitude 214.7483647 is outside ...")
    hint: str


def takes_of(item) -> Takes | None:
    """What x/y/z of `item` are, by its command (None: not a position, or a command the table lacks)."""
    if item.command == _C.MAV_CMD_DO_SET_HOME and item.param1 == 1:
        return None   # "use current location": the position params are ignored
    return POSITIONS.get(item.command)


def command_label(command: int) -> str:
    entry = _C.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None and not entry.name.endswith("_ENUM_END") else f"command {command}"


def _format_problem(item) -> Problem | None:
    if not 0 <= item.command <= 65535:
        return Problem("command", f"command {item.command} is not a MAV_CMD number (0..65535)",
                       "write the MAV_CMD number, e.g. 16 (NAV_WAYPOINT)")
    if item.frame not in FRAMES:
        return Problem("frame", f"frame {item.frame} is not a MAV_FRAME",
                       "use a MAV_FRAME number, e.g. 3 (GLOBAL_RELATIVE_ALT) or 2 (MISSION, for a command "
                       "without a position)")
    if item.autocontinue not in (0, 1):
        return Problem("autocontinue", f"autocontinue {item.autocontinue} is neither 0 nor 1",
                       "autocontinue is a flag: 1 (go on to the next item) or 0")
    if item.command in _RADIUS_COMMANDS and not (math.isfinite(item.param1) and item.param1 > 0):
        return Problem("param1", f"radius {item.param1:g} is not a positive number of metres",
                       "give the fence circle its radius in metres (param1)")
    return None


def _position_problem(item, takes: Takes, unset: frozenset[str]) -> Problem | None:
    name = command_label(item.command)
    if takes.latlon and item.frame in GLOBAL_FRAMES:
        for field, what, limit, value in (("x", "latitude", 90, item.x), ("y", "longitude", 180, item.y)):
            if field in unset and not takes.zero_means:
                return Problem(field, f"{what} is not set (null or NaN)",
                               f"a {name} needs a position: give its latitude and longitude in degrees")
            if not -limit * 10**7 <= value <= limit * 10**7:
                return Problem(field, f"{what} {value / 1e7:.7f} is outside -{limit}..{limit}",
                               f"a {name} needs a real position: latitude -90..90, longitude -180..180 degrees")
    if takes.altitude and item.frame != _C.MAV_FRAME_MISSION:
        z = item.z
        if not (math.isfinite(z) and abs(z) <= MAX_ALTITUDE_M):
            return Problem("z", f"altitude {z:g} is not a real altitude (finite, within ±{MAX_ALTITUDE_M:.0f} m)",
                           f"give the {name} its altitude in metres")
    return None


def item_problem(item, *, unset: frozenset[str] = frozenset()) -> Problem | None:
    """The first value of `item` that no file form or vehicle should take, or None. `unset` names the fields
    among "x"/"y" that the file left null or NaN (read as 0): refused where the command needs a position."""
    return _format_problem(item) or (
        _position_problem(item, takes, unset) if (takes := takes_of(item)) is not None else None)


def home_problem(home) -> Problem | None:
    """The home position (lat, lon, alt) as a file keeps it: a real position; its altitude NaN (unknown:
    ArduPilot before a fix) or real."""
    lat, lon, alt = home
    for field, what, limit, value in (("x", "latitude", 90, lat), ("y", "longitude", 180, lon)):
        if not (math.isfinite(value) and -limit <= value <= limit):
            return Problem(field, f"home {what} {value:g} is outside -{limit}..{limit}",
                           "the home position needs a real latitude (-90..90) and longitude (-180..180)")
    if not (math.isnan(alt) or abs(alt) <= MAX_ALTITUDE_M):
        return Problem("z", f"home altitude {alt:g} is not a real altitude (within ±{MAX_ALTITUDE_M:.0f} m)",
                       "give the home altitude in metres above mean sea level")
    return None


def check_items(form: str, home, mission=(), fence=(), rally=()) -> None:
    """PlanError naming the first item (numbered as check_finite numbers them: mission items from 1, as the
    .plan's doJumpId and the WPL row index do, fence and rally items from 0, their seq) and field that `form`
    ("a .plan", "a waypoint") file should not hold; the home position too."""
    if home is not None:
        problem = home_problem(home)
        if problem is not None:
            raise PlanError(f"{problem.message}, which {form} file should not hold", hint=problem.hint)
    for kind, items, first in (("mission", mission, 1), ("fence", fence, 0), ("rally", rally, 0)):
        for i, it in enumerate(items, first):
            problem = item_problem(it)
            if problem is not None:
                raise PlanError(f"{kind} item {i} ({command_label(it.command)}): {problem.message}, which {form} "
                                "file should not hold", hint=problem.hint)
