"""Firmware profiles as data: which MAV_CMDs each autopilot accepts in an uploaded mission, its item limit,
and how it passes camera commands on. The compiler never emits an item its firmware would reject:
`check_items` is the last gate before the outputs.

Sources (shared/reference/):
- ArduPilot: autopilots-and-cameras.md §2.2 (AP_Mission `mavlink_int_to_mission_cmd`; anything missing from
  it is MAV_MISSION_UNSUPPORTED and aborts the upload, §2.3) and survey-planners §7.2 (version support from
  the wiki's mavlink-camera.rst: IMAGE_START_CAPTURE 4.4+, IMAGE_STOP_CAPTURE 4.5+, SET_CAMERA_SOURCE 4.6+).
- PX4: autopilots-and-cameras.md §3.1 (mavlink_mission.cpp `parse_mavlink_mission_item` whitelist; the
  default branch returns MAV_MISSION_UNSUPPORTED) and survey-planners §7.3.
- Both: §7 acceptance matrix (USER_1..5 rejected by both; SET_CAMERA_MODE PX4 only; DO_DIGICAM_CONFIGURE
  ArduPilot only; DO_SET_CAM_TRIGG_INTERVAL PX4 only).
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from missions.errors import PlanError
from missions.emit.items import MissionItem, mavlink

C = mavlink  # MAV_CMD_* constants of the ArduPilot dialect (a superset of common.xml)


def cmd_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"MAV_CMD {command}"


@dataclass(frozen=True)
class FirmwareProfile:
    name: str                              # "ardupilot" | "px4"
    title: str
    min_version: str
    accepted: frozenset[int]               # MAV_CMDs the upload parser takes
    rejected: tuple[tuple[int, str], ...]  # known-rejected commands -> the rule, for messages
    default_item_limit: int
    item_limit_why: str
    camera_target: str                     # how IMAGE_START_CAPTURE p1 is read: "instance" | "component"
    interval_trigger: bool                 # DO_SET_CAM_TRIGG_INTERVAL accepted
    camera_mode_item: bool                 # SET_CAMERA_MODE accepted (reaches the camera)
    digicam_configure_item: bool           # DO_DIGICAM_CONFIGURE accepted
    script_messages: bool                  # DO_SEND_SCRIPT_MESSAGE + Lua available
    max_camera_instances: int              # AP_Camera instances (CAMn_*); PX4 addresses components instead
    source: str
    # Distance triggering reaches every camera (PX4 camera_trigger: components 100..105) or only the primary
    # one (ArduPilot: AP_Camera::set_trigger_distance() calls `primary` only, AP_Camera.cpp; the first photo
    # of DO_SET_CAM_TRIGG_DIST param3 = 1 goes to every instance through take_picture()).
    distance_trigger_all: bool = True
    # command -> the params (1-4) that may be NaN; None: NaN is accepted everywhere ("use the default", as the
    # MAVLink spec says). ArduPilot refuses NaN elsewhere with MAV_MISSION_INVALID_PARAMn and aborts the upload
    # (AP_Mission / MissionItemProtocol_Waypoints::sanity_check_params: a nan_mask per command, 0xff otherwise).
    nan_params: dict[int, frozenset[int]] | None = None

    def accepts(self, command: int) -> bool:
        return command in self.accepted

    def rule(self, command: int) -> str:
        for c, why in self.rejected:
            if c == command:
                return why
        return (f"{self.title} {self.min_version}+ rejects {cmd_name(command)} at upload with "
                "MAV_MISSION_UNSUPPORTED (not in its mission-item parser)")


_NAV_COMMON = {
    C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_TAKEOFF, C.MAV_CMD_NAV_LAND, C.MAV_CMD_NAV_RETURN_TO_LAUNCH,
    C.MAV_CMD_NAV_LOITER_UNLIM, C.MAV_CMD_NAV_LOITER_TURNS, C.MAV_CMD_NAV_LOITER_TIME,
    C.MAV_CMD_NAV_LOITER_TO_ALT, C.MAV_CMD_NAV_VTOL_TAKEOFF, C.MAV_CMD_NAV_VTOL_LAND, C.MAV_CMD_NAV_DELAY,
    C.MAV_CMD_DO_CHANGE_SPEED, C.MAV_CMD_DO_SET_HOME, C.MAV_CMD_DO_JUMP, C.MAV_CMD_DO_LAND_START,
    C.MAV_CMD_DO_SET_ROI, C.MAV_CMD_DO_SET_ROI_LOCATION, C.MAV_CMD_DO_SET_ROI_NONE, C.MAV_CMD_DO_MOUNT_CONTROL,
    C.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, C.MAV_CMD_DO_VTOL_TRANSITION, C.MAV_CMD_CONDITION_DELAY,
    C.MAV_CMD_DO_DIGICAM_CONTROL, C.MAV_CMD_DO_SET_CAM_TRIGG_DIST, C.MAV_CMD_IMAGE_START_CAPTURE,
    C.MAV_CMD_VIDEO_START_CAPTURE, C.MAV_CMD_VIDEO_STOP_CAPTURE, C.MAV_CMD_SET_CAMERA_FOCUS,
}

_USER_RULE = ("{fw} rejects MAV_CMD_USER_1..5 at upload with MAV_MISSION_UNSUPPORTED and the whole upload "
              "aborts (reference autopilots-and-cameras §0.1, §7)")

ARDUPILOT = FirmwareProfile(
    name="ardupilot", title="ArduPilot", min_version="4.4",
    accepted=frozenset(_NAV_COMMON | {
        C.MAV_CMD_DO_DIGICAM_CONFIGURE, C.MAV_CMD_SET_CAMERA_ZOOM, C.MAV_CMD_DO_SEND_SCRIPT_MESSAGE,
        C.MAV_CMD_NAV_SCRIPT_TIME,
    }),
    rejected=(
        (C.MAV_CMD_SET_CAMERA_MODE, "ArduPilot does not accept SET_CAMERA_MODE (530) in missions (\"not yet "
         "supported\", ArduPilot wiki mavlink-camera.rst; reference §2.2)"),
        (C.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, "ArduPilot does not accept DO_SET_CAM_TRIGG_INTERVAL (214) in missions "
         "(absent from AP_Mission's converter; reference §2.2, §7): use trigger: distance, or PX4"),
        (C.MAV_CMD_DO_TRIGGER_CONTROL, "ArduPilot does not accept DO_TRIGGER_CONTROL (2003) in missions (reference §2.2)"),
        (C.MAV_CMD_IMAGE_STOP_CAPTURE, "IMAGE_STOP_CAPTURE needs ArduPilot 4.5; this profile is 4.4 and later"),
        (C.MAV_CMD_STORAGE_FORMAT, "STORAGE_FORMAT is not a mission item on ArduPilot (reference §2.2)"),
        (C.MAV_CMD_RESET_CAMERA_SETTINGS, "RESET_CAMERA_SETTINGS is not a mission item on ArduPilot (reference §2.2)"),
        (C.MAV_CMD_VIDEO_START_STREAMING, "video streaming commands are not mission items on ArduPilot"),
        (C.MAV_CMD_VIDEO_STOP_STREAMING, "video streaming commands are not mission items on ArduPilot"),
        *((c, _USER_RULE.format(fw="ArduPilot")) for c in (C.MAV_CMD_USER_1, C.MAV_CMD_USER_2, C.MAV_CMD_USER_3,
                                                             C.MAV_CMD_USER_4, C.MAV_CMD_USER_5)),
    ),
    # ~718/724 items fit the mission storage of common boards (ArduPilot #7254, MissionPlanner #1644; 15
    # bytes per item). ArduPilot also stores home as item 0, so 700 of ours leaves headroom for boards with
    # a little less storage. Set vehicle.max_mission_items for a board with more (or far less: APM2 107).
    default_item_limit=700,
    item_limit_why="about 718 items fit common boards' mission storage (ArduPilot #7254); 700 keeps headroom",
    camera_target="instance", interval_trigger=False, camera_mode_item=False, digicam_configure_item=True,
    script_messages=True, max_camera_instances=2,
    source="reference autopilots-and-cameras §2.2/§7; survey-planners §7.2; ArduPilot AP_Camera.cpp",
    distance_trigger_all=False,
    nan_params={C.MAV_CMD_NAV_WAYPOINT: frozenset({4}), C.MAV_CMD_NAV_LAND: frozenset({4}),
                C.MAV_CMD_NAV_TAKEOFF: frozenset({4}), C.MAV_CMD_NAV_VTOL_TAKEOFF: frozenset({4}),
                C.MAV_CMD_NAV_VTOL_LAND: frozenset({3, 4})},
)

PX4 = FirmwareProfile(
    name="px4", title="PX4", min_version="1.14",
    accepted=frozenset(_NAV_COMMON | {
        C.MAV_CMD_DO_TRIGGER_CONTROL, C.MAV_CMD_IMAGE_STOP_CAPTURE, C.MAV_CMD_DO_CONTROL_VIDEO,
        C.MAV_CMD_OBLIQUE_SURVEY, C.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, C.MAV_CMD_SET_CAMERA_MODE,
        C.MAV_CMD_DO_MOUNT_CONFIGURE, C.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE, C.MAV_CMD_CONDITION_DISTANCE,
        C.MAV_CMD_DO_SET_ROI_WPNEXT_OFFSET,
    }),
    rejected=(
        (C.MAV_CMD_DO_DIGICAM_CONFIGURE, "PX4 rejects DO_DIGICAM_CONFIGURE (202) at upload (not in "
         "mavlink_mission.cpp's list; reference §3.1)"),
        (C.MAV_CMD_DO_SEND_SCRIPT_MESSAGE, "DO_SEND_SCRIPT_MESSAGE is ArduPilot's (Lua scripting); PX4 has no "
         "mission scripting"),
        (C.MAV_CMD_STORAGE_FORMAT, "PX4 rejects STORAGE_FORMAT at upload (reference §3.1)"),
        (C.MAV_CMD_RESET_CAMERA_SETTINGS, "PX4 rejects RESET_CAMERA_SETTINGS at upload (reference §3.1)"),
        (C.MAV_CMD_VIDEO_START_STREAMING, "PX4 rejects video streaming commands at upload (reference §3.1)"),
        (C.MAV_CMD_VIDEO_STOP_STREAMING, "PX4 rejects video streaming commands at upload (reference §3.1)"),
        (C.MAV_CMD_SET_CAMERA_ZOOM, "SET_CAMERA_ZOOM is accepted only by some PX4 versions (reference §3.1); "
         "not emitted"),
        *((c, _USER_RULE.format(fw="PX4")) for c in (C.MAV_CMD_USER_1, C.MAV_CMD_USER_2, C.MAV_CMD_USER_3,
                                                       C.MAV_CMD_USER_4, C.MAV_CMD_USER_5)),
    ),
    # PX4's dataman holds 500 mission items since PR #18827 (2021; NUM_MISSIONS_SUPPORTED 2000 -> 500).
    default_item_limit=500,
    item_limit_why="PX4's dataman stores 500 mission items (PX4 PR #18827)",
    camera_target="component", interval_trigger=True, camera_mode_item=True, digicam_configure_item=False,
    script_messages=False, max_camera_instances=6,
    source="reference autopilots-and-cameras §3.1/§3.2/§7; survey-planners §7.3",
)

PROFILES = {"ardupilot": ARDUPILOT, "px4": PX4}

# PX4 camera_trigger checks the distance every 50 ms (CameraTrigger::Run, poll_interval_usec = 50000) and
# measures the next shot from where it fired, so each shot comes up to one check's travel late.
PX4_TRIGGER_CHECK_S = 0.05
# A multicopter reaches a mission waypoint, and runs the DO items after it, within NAV_ACC_RAD (PX4 default)
PX4_ACCEPTANCE_M = 2.0


def px4_commanded_distance(spacing_m: float, speed_mps: float) -> float:
    """The DO_SET_CAM_TRIGG_DIST that makes PX4 fly at most `spacing_m` between shots at `speed_mps`: one
    check's travel shorter, so the last shot of a line (planned on its end) still comes before the trigger
    is switched off there."""
    return max(spacing_m - speed_mps * PX4_TRIGGER_CHECK_S, 0.5 * spacing_m)


def profile(name: str) -> FirmwareProfile:
    try:
        return PROFILES[name]
    except KeyError:
        raise PlanError(f"unknown firmware {name!r}", hint="ardupilot or px4") from None


def check_items(items: tuple[MissionItem, ...] | list[MissionItem], prof: FirmwareProfile,
                where: str | None = None) -> None:
    """PlanError naming the firmware rule if any item would be rejected at upload (or cannot be stored)."""
    for i, it in enumerate(items):
        here = f"{where + ', ' if where else ''}mission item {i + 1} ({cmd_name(it.command)})"
        if not prof.accepts(it.command):
            raise PlanError(f"{prof.title} would reject this item at upload", where=here, hint=prof.rule(it.command))
        if prof.nan_params is not None:
            for k, v in enumerate((it.param1, it.param2, it.param3, it.param4), 1):
                if math.isnan(v) and k not in prof.nan_params.get(it.command, ()):
                    raise PlanError(f"param{k} is NaN, which {prof.title} refuses for this command at upload "
                                    f"(MAV_MISSION_INVALID_PARAM{k})", where=here,
                                    hint="a bug in wiris-tools (the compiler emitted an item it must not): please "
                                         "report it with the plan")
        # MISSION_ITEM_INT carries params 5/6 as int32: no NaN, no fractions (reference §4.2)
        if not (isinstance(it.x, int) and isinstance(it.y, int)) or not (-2**31 <= it.x < 2**31 and -2**31 <= it.y < 2**31):
            raise PlanError("params 5/6 (x/y) must be int32 in MISSION_ITEM_INT", where=here,
                            hint="a bug in wiris-tools (the compiler emitted an item it must not): please report it "
                                 "with the plan")


# ------------------------------------------------------------------------------------------- item limits
