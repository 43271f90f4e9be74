"""Pre-flight sequence: slots merged per command, offsets, NaN keep, `when`, RedEdge PARAM_SETs, JSON format.

Expected wire values are read from the Workswell manual's tables (quoted next to each assertion), not from
the catalogue code under test.
"""

from __future__ import annotations

import json
import math

import pytest

from cdf.catalogue import catalogue
from missions.errors import PlanError
from missions.plan import Payload
from missions.emit.setup import RedEdgeSurvey, commands_for, dumps_setup, setup_steps, wire_params


def wiris(settings: dict, comp: int = 101, camera: str = "wiris-pro") -> Payload:
    cam = catalogue().get(camera)
    return Payload(name="thermal", camera=camera, component_id=comp, settings=tuple(settings.items()),
                   values=tuple((k, cam.setting(k).check(v)) for k, v in settings.items()))


def steps_for(settings: dict, **kw):
    p = wiris(settings, **kw)
    return setup_steps([p], {"thermal": catalogue().get(p.camera)})


def by_command(steps, name):
    return [s for s in steps if s.command == name]


def test_layout_fullscreen_is_param5_three_and_rest_keep():
    # manual §6.3.2.5: "5: Layout ... increased by 1"; §7.2.3: Fullscreen = 2  ->  3
    (s,) = by_command(steps_for({"layout": "fullscreen"}), "MAV_CMD_SET_CAMERA_MODE")
    assert s.params[4] == 3.0
    assert s.params[5] is None and s.params[6] is None        # main camera, opacity: NaN = keep
    assert s.target_component == 101 and s.kind == "command_long"


def test_settings_of_one_command_merge_into_one():
    steps = steps_for({"layout": "blended", "main_camera": "visible", "blend_opacity": 40})
    (s,) = by_command(steps, "MAV_CMD_SET_CAMERA_MODE")
    # §7.2.3 Blended = 3 -> 4; §7.2.2 Visible = 1 -> 2; p7 opacity as is
    assert s.params[4:] == (4.0, 2.0, 40.0)


def test_manual_range_slots_and_keep():
    steps = steps_for({"range_mode": "manual", "range_min_c": -5, "range_max_c": 80, "emissivity": 0.9})
    (s,) = by_command(steps, "MAV_CMD_USER_1")
    # §6.3.2.13 Wiris Pro: 1 mode (manual = 1), 3 max, 4 min, 5 emissivity; 2, 6, 7 untouched
    assert s.params == (1.0, None, 80.0, -5.0, 0.9, None, None)
    assert all(math.isnan(v) for i, v in enumerate(wire_params(s.params)) if i in (1, 5, 6))


def test_span_mode_uses_the_same_slots():
    (s,) = by_command(steps_for({"range_mode": "span", "span_half_c": 20, "span_center_c": 30}), "MAV_CMD_USER_1")
    assert s.params[:4] == (2.0, None, 20.0, 30.0)


def test_when_not_met_drops_the_slot():
    cam = catalogue().get("wiris-pro")
    (c,) = commands_for(cam, [("range_mode", 0), ("range_max_c", 50.0)])
    assert c.params[2] is None and c.keys == ("range_mode",)


def test_capture_flags_and_storage_offset():
    (s,) = by_command(steps_for({"capture": ["radiometric_jpeg", "visible_jpeg"], "storage": "microsd"}),
                      "MAV_CMD_IMAGE_START_CAPTURE")
    # §7.2.7 flags 0x01 | 0x08 = 9; §6.3.2.6 p6 "Storage ID + 1", §7.2.1 microSD = 2 -> 3; p3 = 1 image
    assert s.params[4] == 9.0 and s.params[5] == 3.0 and s.params[2] == 1.0
    assert "test photo" in s.description


def test_order_identify_first_capture_last():
    steps = steps_for({"capture": ["radiometric_jpeg"], "palette": 2, "layout": "inspection"})
    names = [s.command for s in steps]
    assert names[0] == "MAV_CMD_REQUEST_MESSAGE" and names[-1] == "MAV_CMD_IMAGE_START_CAPTURE"
    assert names.index("MAV_CMD_SET_CAMERA_MODE") < names.index("MAV_CMD_USER_2")


