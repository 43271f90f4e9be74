"""Firmware profiles against an independent list written from the reference, check_items, and item-limit parts."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from missions.errors import PlanError
from missions.emit.firmware import ARDUPILOT, PX4, check_items
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem

# Written from shared/reference/autopilots-and-cameras.md §2.2 / §3.1 / §7 and survey-planners §7, by name.
REFERENCE = {
    "ardupilot": {
        "accepts": ["DO_DIGICAM_CONFIGURE", "DO_DIGICAM_CONTROL", "DO_SET_CAM_TRIGG_DIST", "IMAGE_START_CAPTURE",
                    "VIDEO_START_CAPTURE", "VIDEO_STOP_CAPTURE", "SET_CAMERA_ZOOM", "SET_CAMERA_FOCUS",
                    "DO_SEND_SCRIPT_MESSAGE", "NAV_SCRIPT_TIME", "DO_MOUNT_CONTROL", "DO_GIMBAL_MANAGER_PITCHYAW"],
        "rejects": ["SET_CAMERA_MODE", "DO_TRIGGER_CONTROL", "DO_SET_CAM_TRIGG_INTERVAL", "STORAGE_FORMAT",
                    "RESET_CAMERA_SETTINGS", "VIDEO_START_STREAMING", "VIDEO_STOP_STREAMING",
                    "USER_1", "USER_2", "USER_3", "USER_4", "USER_5"],
    },
    "px4": {
        "accepts": ["DO_TRIGGER_CONTROL", "DO_DIGICAM_CONTROL", "DO_MOUNT_CONFIGURE", "DO_MOUNT_CONTROL",
                    "DO_GIMBAL_MANAGER_PITCHYAW", "DO_GIMBAL_MANAGER_CONFIGURE", "SET_CAMERA_FOCUS",
                    "IMAGE_START_CAPTURE", "IMAGE_STOP_CAPTURE", "VIDEO_START_CAPTURE", "VIDEO_STOP_CAPTURE",
                    "DO_CONTROL_VIDEO", "DO_SET_CAM_TRIGG_DIST", "OBLIQUE_SURVEY", "DO_SET_CAM_TRIGG_INTERVAL",
                    "SET_CAMERA_MODE", "DO_VTOL_TRANSITION", "NAV_DELAY", "CONDITION_DELAY", "CONDITION_DISTANCE",
                    "DO_CHANGE_SPEED", "DO_SET_HOME", "DO_LAND_START"],
        "rejects": ["DO_DIGICAM_CONFIGURE", "STORAGE_FORMAT", "RESET_CAMERA_SETTINGS", "VIDEO_START_STREAMING",
                    "VIDEO_STOP_STREAMING", "USER_1", "USER_2", "USER_3", "USER_4", "USER_5"],
    },
}
PROFILES = {"ardupilot": ARDUPILOT, "px4": PX4}


def cmd(name: str) -> int:
    return getattr(m, "MAV_CMD_" + name)


@pytest.mark.parametrize("fw", ["ardupilot", "px4"])
def test_profiles_agree_with_reference(fw):
    prof = PROFILES[fw]
    for name in REFERENCE[fw]["accepts"]:
        assert prof.accepts(cmd(name)), f"{fw} should accept {name}"
    for name in REFERENCE[fw]["rejects"]:
        assert not prof.accepts(cmd(name)), f"{fw} should reject {name}"


def test_item_limits_and_camera_addressing():
    assert ARDUPILOT.default_item_limit == 700 and PX4.default_item_limit == 500
    assert ARDUPILOT.camera_target == "instance" and PX4.camera_target == "component"
    assert not ARDUPILOT.interval_trigger and PX4.interval_trigger


@pytest.mark.parametrize("fw,name,words", [
    ("ardupilot", "USER_1", "MAV_MISSION_UNSUPPORTED"), ("px4", "USER_1", "MAV_MISSION_UNSUPPORTED"),
    ("ardupilot", "SET_CAMERA_MODE", "SET_CAMERA_MODE"), ("ardupilot", "DO_SET_CAM_TRIGG_INTERVAL", "214"),
    ("px4", "DO_DIGICAM_CONFIGURE", "202")])
def test_check_items_names_the_rule(fw, name, words):
    items = [MissionItem(command=cmd("NAV_WAYPOINT"), x=1, y=1, z=10),
             MissionItem(command=cmd(name), frame=FRAME_MISSION)]
    with pytest.raises(PlanError) as ei:
        check_items(items, PROFILES[fw])
    assert "mission item 2" in ei.value.where and name in ei.value.where
    assert words in ei.value.hint


def _wp(i: int) -> MissionItem:
    return MissionItem(command=cmd("NAV_WAYPOINT"), frame=FRAME_GLOBAL_RELATIVE_ALT, param4=math.nan,
                       x=500000000 + i * 100, y=140000000, z=40.0)


def test_ardupilot_nan_params_refused_where_its_upload_refuses_them():
    """AP_Mission::sanity_check_params: NaN only in param4 of WAYPOINT/LAND/TAKEOFF/VTOL_TAKEOFF and params 3-4
    of VTOL_LAND; any other NaN is MAV_MISSION_INVALID_PARAMn and the upload aborts. PX4 takes NaN."""
    check_items((_wp(0),), ARDUPILOT)
    check_items((MissionItem(command=cmd("NAV_VTOL_LAND"), param3=math.nan, param4=math.nan, x=1, y=1),), ARDUPILOT)
    for item, k in ((MissionItem(command=cmd("NAV_LOITER_UNLIM"), param4=math.nan, x=1, y=1), 4),
                    (MissionItem(command=cmd("NAV_WAYPOINT"), param2=math.nan, x=1, y=1), 2),
                    (MissionItem(command=cmd("DO_SET_CAM_TRIGG_DIST"), frame=FRAME_MISSION, param3=math.nan), 3)):
        with pytest.raises(PlanError) as ei:
            check_items((item,), ARDUPILOT)
        assert f"param{k} is NaN" in ei.value.message and ei.value.hint
        check_items((item,), PX4)


@pytest.mark.parametrize("x,y", [(2**31, 0), (0, -2**31 - 1), (1.5, 0)])
def test_check_items_refuses_params_5_6_that_are_not_int32(x, y):
    items = [MissionItem(command=cmd("DO_DIGICAM_CONTROL"), frame=FRAME_MISSION, x=x, y=y)]
    with pytest.raises(PlanError, match="int32") as ei:
        check_items(items, PX4)
    assert "mission item 1" in ei.value.where
    assert "report" in ei.value.hint
