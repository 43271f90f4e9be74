"""Property: whatever survey parameters a plan picks, the compiler returns a mission its firmware accepts (only
commands from the reference's list, every part within the item limit) or a located PlanError — never another
exception, never an item the firmware would reject at upload."""

from __future__ import annotations

from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings, strategies as st
from pymavlink.dialects.v20 import ardupilotmega as m

from missions.compile import compile_plan
from missions.errors import PlanError
from missions.plan import parse_plan

HERE = Path(__file__).resolve().parent

# Written from reference autopilots-and-cameras §2.2/§3.1/§7 (the commands each firmware takes in a mission
# that this compiler has any reason to emit).
ACCEPTED = {
    "ardupilot": {"NAV_TAKEOFF", "NAV_VTOL_TAKEOFF", "NAV_WAYPOINT", "NAV_LOITER_TIME", "NAV_LOITER_UNLIM",
                  "NAV_RETURN_TO_LAUNCH", "NAV_LAND", "NAV_VTOL_LAND", "DO_CHANGE_SPEED", "DO_SET_CAM_TRIGG_DIST",
                  "IMAGE_START_CAPTURE", "DO_SEND_SCRIPT_MESSAGE", "DO_DIGICAM_CONTROL", "DO_DIGICAM_CONFIGURE"},
    "px4": {"NAV_TAKEOFF", "NAV_VTOL_TAKEOFF", "NAV_WAYPOINT", "NAV_LOITER_TIME", "NAV_LOITER_UNLIM",
            "NAV_RETURN_TO_LAUNCH", "NAV_LAND", "NAV_VTOL_LAND", "DO_CHANGE_SPEED", "DO_SET_CAM_TRIGG_DIST",
            "DO_SET_CAM_TRIGG_INTERVAL", "DO_TRIGGER_CONTROL", "IMAGE_START_CAPTURE", "IMAGE_STOP_CAPTURE",
            "SET_CAMERA_MODE", "DO_DIGICAM_CONTROL"},
}

CAMERA_CHANGES = [{"layout": "blended", "blend_opacity": 40}, {"palette": 2}, {"range_mode": "auto"},
                  {"zoom": 3.0}, {"gain_db": 6}, {"main_camera": "visible"}]


@st.composite
def plans(draw):
    frame = draw(st.sampled_from(["copter", "plane", "vtol"]))
    doc = {
        "version": 1, "name": "prop",
        "vehicle": {"firmware": draw(st.sampled_from(["ardupilot", "px4"])), "frame": frame,
                    # within the frame's plausible range (missions.plan.schema.SPEED_RANGE_MPS)
                    "speed_mps": draw(st.floats(1, 12) if frame == "copter" else st.floats(8, 16)),
                    "max_mission_items": draw(st.sampled_from([None, 30, 80, 500]))},
        "home": {"lat": 50.1098, "lon": 14.5002, "alt_amsl_m": 262},
        "payloads": {"thermal": {"camera": draw(st.sampled_from(["wiris-pro", "wiris-security"])),
                                 "component_id": 101}},
        "mission": [{"takeoff": {"alt_m": draw(st.floats(5, 100))}}],
    }
    if doc["vehicle"]["max_mission_items"] is None:
        del doc["vehicle"]["max_mission_items"]
    if doc["payloads"]["thermal"]["camera"] == "wiris-pro":
        doc["payloads"]["thermal"]["lens_mm"] = draw(st.sampled_from([9, 13, 19, 25, 35]))
    w = draw(st.floats(0.001, 0.006))
    h = draw(st.floats(0.001, 0.004))
    lat0, lon0 = 50.11, 14.50
    doc["mission"].append({"survey": {
        "area": [[lat0, lon0], [lat0, lon0 + w], [lat0 + h, lon0 + w], [lat0 + h, lon0]],
        "payloads": ["thermal"], "altitude_m": draw(st.floats(10, 150)),
        "overlap": {"front": draw(st.floats(0, 90)), "side": draw(st.floats(0, 85))},
        "angle_deg": draw(st.one_of(st.just("auto"), st.floats(-180, 180))),
        "trigger": draw(st.sampled_from(["distance", "distance", "distance", "interval", "hover"]))}})
    for _ in range(draw(st.integers(0, 2))):
        doc["mission"].append({"camera": {"payload": "thermal", "settings": draw(st.sampled_from(CAMERA_CHANGES))}})
    doc["mission"].append(draw(st.sampled_from([{"rtl": {}}, {"land": {}}])))
    return doc


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(plans())
def test_compiled_missions_are_accepted_or_refused_with_a_location(doc):
    text = yaml.safe_dump(doc, sort_keys=False)
    try:
        c = compile_plan(parse_plan(text, "prop.yaml", HERE))
    except PlanError as e:
        probs = getattr(e, "problems", None)
        wheres = [p.where for p in probs] if probs else [e.where]
        assert all(w and w.startswith("prop.yaml") for w in wheres), str(e)
        return
    fw = doc["vehicle"]["firmware"]
    names = {m.enums["MAV_CMD"][it.command].name.removeprefix("MAV_CMD_") for it in c.items}
    assert names <= ACCEPTED[fw]
    assert all(len(p) <= c.item_limit for p in c.parts)
    for p in c.parts:
        assert {m.enums["MAV_CMD"][it.command].name.removeprefix("MAV_CMD_") for it in p} <= ACCEPTED[fw]
    assert (c.lua is not None) == any(it.command == m.MAV_CMD_DO_SEND_SCRIPT_MESSAGE for it in c.items)
