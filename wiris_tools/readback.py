"""Read-back comparison: is the mission the vehicle holds the one that was sent, as its firmware keeps it?

ArduPilot and PX4 do not give back every field as sent: they drop the params a command does not use,
keep altitudes in centimetres or as float32, and report frames as their `_INT` twins. readback_rule
says, per firmware and command, how each of the eight values is kept (tables below, each citing the
source it comes from); compare_items compares sent and downloaded items under that rule and raises
LinkError at the first real difference. transfer.MissionClient.upload_verified and the vehicle
simulator (vehicle_sim, which gives items back the way a firmware would) both use it.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MissionItem
from wiris_tools.errors import LinkError


_COMPARED = ("command", "frame", "param1", "param2", "param3", "param4", "x", "y", "z", "autocontinue",
             "mission_type")


def _f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


def _same_field(a, b) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        fa, fb = _f32(float(a)), _f32(float(b))
        return fa == fb or (math.isnan(fa) and math.isnan(fb))
    return a == b


# -- read-back as each firmware gives it ---------------------------------------------------------------
#
# Neither autopilot echoes an item: each converts it into its own storage and converts that back on
# download, so a field-by-field comparison fails every normal upload. A rule says, for one command, how the
# firmware keeps p1, p2, p3, p4, x, y, z (one letter each) and the frame (the eighth letter); the read-back is
# compared at that resolution, and a field the firmware does not keep is not compared. The command, the
# mission type, the coordinates and every kept field are always compared, so a vehicle holding another
# mission still fails verification. A command missing from a table is compared field by field (a false
# alarm at worst, never a false success).
#   -  not kept (comes back 0): not compared
#   f  a float32 as sent (NaN equal to NaN)
#   i  a whole number: C's float-to-integer cast truncates toward zero (NaN, which ArduPilot refuses in
#      these slots, as 0)
#   c  a byte: min(255, whole number) (ArduPlane packs two into one uint16)
#   b  a flag: only whether the value is > 0
#   s  a direction: only the sign (-1 when negative, +1 otherwise, NaN included)
#   y  a heading in degrees kept in radians wrapped to [0, 2 pi) (PX4): equal modulo 360 to 0.001 degree
#   e  an int32 as sent (latitude/longitude in degE7: exact)
#   g  an int32 kept in a float32 (PX4 keeps a MISSION-frame item's x/y among its float params)
#   h  an altitude in whole centimetres (ArduPilot's Location.alt, int32 cm): equal within 1 cm
#   t  ArduPilot's loiter turns (low byte of p1): below one turn in 1/256ths, else whole turns to 255
#   r  ArduPilot's loiter radius (high byte of p1): whole metres to 255, beyond in tens of metres to
#      2550, the sign kept
#   k  ArduPilot's Float16_t (half precision; its set() rounds half away from zero)
# frame:  L  a position: only the altitude reference is compared (absolute, above home, above terrain)
#         E  as sent, a frame equal to its _INT twin
#         -  not kept

_C = mavlink2
# The altitude reference of each position frame.
ALT_REFERENCE = {
    _C.MAV_FRAME_GLOBAL: "amsl", _C.MAV_FRAME_GLOBAL_INT: "amsl",
    # ArduPilot reads a position in MAV_FRAME_MISSION as absolute (AP_Mission.cpp, mavlink_int_to_mission_cmd:
    # case MAV_FRAME_MISSION -> relative_alt = 0); PX4 keeps a MISSION-frame item as params, never as a position.
    _C.MAV_FRAME_MISSION: "amsl",
    _C.MAV_FRAME_GLOBAL_RELATIVE_ALT: "home", _C.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: "home",
    _C.MAV_FRAME_GLOBAL_TERRAIN_ALT: "terrain", _C.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: "terrain",
}
_INT_TWIN = {_C.MAV_FRAME_GLOBAL_INT: _C.MAV_FRAME_GLOBAL,
             _C.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: _C.MAV_FRAME_GLOBAL_RELATIVE_ALT,
             _C.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: _C.MAV_FRAME_GLOBAL_TERRAIN_ALT}

# ArduCopter, Rover and Sub: libraries/AP_Mission/AP_Mission.cpp, mission_cmd_to_mavlink_int (what
# mavlink_int_to_mission_cmd kept, with the Mission_Command field types of AP_Mission.h); x/y/z only for
# stored_in_location() commands, every other command comes back in frame 0. Sources: the two functions read
# entry by entry at upstream ArduPilot/ardupilot a877ec7c (4.4-era, AP_Mission.h types from 019546d9), and
# every entry of this table and of the fence and rally tables below uploaded to and downloaded from the
# ArduPilot SITL this project tests with, master 90700977 (4.7.0-dev, ../shared/sitl; in-range values, each
# field distinct): each kept field came back as its letter says and each "-" field as 0, except
# DO_MOUNT_CONTROL's z (the mount mode, not compared). Not checked at the release tags Copter-4.4.x, 4.5.x
# or 4.6.x: their sources could not be read here. What came after a877ec7c (IMAGE_START_CAPTURE's instance,
# IMAGE_STOP_CAPTURE, SET_CAMERA_SOURCE, DO_SET_ROI_LOCATION/NONE, fractional loiter turns) is therefore known
# only for 4.7.0-dev; a877ec7c keeps no IMAGE_START_CAPTURE instance ("image_start_capture.interval_s =
# packet.param2" first), so a 4.4 vehicle gives p1 back as 0. A negative value in an unsigned slot (a camera
# id, an image count) comes back wrapped on the x86 SITL (-7 as 249 in a uint8) and 0 on ARM boards: it is
# not what the rule predicts, a false alarm of --verify for an input no plan has.
_ARDUPILOT_MISSION = {
    _C.MAV_CMD_NAV_WAYPOINT: "i---eehL",            # p1 delay s (uint16); acceptance/pass-by/yaw dropped
    _C.MAV_CMD_NAV_LOITER_UNLIM: "--i-eehL",        # radius as uint16, its sign the direction
    # "param1_stored *= 256.0" when 0 < turns < 1 (type_specific_bits 1<<1; read back "/= 256.0"), else
    # "cmd.p1 = MIN(255, param1_stored)"; radius "radius_m = abs_radius" up to 255, else "MIN(255, abs_radius
    # * 0.1)" with type_specific_bits 1<<0 (read back "*= 10"), negated when loiter_ccw; xtrack flag
    _C.MAV_CMD_NAV_LOITER_TURNS: "t-rbeehL",
    _C.MAV_CMD_NAV_LOITER_TIME: "i-sbeehL",         # seconds (uint16), direction only, xtrack flag
    _C.MAV_CMD_NAV_RETURN_TO_LAUNCH: "--------",
    _C.MAV_CMD_NAV_LAND: "i--seehL",                # abort altitude (uint16), p4 direction only (is_negative)
    _C.MAV_CMD_NAV_TAKEOFF: "i---eehL",             # minimum pitch (uint16); yaw dropped
    _C.MAV_CMD_NAV_CONTINUE_AND_CHANGE_ALT: "i---eehL",
    _C.MAV_CMD_NAV_LOITER_TO_ALT: "-i-beehL",
    _C.MAV_CMD_NAV_SPLINE_WAYPOINT: "i---eehL",
    _C.MAV_CMD_NAV_GUIDED_ENABLE: "i---eehL",
    _C.MAV_CMD_NAV_DELAY: "fiii----",               # seconds (float), UTC hour/min/sec (int8)
    _C.MAV_CMD_NAV_VTOL_TAKEOFF: "----eehL",
    _C.MAV_CMD_NAV_VTOL_LAND: "i---eehL",
    _C.MAV_CMD_CONDITION_DELAY: "f-------",
    _C.MAV_CMD_CONDITION_DISTANCE: "f-------",
    # Yaw_Command: "float angle_deg; float turn_rate_dps; int8_t direction; uint8_t relative_angle"
    _C.MAV_CMD_CONDITION_YAW: "ffii----",
    _C.MAV_CMD_DO_JUMP: "ii------",
    _C.MAV_CMD_DO_CHANGE_SPEED: "iff-----",         # speed type uint8, speed and throttle float
    _C.MAV_CMD_DO_SET_HOME: "i---eehL",
    _C.MAV_CMD_DO_SET_RELAY: "ii------",
    _C.MAV_CMD_DO_REPEAT_RELAY: "iif-----",
    _C.MAV_CMD_DO_SET_SERVO: "ii------",
    _C.MAV_CMD_DO_REPEAT_SERVO: "iiif----",
    _C.MAV_CMD_DO_LAND_START: "----eehL",
    _C.MAV_CMD_DO_GO_AROUND: "----eehL",
    _C.MAV_CMD_DO_SET_ROI: "i---eehL",
    _C.MAV_CMD_DO_SET_ROI_LOCATION: "i---eehL",     # p1 gimbal device id
    _C.MAV_CMD_DO_SET_ROI_NONE: "i-------",
    _C.MAV_CMD_DO_DIGICAM_CONFIGURE: "iiiieef-",    # mode, shutter, aperture, ISO, exposure, cmd id; cut-off s
    _C.MAV_CMD_DO_DIGICAM_CONTROL: "iiiiee--",      # session, zoom pos/step, focus lock, shoot, cmd id
    _C.MAV_CMD_DO_MOUNT_CONTROL: "fff-----",        # pitch, roll, yaw (z comes back as the mount mode)
    _C.MAV_CMD_DO_SET_CAM_TRIGG_DIST: "f-i-----",   # metres (float), trigger once now (uint8)
    _C.MAV_CMD_DO_FENCE_ENABLE: "i-------",
    _C.MAV_CMD_DO_PARACHUTE: "i-------",
    _C.MAV_CMD_DO_GRIPPER: "ii------",
    _C.MAV_CMD_DO_GUIDED_LIMITS: "ifff----",
    _C.MAV_CMD_DO_AUTOTUNE_ENABLE: "i-------",
    _C.MAV_CMD_DO_VTOL_TRANSITION: "i-------",
    _C.MAV_CMD_DO_SEND_SCRIPT_MESSAGE: "ifff----",  # id (uint16), three floats for the script
    # nav_script_time_Command: "uint8_t command; uint8_t timeout_s; Float16_t arg1; Float16_t arg2; int16_t arg3;
    # int16_t arg4" ("arg1.set(packet.param3)", "arg3 = int16_t(packet.x)"; x/y exact within int16); z not kept
    _C.MAV_CMD_NAV_SCRIPT_TIME: "iikkee--",
    _C.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW: "iiiie-i-",  # int8/int16 angles and rates, flags in x, gimbal in z
    _C.MAV_CMD_IMAGE_START_CAPTURE: "ifii----",     # instance uint8, interval float, count and seq uint16
    _C.MAV_CMD_IMAGE_STOP_CAPTURE: "i-------",
    _C.MAV_CMD_SET_CAMERA_ZOOM: "if------",         # zoom type uint8, value float
    _C.MAV_CMD_SET_CAMERA_FOCUS: "if------",
    _C.MAV_CMD_SET_CAMERA_SOURCE: "iii-----",
    _C.MAV_CMD_VIDEO_START_CAPTURE: "i-------",     # stream id
    _C.MAV_CMD_VIDEO_STOP_CAPTURE: "i-------",
}
# ArduPlane (same function, the APM_BUILD_ArduPlane branch, read at a877ec7c; not run on the plane SITL): a
# waypoint keeps acceptance radius and pass-by distance, each clamped to a byte, instead of the delay.
_ARDUPLANE_MISSION = {**_ARDUPILOT_MISSION, _C.MAV_CMD_NAV_WAYPOINT: "-cc-eehL"}
# libraries/GCS_MAVLink/MissionItemProtocol_Fence.cpp (get_item_as_mission_item, 92e0e660): vertex count
# (uint8) or radius (float; AC_PolyFence_loader "read_float") in p1, x/y; z is sent as 0, the frame not kept.
_ARDUPILOT_FENCE = {
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION: "i---ee--",
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION: "i---ee--",
    _C.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION: "f---ee--",
    _C.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION: "f---ee--",
    _C.MAV_CMD_NAV_FENCE_RETURN_POINT: "----ee--",
}
# libraries/GCS_MAVLink/MissionItemProtocol_Rally.cpp (4e393e20): RallyLocation keeps lat, lng and alt as int16
# metres ("ret.alt = cmd.z"); only MAV_FRAME_GLOBAL_RELATIVE_ALT(_INT) is accepted, it comes back as
# GLOBAL_RELATIVE_ALT.
_ARDUPILOT_RALLY = {_C.MAV_CMD_NAV_RALLY_POINT: "----eeiL"}

# PX4: src/modules/mavlink/mavlink_mission.cpp. parse_mavlink_mission_item keeps an item by its frame, not its
# command: a MAV_FRAME_MISSION item as its seven float params (DO_JUMP's first two as integers), a position
# item per command; format_mavlink_mission_item sends a position back in GLOBAL_INT / GLOBAL_RELATIVE_ALT_INT.
_PX4_MISSION_FRAME = "ffffggfE"
_PX4_MISSION_FRAME_BY_COMMAND = {_C.MAV_CMD_DO_JUMP: "iiffggfE"}
_PX4_POSITION = {
    _C.MAV_CMD_NAV_WAYPOINT: "ff-yeefL",            # hold time, acceptance radius, yaw; p3 dropped
    _C.MAV_CMD_NAV_LOITER_UNLIM: "--fyeefL",
    _C.MAV_CMD_NAV_LOITER_TIME: "fbfbeefL",         # force heading and xtrack as flags
    _C.MAV_CMD_NAV_LAND: "-f-yeefL",                # precision land mode, yaw; abort altitude dropped
    _C.MAV_CMD_NAV_TAKEOFF: "---yeefL",             # yaw only
    _C.MAV_CMD_NAV_LOITER_TO_ALT: "bf-beefL",
    _C.MAV_CMD_NAV_VTOL_TAKEOFF: "---yeefL",
    _C.MAV_CMD_NAV_VTOL_LAND: "---yeefL",
    _C.MAV_CMD_NAV_RALLY_POINT: "----eefL",
    # Fence points live in mission_fence_point_s, which has no altitude reference: they come back in
    # GLOBAL_INT whatever was sent (send_mission_item, MAV_MISSION_TYPE_FENCE).
    _C.MAV_CMD_NAV_FENCE_RETURN_POINT: "----eef-",
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION: "f---eef-",
    _C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION: "f---eef-",
    _C.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION: "f---eef-",
    _C.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION: "f---eef-",
}
# The fallback for a command no table knows: every field as sent.
_AS_SENT = "ffffeefE"

_PLANE_TYPES = frozenset({_C.MAV_TYPE_FIXED_WING, _C.MAV_TYPE_VTOL_DUOROTOR, _C.MAV_TYPE_VTOL_QUADROTOR,
                          _C.MAV_TYPE_VTOL_TILTROTOR, _C.MAV_TYPE_VTOL_RESERVED2, _C.MAV_TYPE_VTOL_RESERVED3,
                          _C.MAV_TYPE_VTOL_RESERVED4, _C.MAV_TYPE_VTOL_RESERVED5})


def readback_firmware(heartbeat) -> str | None:
    """Which read-back rules apply to the autopilot of `heartbeat`: "ardupilot" (Copter, Rover, Sub),
    "arduplane" (ArduPlane reports a fixed-wing or VTOL type), "px4", or None (compare every field)."""
    if heartbeat is None:
        return None
    if heartbeat.autopilot == _C.MAV_AUTOPILOT_ARDUPILOTMEGA:
        return "arduplane" if heartbeat.type in _PLANE_TYPES else "ardupilot"
    if heartbeat.autopilot == _C.MAV_AUTOPILOT_PX4:
        return "px4"
    return None


def readback_rule(firmware: str, item: MissionItem) -> str:
    """The eight-letter rule (see above) by which `firmware` gives `item` back on download."""
    kind = item.mission_type
    if firmware == "px4":
        if kind == _C.MAV_MISSION_TYPE_MISSION and item.frame == _C.MAV_FRAME_MISSION:
            return _PX4_MISSION_FRAME_BY_COMMAND.get(item.command, _PX4_MISSION_FRAME)
        return _PX4_POSITION.get(item.command, _AS_SENT)
    table = {_C.MAV_MISSION_TYPE_FENCE: _ARDUPILOT_FENCE, _C.MAV_MISSION_TYPE_RALLY: _ARDUPILOT_RALLY}.get(
        kind, _ARDUPLANE_MISSION if firmware == "arduplane" else _ARDUPILOT_MISSION)
    return table.get(item.command, _AS_SENT)


def _whole(v: float) -> int:
    return 0 if not math.isfinite(v) else math.trunc(v)


def ap_loiter_turns(v: float) -> float:
    """LOITER_TURNS param1 as ArduPilot gives it back (AP_Mission.cpp: mavlink_int_to_mission_cmd stores
    "param1_stored *= 256.0" for 0 < turns < 1, else "cmd.p1 = MIN(255, param1_stored)" in the low byte of
    the uint16 p1; mission_cmd_to_mavlink_int sends "LOWBYTE(cmd.p1)", "/= 256.0" for the fraction). A
    negative count (meaningless) is taken as 0, what the saturating float-to-unsigned cast of ARM gives."""
    v = _f32(v)
    if not math.isfinite(v):
        return 0.0
    if 0.0 < v < 1.0:
        return math.trunc(v * 256.0) / 256.0
    return float(max(0, min(255, math.trunc(v))))


def ap_loiter_radius(v: float) -> float:
    """LOITER_TURNS param3 as ArduPilot gives it back (mavlink_int_to_mission_cmd: "radius_m = abs_radius"
    when abs_radius <= 255, else "MIN(255, abs_radius * 0.1)" and type_specific_bits 1<<0, into the high
    byte of p1, "loiter_ccw = (packet.param3 < 0)"; mission_cmd_to_mavlink_int: "HIGHBYTE(cmd.p1)", negated
    when loiter_ccw, "*= 10" with the bit)."""
    v = _f32(v)
    if not math.isfinite(v):
        return 0.0
    a = abs(v)
    n = math.trunc(a) if a <= 255 else min(255, math.trunc(a * 0.1)) * 10
    return -float(n) if v < 0 else float(n)


def ap_float16(v: float) -> float:
    """`v` through ArduPilot's Float16_t (AP_Common/float16.cpp: set() masks the float32 with 0xFFFFF000,
    scales by 2^-112, "in.u -= round_mask" - adding half a step, so ties round away from zero - and shifts
    by 13, saturating to infinity; get() is the exact widening)."""
    u = struct.unpack("<I", struct.pack("<f", _f32(v)))[0]
    sign = u & 0x80000000
    u ^= sign
    if u >= 0x7F800000:
        h = 0x7FFF if u > 0x7F800000 else 0x7C00
    else:
        scaled = struct.unpack("<f", struct.pack("<I", u & 0xFFFFF000))[0] * 2.0 ** -112
        u = (struct.unpack("<I", struct.pack("<f", scaled))[0] + 0x1000) & 0xFFFFFFFF
        h = min(u, 31 << 23) >> 13
    return struct.unpack("<e", struct.pack("<H", h | (sign >> 16)))[0]


def _kept_equal(kind: str, a, b) -> bool:
    """Whether sent value `a` and read-back `b` are the same value as the firmware keeps it (`kind`)."""
    if kind == "-":
        return True
    if kind == "e":
        return a == b
    if kind == "g":
        return _f32(float(a)) == _f32(float(b))
    if kind == "i":
        return _whole(a) == _whole(b)
    if kind == "c":
        return min(255, _whole(a)) == min(255, _whole(b))
    if kind == "b":
        return (a > 0) == (b > 0)
    if kind == "s":
        return (a < 0) == (b < 0)
    if kind == "t":
        return ap_loiter_turns(a) == ap_loiter_turns(b)
    if kind == "r":
        return ap_loiter_radius(a) == ap_loiter_radius(b)
    if kind == "k":
        return _same_field(ap_float16(a), ap_float16(b))
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if kind == "y":
        return abs((a - b + 180.0) % 360.0 - 180.0) < 1e-3
    if kind == "h":
        # whole centimetres, converted in float32 each way: within 1 cm (and float32's relative error)
        return abs(a - b) <= 0.01 + abs(a) * 2.0 ** -22
    return _same_field(float(a), float(b))   # "f"


def _frame_equal(kind: str, a: int, b: int) -> bool:
    if kind == "-":
        return True
    if kind == "L" and a in ALT_REFERENCE and b in ALT_REFERENCE:
        return ALT_REFERENCE[a] == ALT_REFERENCE[b]
    return _INT_TWIN.get(a, a) == _INT_TWIN.get(b, b)


def _difference(a: MissionItem, b: MissionItem, firmware: str | None) -> str | None:
    """The name of the first field where read-back `b` differs from sent `a`; None when they agree."""
    if firmware is None:
        return next((n for n in _COMPARED if not _same_field(getattr(a, n), getattr(b, n))), None)
    for name in ("command", "mission_type"):
        if getattr(a, name) != getattr(b, name):
            return name
    rule = readback_rule(firmware, a)
    if not _frame_equal(rule[7], a.frame, b.frame):
        return "frame"
    for kind, name in zip(rule, ("param1", "param2", "param3", "param4", "x", "y", "z")):
        if not _kept_equal(kind, getattr(a, name), getattr(b, name)):
            return name
    # ArduPilot sends autocontinue = 1 for every item (MissionItemProtocol_Waypoints::get_item); PX4 keeps it.
    if firmware == "px4" and bool(a.autocontinue) != bool(b.autocontinue):
        return "autocontinue"
    return None


def compare_items(sent: Sequence[MissionItem], got: Sequence[MissionItem], *, where: str = "read-back",
                  home_replaced: bool = False, firmware: str | None = None) -> None:
    """Raise LinkError naming the first item and field where `got` differs from `sent`.

    firmware None: every field as it travels (floats as float32, NaN equal to NaN - what
    MissionItem.same_on_wire compares). firmware "ardupilot", "arduplane" or "px4": as that firmware keeps
    the item (readback_rule), so its normal conversions are not differences but any change of command,
    coordinates or a kept value still is."""
    if len(sent) != len(got):
        raise LinkError(f"the vehicle holds {len(got)} items, {len(sent)} were sent", where=where,
                        hint="upload again; if it repeats, the vehicle is dropping items")
    for i, (a, b) in enumerate(zip(sent, got)):
        if a.same_on_wire(b):
            continue
        if home_replaced and i == 0:
            name = "command" if a.command != b.command else None  # ArduPilot keeps its home position in item 0
        else:
            name = _difference(a, b, firmware)
        if name is not None:
            va, vb = getattr(a, name), getattr(b, name)
            raise LinkError(f"item {i} differs in {name}: sent {va!r}, vehicle holds {vb!r}",
                            where=f"{where}, item {i}",
                            hint="the vehicle changed or lost the item; do not fly this mission - upload again")