def test_video_setting_refused():
    with pytest.raises(PlanError, match="starts recording"):
        steps_for({"video": ["visible_encoded"]})


def test_rededge_overlap_mode_params():
    cam = catalogue().get("rededge-mx")
    p = Payload(name="ms", camera="rededge-mx", component_id=100)
    steps = setup_steps([p], {"ms": cam}, {"ms": RedEdgeSurvey(60, 15, 80, 70)})
    got = {s.param_id: (s.value, s.type) for s in steps}
    # the serial API's "Supported Parameters" types: the camera reads the value's bytes as these
    assert got == {"autoCapMode": (2, "MAV_PARAM_TYPE_UINT32"), "operatingAlt": (60, "MAV_PARAM_TYPE_INT32"),
                   "opAltTolerance": (15, "MAV_PARAM_TYPE_UINT32"), "overlapAlongTrk": (80, "MAV_PARAM_TYPE_UINT32"),
                   "overlapCrossTrk": (70, "MAV_PARAM_TYPE_UINT32")}
    assert all(type(s.value) is int for s in steps)
    assert all(s.kind == "param_set" and s.target_component == 100 and s.expect == "PARAM_VALUE" for s in steps)


def test_rededge_plan_setting_wins():
    cam = catalogue().get("rededge-mx")
    p = Payload(name="ms", camera="rededge-mx", component_id=100, settings=(("auto_capture", "timer"),),
                values=(("auto_capture", 1),))
    steps = setup_steps([p], {"ms": cam}, {"ms": RedEdgeSurvey(60.0, 15.0, 80.0, 70.0)})
    assert [s.value for s in steps if s.param_id == "autoCapMode"] == [1]


def rededge(settings: dict) -> Payload:
    cam = catalogue().get("rededge-mx")
    return Payload(name="ms", camera="rededge-mx", component_id=100, settings=tuple(settings.items()),
                   values=tuple((k, cam.setting(k).check(v)) for k, v in settings.items()))


def test_rededge_exposure_is_one_digicam_configure_for_every_imager():
    p = rededge({"exposure_mode": "manual", "shutter_divisor": 2000, "iso": "iso400"})
    steps = setup_steps([p], {"ms": catalogue().get("rededge-mx")}, {"ms": RedEdgeSurvey(60.0, 15.0, 80.0, 70.0)})
    (s,) = [s for s in steps if s.kind == "message"]
    assert steps[-1] is s                         # after the overlap-mode PARAM_SETs
    # serial API page, DIGICAM_CONFIGURE (154): Mode <li value="4">Manual</li>; Shutter Speed "to specify
    # 1/60sec, send 60"; ISO gain <li value="4">ISO400</li>; Extra Command "Set to 255 for all"; the fields it
    # ignores are left out (sent as 0)
    assert s.message == "DIGICAM_CONFIGURE" and s.target_component == 100 and s.expect == "UNACKNOWLEDGED"
    assert dict(s.fields) == {"mode": 4, "shutter_speed": 2000, "iso": 4, "extra_param": 255}
    doc = json.loads(dumps_setup("demo", steps))["steps"][-1]
    assert doc["kind"] == "message" and doc["fields"] == {"extra_param": 255, "iso": 4, "mode": 4,
                                                          "shutter_speed": 2000}
    assert doc["expect"] == {"result": "UNACKNOWLEDGED"}
    (auto,) = setup_steps([rededge({"exposure_mode": "auto"})], {"ms": catalogue().get("rededge-mx")})
    assert dict(auto.fields) == {"mode": 1, "extra_param": 255}     # "1. Auto gain/exposure"


def test_json_format():
    steps = steps_for({"layout": "fullscreen"})
    doc = json.loads(dumps_setup("demo", steps))
    assert doc["format"] == "wiris-setup" and doc["version"] == 1 and doc["plan"] == "demo"
    mode = [s for s in doc["steps"] if s.get("command") == "MAV_CMD_SET_CAMERA_MODE"][0]
    assert mode["params"][4] == 3 and mode["params"][6] is None and len(mode["params"]) == 7
    assert mode["expect"] == {"result": "MAV_RESULT_ACCEPTED"}
