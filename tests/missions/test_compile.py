"""compile_plan end to end: items per firmware × camera, the rules that refuse, parts, warnings, params."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from missions.emit import lua
from missions.compile import compile_plan
from missions.errors import PlanError
from missions.measure.report import report
from missions.plan import parse_plan
from missions.emit.setup import commands_for
from missions.emit.trigger_distance import ardupilot_commanded_distance

PLANS = Path(__file__).resolve().parent / "plans"

# What the compiler may emit, per firmware, written from reference autopilots-and-cameras §2.2/§3.1/§7.
MAY_EMIT = {
    "ardupilot": {"NAV_TAKEOFF", "NAV_VTOL_TAKEOFF", "NAV_WAYPOINT", "NAV_LOITER_TIME", "NAV_LOITER_UNLIM",
                  "NAV_RETURN_TO_LAUNCH", "NAV_LAND", "NAV_VTOL_LAND", "DO_CHANGE_SPEED", "DO_SET_CAM_TRIGG_DIST",
                  "IMAGE_START_CAPTURE", "DO_SEND_SCRIPT_MESSAGE"},
    "px4": {"NAV_TAKEOFF", "NAV_VTOL_TAKEOFF", "NAV_WAYPOINT", "NAV_LOITER_TIME", "NAV_LOITER_UNLIM",
            "NAV_RETURN_TO_LAUNCH", "NAV_LAND", "NAV_VTOL_LAND", "DO_CHANGE_SPEED", "DO_SET_CAM_TRIGG_DIST",
            "DO_SET_CAM_TRIGG_INTERVAL", "DO_TRIGGER_CONTROL", "IMAGE_START_CAPTURE", "SET_CAMERA_MODE",
            "DO_DIGICAM_CONTROL"},
}

SQUARE = [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]
BASE = {
    "version": 1, "name": "t",
    "vehicle": {"firmware": "ardupilot", "frame": "copter", "speed_mps": 5},
    "home": {"lat": 50.1098, "lon": 14.5002, "alt_amsl_m": 262},
    "payloads": {"thermal": {"camera": "wiris-pro", "lens_mm": 13, "component_id": 101,
                             "settings": {"layout": "fullscreen"}}},
    "mission": [
        {"takeoff": {"alt_m": 30}},
        {"survey": {"area": SQUARE, "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 80, "side": 70}}},
        {"rtl": {}},
    ],
}


# a survey speed within each frame's plausible range (missions.plan.schema.SPEED_RANGE_MPS)
SPEED_MPS = {"copter": 5, "plane": 12, "vtol": 12}


def flown_by(frame: str):
    """The change that makes BASE a plan for `frame`: its speed, and for a fixed wing a front overlap that
    keeps the photos the camera's 1 s apart at that speed."""
    def change(doc):
        doc["vehicle"].update(frame=frame, speed_mps=SPEED_MPS[frame])
        if frame != "copter":
            survey(doc)["overlap"]["front"] = 50
            # 12 m/s during the WIRIS's 10 ms time constant smears 2.3 px of 5.2 cm: allow it here
            survey(doc)["blur_px"] = 3
    return change


def build(tmp_path: Path, changes=None, firmware=None):
    doc = copy.deepcopy(BASE)
    if changes:
        changes(doc)
    text = yaml.safe_dump(doc, sort_keys=False)
    path = tmp_path / "plan.yaml"
    path.write_text(text)
    return compile_plan(parse_plan(text, str(path), tmp_path), firmware=firmware)


def names(items):
    return [m.enums["MAV_CMD"][it.command].name.removeprefix("MAV_CMD_") for it in items]


def survey(doc):
    return next(s["survey"] for s in doc["mission"] if "survey" in s)


@pytest.mark.parametrize("fw", ["ardupilot", "px4"])
def test_good_plan_only_accepted_commands(fw):
    c = compile_plan(PLANS / "good.yaml", firmware=fw) if fw == "ardupilot" else None
    if fw == "px4":
        # the good plan's in-flight range_mode change is a USER_1: refused on PX4 (tested below); drop it here
        plan = parse_plan((PLANS / "good.yaml").read_text().replace(
            "  - camera: {payload: thermal, settings: {range_mode: auto, palette: 3}}\n", ""),
            str(PLANS / "good.yaml"), PLANS)
        c = compile_plan(plan, firmware="px4")
    assert set(names(c.items)) <= MAY_EMIT[fw]
    assert c.firmware == fw and c.parts == (c.items,)


def test_distance_trigger_brackets_each_leg(tmp_path):
    c = build(tmp_path)
    n = names(c.items)
    assert n[:2] == ["NAV_TAKEOFF", "DO_CHANGE_SPEED"] and n[-1] == "NAV_RETURN_TO_LAUNCH"
    trig = [it for it in c.items if it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
    ons, offs = trig[0::2], trig[1::2]
    assert len(ons) == len(offs) >= 2
    assert all(t.param1 > 0 and t.param3 == 1 for t in ons)
    assert all(t.param1 == 0 for t in offs)
    # trigger distance = along-track footprint × (1 − front): 512 px × 17 µm × 40 m / 13 mm × 0.2, commanded
    # half a 50 Hz check short of whole checks of ArduPilot's metres (missions.emit.trigger_distance)
    assert c.areas[0].trigger_distance_m == pytest.approx(8.704 * 40 / 13 * 0.2, rel=1e-6)
    assert ons[0].param1 == pytest.approx(ardupilot_commanded_distance(c.areas[0].trigger_distance_m, c.speed_mps,
                                                                       c.home[0]), rel=1e-9)
    assert c.areas[0].trigger_distance_m - 3 * c.speed_mps / 50 < ons[0].param1 < c.areas[0].trigger_distance_m
    for k, it in enumerate(c.items):
        if it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
            assert c.items[k - 1].command == m.MAV_CMD_NAV_WAYPOINT
    wps = [it for it in c.items if it.command == m.MAV_CMD_NAV_WAYPOINT]
    assert all(it.frame == m.MAV_FRAME_GLOBAL_RELATIVE_ALT and it.z == 40 for it in wps)
    assert c.areas[0].altitude_m == 40


def test_gsd_sets_altitude(tmp_path):
    def ch(doc):
        s = survey(doc)
        del s["altitude_m"]
        s["gsd_cm"] = 5.0
    c = build(tmp_path, ch)
    assert c.areas[0].altitude_m == pytest.approx(0.05 * 13 / 0.017, rel=1e-6)   # GSD (m) · f / pitch


def test_interval_on_ardupilot_names_the_rule(tmp_path):
    with pytest.raises(PlanError) as ei:
        build(tmp_path, lambda d: survey(d).update(trigger="interval"))
    assert "ArduPilot" in ei.value.message and "214" in ei.value.hint
    assert ei.value.where.startswith(str(tmp_path / "plan.yaml") + ":")


def test_interval_on_px4(tmp_path):
    c = build(tmp_path, lambda d: survey(d).update(trigger="interval"), firmware="px4")
    iv = [it for it in c.items if it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL]
    assert iv and iv[0].param1 == pytest.approx(1000 * c.areas[0].trigger_distance_m / 5, abs=1)
    ctl = [it.param1 for it in c.items if it.command == m.MAV_CMD_DO_TRIGGER_CONTROL]
    assert ctl[0::2] == [1.0] * len(iv) and ctl[1::2] == [0.0] * len(iv)
    assert ("TRIG_MODE", 1.0) in [(n, v) for n, v, _ in c.params]


def add_camera_step(settings):
    def ch(doc):
        doc["mission"].insert(2, {"camera": {"payload": "thermal", "settings": settings}})
    return ch


def test_user1_in_flight_on_px4_names_the_rule(tmp_path):
    with pytest.raises(PlanError) as ei:
        build(tmp_path, add_camera_step({"emissivity": 0.9}), firmware="px4")
    assert "emissivity" in ei.value.message and "PX4" in ei.value.message
    assert "USER_1..5" in ei.value.hint and "MAV_MISSION_UNSUPPORTED" in ei.value.hint
    assert ":" in ei.value.where


def test_camera_mode_in_flight_on_px4_is_a_mission_item(tmp_path):
    c = build(tmp_path, add_camera_step({"layout": "fullscreen", "blend_opacity": 30}), firmware="px4")
    (it,) = [it for it in c.items if it.command == m.MAV_CMD_SET_CAMERA_MODE]
    assert it.param1 == 101 and it.param2 == m.CAMERA_MODE_IMAGE
    assert it.x == 3 and it.y == 0 and it.z == 30      # layout+1, main camera 0 = keep (manual §6.3.2.5)
    assert c.lua is None


def test_in_flight_changes_on_ardupilot_go_through_the_bridge(tmp_path):
    settings = {"layout": "blended", "blend_opacity": 30, "range_mode": "manual", "range_min_c": 0,
                "range_max_c": 90, "emissivity": 0.9, "palette": 4, "alarm_mode": "above", "alarm_above": 60,
                "zoom": 2.0}
    c = build(tmp_path, add_camera_step(settings))
    assert c.lua and "mission_receive" in c.lua
    assert ("SCR_ENABLE", 1.0) in [(n, v) for n, v, _ in c.params]
    script = [it for it in c.items if it.command == m.MAV_CMD_DO_SEND_SCRIPT_MESSAGE]
    cam = catalogue().get("wiris-pro")
    values = [(k, cam.setting(k).check(v)) for k, v in settings.items()]
    expected = [(cmd.command, 101, cmd.params) for cmd in commands_for(cam, values, {"layout": 2})]
    assert [(b.command, b.component, b.params) for b in lua.decode(script)] == expected
    # never more than the script queue holds between two NAV items
    run = 0
    for it in c.items:
        if it.frame != m.MAV_FRAME_MISSION:
            run = 0
        elif it.command == m.MAV_CMD_DO_SEND_SCRIPT_MESSAGE:
            run += 1
            assert run <= lua.QUEUE_SIZE


def test_capture_settings_cannot_change_in_flight(tmp_path):
    with pytest.raises(PlanError, match="capture cannot change in flight"):
        build(tmp_path, add_camera_step({"capture": ["radiometric_tiff"]}))


def test_hover_shoots_once_per_stop(tmp_path):
    c = build(tmp_path, lambda d: survey(d).update(trigger="hover"))
    caps = [k for k, it in enumerate(c.items) if it.command == m.MAV_CMD_IMAGE_START_CAPTURE]
    assert caps and not any(it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST for it in c.items)
    for k in caps:
        wp, cap = c.items[k - 1], c.items[k]
        assert wp.command == m.MAV_CMD_NAV_WAYPOINT and wp.param1 >= 4
        assert cap.param1 == 0 and cap.param3 == 1          # all cameras, one image


def waypoint_capture(doc):
    doc["mission"].insert(2, {"waypoint": {"lat": 50.111, "lon": 14.501, "alt_m": 30, "hold_s": 3,
                                           "capture": "thermal"}})


# the plan's WIRIS is at component 101: ArduPilot's MAVLinkCamV2 finds it only as CAM2 (100 + 2 - 1), and the
# mission's IMAGE_START_CAPTURE p1 names that instance; PX4 names the component
@pytest.mark.parametrize("fw,target", [("ardupilot", 2), ("px4", 101)])
def test_waypoint_capture_target_per_firmware(tmp_path, fw, target):
    c = build(tmp_path, waypoint_capture, firmware=fw)
    (cap,) = [it for it in c.items if it.command == m.MAV_CMD_IMAGE_START_CAPTURE]
    assert cap.param1 == target and cap.param3 == 1
    k = c.items.index(cap)
    assert c.items[k - 1].param1 == 3
    # the report re-flies that capture as the firmware aims it: CAM2 is the WIRIS at 101, not "the 2nd camera"
    from missions.measure.flight import simulate
    assert [p.payloads for p in simulate(c).photos if p.cause == k] == [("thermal",)]


def with_rededge(doc, comp=None):
    doc["payloads"]["ms"] = {"camera": "rededge-mx"}
    if comp:
        doc["payloads"]["ms"]["component_id"] = comp


def test_rededge_capture_refused(tmp_path):
    def ch(doc):
        with_rededge(doc)
        waypoint_capture(doc)
        doc["mission"][2]["waypoint"]["capture"] = "ms"
    with pytest.raises(PlanError, match="RedEdge"):
        build(tmp_path, ch)


def test_rededge_alongside_gets_overlap_mode_and_port(tmp_path):
    def ch(doc):
        with_rededge(doc)
        survey(doc)["payloads"] = ["thermal", "ms"]
    c = build(tmp_path, ch)
    got = {s.param_id: s.value for s in c.setup if s.kind == "param_set"}
    assert got["autoCapMode"] == 2 and got["operatingAlt"] == 40 and got["overlapAlongTrk"] == 80
    params = {n: v for n, v, _ in c.params}
    # SRn is the n-th MAVLink channel, not SERIALn (ArduPilot #28646): with SERIAL0-2 MAVLink and SERIAL3 the GPS,
    # SERIAL4 is channel 3; SR4 would be a channel that does not exist, and the RedEdge would get no GPS
    assert params["SERIAL4_PROTOCOL"] == 1 and params["SR3_EXT_STAT"] > 0 and params["MAV4_EXT_STAT"] > 0
    assert params["SR2_POSITION"] > 0 and not any(n.startswith("SR4_") for n in params)
    # the WIRIS left component 100 to the RedEdge: at 101 ArduPilot finds it only as CAM2, and CAM1 goes off so
    # that CAM2 is the primary camera distance triggering fires; the RedEdge is not an AP_Camera instance
    assert params["CAM2_TYPE"] == 6 and params["CAM1_TYPE"] == 0 and "CAM3_TYPE" not in params


def test_px4_has_two_mavlink_instances_for_cameras(tmp_path):
    """PX4 has MAV_0..MAV_2 and MAV_0 is the ground station's: a third MAVLink camera has no MAV_3 to go to."""
    def two(doc):
        doc["payloads"]["vis"] = {"camera": "wiris-security", "component_id": 102}
    params = {n for n, _v, _ in build(tmp_path, two, firmware="px4").params}
    assert {"MAV_1_CONFIG", "MAV_2_CONFIG"} <= params and not any(n.startswith("MAV_3") for n in params)

    def three(doc):
        two(doc)
        doc["payloads"]["vis2"] = {"camera": "wiris-security", "component_id": 103}
    with pytest.raises(PlanError) as ei:
        build(tmp_path, three, firmware="px4")
    assert "MAV_0..MAV_2" in ei.value.message and ei.value.hint


def test_rededge_and_wiris_both_on_100(tmp_path):
    def ch(doc):
        with_rededge(doc, 100)
        doc["payloads"]["thermal"]["component_id"] = 100
    with pytest.raises(PlanError) as ei:
        build(tmp_path, ch)
    assert "101..105" in str(ei.value)


def test_item_limit_splits_into_parts(tmp_path):
    c = build(tmp_path, lambda d: d["vehicle"].update(max_mission_items=20))
    assert c.item_limit == 20 and len(c.parts) > 1 and all(len(p) <= 20 for p in c.parts)
    assert any(w.code == "mission_split" for w in c.warnings)


def test_too_fast_for_the_camera_names_the_speed(tmp_path):
    def ch(doc):
        doc["vehicle"]["speed_mps"] = 15
        survey(doc).update(altitude_m=10, overlap={"front": 90, "side": 70})
    with pytest.raises(PlanError) as ei:
        build(tmp_path, ch)
    # along-track 8.704 mm × 10 m / 13 mm × 0.1 = 0.67 m per photo; 1 s minimum -> 0.6 m/s
    assert "minimum capture interval of 1 s" in ei.value.message
    assert "0.6 m/s" in ei.value.hint
    assert ":" in ei.value.where


def test_warnings_altitude_and_assumed_optics(tmp_path):
    """Above 120 m only under a permit the plan states (without one the loader refuses: test_plan_checks)."""
    def change(d):
        survey(d).update(altitude_m=150)
        d["vehicle"]["max_altitude_m"] = 150
    c = build(tmp_path, change)
    codes = {w.code for w in c.warnings}
    assert {"altitude_above_120m", "assumed_optics"} <= codes


def test_a_high_waypoint_is_warned_about_once(tmp_path):
    """The compiler warns with the plan's location; the report does not repeat it from the re-flight."""
    def change(d):
        d["mission"].insert(-1, {"waypoint": {"lat": 50.1105, "lon": 14.5035, "alt_m": 130}})
        d["vehicle"]["max_altitude_m"] = 130
    c = build(tmp_path, change)
    rep = report(c)
    high = [w for w in rep.warnings if w.code == "altitude_above_120m"]
    assert len(high) == 1 and ".yaml:" in high[0].message


@pytest.mark.parametrize("frame,first,p1", [("plane", "NAV_TAKEOFF", 15.0), ("vtol", "NAV_VTOL_TAKEOFF", 0.0),
                                            ("copter", "NAV_TAKEOFF", 0.0)])
def test_takeoff_per_frame(tmp_path, frame, first, p1):
    c = build(tmp_path, flown_by(frame))
    assert names(c.items)[0] == first and c.items[0].param1 == p1 and c.items[0].z == 30


@pytest.mark.parametrize("frame", ["plane", "vtol", "copter"])
@pytest.mark.parametrize("fw", ["ardupilot", "px4"])
def test_speed_type_per_firmware_and_frame(tmp_path, frame, fw):
    """ArduPlane reads a ground-speed DO_CHANGE_SPEED as its minimum ground speed (Plane::do_change_speed:
    `case 1: aparm.min_gndspeed_cm.set(...)`), so a plane's or VTOL's speed is sent as airspeed there."""
    c = build(tmp_path, flown_by(frame), firmware=fw)
    speeds = [it for it in c.items if it.command == m.MAV_CMD_DO_CHANGE_SPEED]
    air = fw == "ardupilot" and frame != "copter"
    assert speeds and all(it.param1 == (m.SPEED_TYPE_AIRSPEED if air else m.SPEED_TYPE_GROUNDSPEED)
                          and it.param2 == SPEED_MPS[frame] for it in speeds)
    assert any(w.code == "speed_is_airspeed" for w in c.warnings) == air


@pytest.mark.parametrize("fw", ["ardupilot", "px4"])
def test_plane_landing_needs_a_glide_slope(tmp_path, fw):
    """A fixed-wing NAV_LAND straight under the last waypoint: PX4 refuses the mission (FW_LND_ANG, 5° by
    default) and ArduPlane would dive; an approach of 40 m over 460 m (5°) or more is accepted."""
    def under(doc):
        flown_by("plane")(doc)
        doc["mission"][-1] = {"land": {}}
    with pytest.raises(PlanError) as ei:
        build(tmp_path, under, firmware=fw)
    assert "glide" in ei.value.message and "rtl" in ei.value.hint and ei.value.where

    def far(doc):
        under(doc)
        doc["mission"].insert(-1, {"waypoint": {"lat": 50.1100, "lon": 14.5000, "alt_m": 40}})
        doc["mission"][-1] = {"land": {"lat": 50.1100 - 470 / 111195.0, "lon": 14.5000}}
    c = build(tmp_path, far, firmware=fw)
    assert c.items[-1].command == m.MAV_CMD_NAV_LAND


def test_self_intersecting_area_located(tmp_path):
    bowtie = [[50.110, 14.500], [50.112, 14.503], [50.110, 14.503], [50.112, 14.500]]
    with pytest.raises(PlanError) as ei:
        build(tmp_path, lambda d: survey(d).update(area=bowtie))
    assert "intersect" in ei.value.message.lower()
    assert ei.value.where and str(tmp_path / "plan.yaml") in ei.value.where


def test_zero_area_located(tmp_path):
    line = [[50.110, 14.500], [50.111, 14.501], [50.112, 14.502]]
    with pytest.raises(PlanError) as ei:
        build(tmp_path, lambda d: survey(d).update(area=line))
    assert "area" in ei.value.message.lower()
    assert ei.value.where and str(tmp_path / "plan.yaml") in ei.value.where


def test_unknown_optics_lead_refused_second_warned(tmp_path):
    def lead(doc):
        doc["payloads"]["agro"] = {"camera": "wiris-agro", "component_id": 102}
        survey(doc)["payloads"] = ["agro"]
    with pytest.raises(PlanError, match="optics"):
        build(tmp_path, lead)

    def second(doc):
        doc["payloads"]["agro"] = {"camera": "wiris-agro", "component_id": 102}
        survey(doc)["payloads"] = ["thermal", "agro"]
    c = build(tmp_path, second, firmware="px4")     # ArduPilot would refuse a second distance-triggered WIRIS
    assert any(w.code == "no_optics" for w in c.warnings)
    assert [p.name for p in c.payloads] == ["thermal"]


def test_corridor_compiles(tmp_path):
    def ch(doc):
        doc["mission"][1] = {"corridor": {"line": [[50.110, 14.500], [50.113, 14.504]], "width_m": 40,
                                          "payloads": ["thermal"], "altitude_m": 40,
                                          "overlap": {"front": 80, "side": 60}}}
    c = build(tmp_path, ch)
    assert c.areas[0].kind == "corridor"
    assert any(it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST and it.param1 > 0 for it in c.items)


def test_corridor_longer_than_a_plan_can_hold_is_refused_before_planning(tmp_path):
    # one vertex's longitude typed wrong: a 12 000 km line (planning it held 9 GB before this was checked)
    def ch(doc):
        doc["home"].update(lat=-35.2615, lon=149.0394)
        doc["mission"][1] = {"corridor": {"line": [[-35.261, 149.04], [-35.2578, 0.5], [-35.2561, 149.0539]],
                                          "width_m": 50, "payloads": ["thermal"], "altitude_m": 50,
                                          "overlap": {"front": 70, "side": 50}}}
    with pytest.raises(PlanError, match=r"corridor line spans \d+ km, more than the 200 km") as ei:
        build(tmp_path, ch)
    assert "plan.yaml:" in ei.value.where and "several plans" in ei.value.hint


def test_survey_with_more_photos_than_a_plan_can_hold_is_refused_before_planning(tmp_path):
    # 13 km x 13 km at 40 m: about 3 000 000 photos (an area typed in the wrong units is larger still)
    big = [[50.0, 14.0], [50.0, 14.1815], [50.1168, 14.1815], [50.1168, 14.0]]
    with pytest.raises(PlanError, match=r"this survey would take about [\d,]+ photos, more than the 2,000,000") as ei:
        build(tmp_path, lambda d: survey(d).update(area=big))
    assert "plan.yaml:" in ei.value.where and "fly higher" in ei.value.hint


@pytest.mark.parametrize("step,what", [
    ({"survey": {"area": [[1.0, 14.5], [1.0, 14.503], [1.002, 14.503], [1.002, 14.5]], "payloads": ["thermal"],
                 "altitude_m": 40, "overlap": {"front": 80, "side": 70}}}, "area"),
    ({"corridor": {"line": [[50.11, 41.5], [50.113, 41.504]], "width_m": 40, "payloads": ["thermal"],
                   "altitude_m": 40, "overlap": {"front": 80, "side": 60}}}, "corridor"),
    ({"waypoint": {"lat": 14.5, "lon": 50.11, "alt_m": 30}}, "waypoint"),
    ({"land": {"lat": 50.11, "lon": 41.5}}, "landing point")])
def test_a_step_far_from_home_is_refused(tmp_path, step, what):
    # a coordinate typed wrong: the flight there would be thousands of km (a RedEdge shoots all the way,
    # and measuring its million photos took 30 s)
    with pytest.raises(PlanError, match=rf"this {what} lies [\d,]+ km from home, more than the 200 km") as ei:
        build(tmp_path, lambda d: d["mission"].insert(1, step))
    assert "plan.yaml:" in ei.value.where and "swapped" in ei.value.hint


def test_the_photo_budget_is_the_whole_plans(tmp_path, monkeypatch):
    import missions.geometry.survey

    one = len(build(tmp_path).intent[0].photos)
    monkeypatch.setattr(missions.geometry.survey, "MAX_PHOTOS", int(one * 1.5))   # room for one survey, not two

    def twice(doc):
        doc["mission"].insert(2, copy.deepcopy(doc["mission"][1]))
    with pytest.raises(PlanError, match=rf"after {one:,} in earlier steps") as ei:
        build(tmp_path, twice)
    assert "plan.yaml:" in ei.value.where


def test_px4_params(tmp_path):
    c = build(tmp_path, firmware="px4")
    params = {n: v for n, v, _ in c.params}
    assert params["TRIG_INTERFACE"] == 3 and params["TRIG_MODE"] == 4
    assert params["MAV_1_FORWARD"] == 1 and params["SER_TEL2_BAUD"] == 57600
    from missions.emit.params import format_params
    text = format_params(c)
    assert "param set TRIG_MODE 4" in text and "# " in text


def test_ardupilot_params_file_format(tmp_path):
    from missions.emit.params import format_params
    c = build(tmp_path)
    lines = format_params(c).splitlines()
    assert "CAM2_TYPE,6" in lines and "SERIAL2_PROTOCOL,2" in lines and "SERIAL2_BAUD,57" in lines
    assert all(l.startswith("#") or "," in l for l in lines)


@pytest.mark.parametrize("version,names", [(None, {"SR2_POSITION", "MAV3_POSITION"}), ("4.5", {"SR2_POSITION"}),
                                           ("4.6", {"SR2_POSITION"}), ("4.7", {"MAV3_POSITION"}),
                                           (4.7, {"MAV3_POSITION"})])
def test_ardupilot_stream_rates_named_as_each_release_names_them(tmp_path, version, names):
    # 4.5 and 4.6 name channel n's stream rates SRn_, 4.7 MAV(n+1)_: a file with only SR2_POSITION gives a 4.7
    # camera no GLOBAL_POSITION_INT and every image is tagged 0,0. Without a release both go in, each commented.
    def ch(doc):
        if version is not None:
            doc["vehicle"]["firmware_version"] = version
    c = build(tmp_path, ch)
    got = {n for n, v, _ in c.params if n.endswith("_POSITION")}
    assert got == names
    why = {n: w for n, _, w in c.params}
    assert all(("4.7+" in why[n]) == n.startswith("MAV") for n in names)


def test_autopilot_serial_names_the_port_and_its_channel(tmp_path):
    def ch(doc):
        doc["payloads"]["thermal"]["autopilot_serial"] = 1
    params = {n: v for n, v, _ in build(tmp_path, ch).params}
    assert params["SERIAL1_PROTOCOL"] == 2 and params["SR1_POSITION"] == 5 and params["MAV2_POSITION"] == 5
    assert "SERIAL2_PROTOCOL" not in params


def test_autopilot_serial_names_the_px4_telem_port(tmp_path):
    def ch(doc):
        doc["payloads"]["thermal"]["autopilot_serial"] = 3
    params = {n: v for n, v, _ in build(tmp_path, ch, firmware="px4").params}
    assert params["MAV_1_CONFIG"] == 103 and params["SER_TEL3_BAUD"] == 57600 and "SER_TEL2_BAUD" not in params


def test_a_wiris_no_ardupilot_camera_instance_looks_for_is_refused(tmp_path):
    # MAVLinkCamV2 looks for CAMn at component 100 + n - 1 only, and ArduPilot has CAM1 and CAM2: a WIRIS at
    # 102 would never be found and take no photo, silently
    def ch(doc):
        doc["payloads"]["thermal"]["component_id"] = 102
    with pytest.raises(PlanError) as ei:
        build(tmp_path, ch)
    assert "100 + n - 1" in ei.value.message and "102" in ei.value.message and "component_id" in ei.value.hint
    assert build(tmp_path, ch, firmware="px4").items     # PX4 addresses the component itself


def test_px4_fixture_plan():
    c = compile_plan(PLANS / "px4-interval.yaml")
    n = names(c.items)
    assert set(n) <= MAY_EMIT["px4"] and c.lua is None
    assert "DO_SET_CAM_TRIGG_INTERVAL" in n and "SET_CAMERA_MODE" in n and n[-1] == "NAV_LAND"
    mode = c.items[n.index("SET_CAMERA_MODE")]
    assert (mode.x, mode.y) == (3, 2)          # fullscreen 2 + 1, visible 1 + 1 (manual §6.3.2.5)
    # Security thermal: 17 µm, 35 mm -> 5 cm/px at 0.05 · 35 / 0.017 m
    assert c.areas[0].altitude_m == pytest.approx(0.05 * 35 / 0.017, rel=1e-6)
    iv = c.items[n.index("DO_SET_CAM_TRIGG_INTERVAL")].param1 / 1000
    assert iv >= 1.8                               # the Security's minimum interval (QGC CameraMetaData)


def test_video_setting_refused_at_the_payload(tmp_path):
    def ch(doc):
        doc["payloads"]["thermal"]["settings"] = {"video": ["visible_encoded"]}
    with pytest.raises(PlanError) as ei:
        build(tmp_path, ch)
    assert "recording" in ei.value.message and str(tmp_path / "plan.yaml") in ei.value.where


def test_rededge_alone_sets_its_own_overlap_mode_and_gets_no_trigger_items(tmp_path):
    def ch(doc):
        doc["payloads"] = {"ms": {"camera": "rededge-m"}}
        survey(doc)["payloads"] = ["ms"]
        survey(doc)["altitude_m"] = 80
    c = build(tmp_path, ch)
    assert not any(it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST for it in c.items)
    got = {s.param_id: s.value for s in c.setup}
    assert got["autoCapMode"] == 2 and got["operatingAlt"] == 80
    assert c.payloads[0].gsd_cm(120) == pytest.approx(8.33, abs=0.01)


def test_rededge_overlap_mode_covers_every_survey_in_its_integers(tmp_path):
    """The camera captures from operatingAlt - opAltTolerance up (serial API: "distance ... below the operating
    altitude to enable automatic capture modes") and holds one overlap: the lowest survey altitude, a margin
    below it, the most demanding overlaps, each an integer of the parameter's type."""
    def ch(doc):
        doc["payloads"] = {"ms": {"camera": "rededge-m"}}
        survey(doc)["payloads"] = ["ms"]
        survey(doc)["altitude_m"] = 60.5
        survey(doc)["overlap"] = {"front": 70, "side": 72.2}
        second = copy.deepcopy(doc["mission"][1])
        second["survey"]["altitude_m"] = 45.7
        second["survey"]["overlap"] = {"front": 80.4, "side": 60}
        doc["mission"].insert(2, second)
    c = build(tmp_path, ch)
    got = {s.param_id: (s.value, s.type) for s in c.setup}
    assert got["operatingAlt"] == (45, "MAV_PARAM_TYPE_INT32")
    # shooting from 45.7 - 11.425 m up: 34.275 m, so the tolerance below the integer target is 11 m
    assert got["opAltTolerance"] == (11, "MAV_PARAM_TYPE_UINT32")
    assert got["overlapAlongTrk"] == (81, "MAV_PARAM_TYPE_UINT32")
    assert got["overlapCrossTrk"] == (73, "MAV_PARAM_TYPE_UINT32")


def two_wiris(doc):
    # 100 and 101: the components ArduPilot's CAM1 and CAM2 look for
    doc["payloads"]["thermal"]["component_id"] = 100
    doc["payloads"]["vis"] = {"camera": "wiris-security", "component_id": 101}
    survey(doc)["payloads"] = ["thermal", "vis"]


def test_two_wiris_distance_triggered_on_ardupilot_refused(tmp_path):
    # ArduPilot AP_Camera::set_trigger_distance() drives the primary instance only
    with pytest.raises(PlanError) as ei:
        build(tmp_path, two_wiris)
    assert "primary" in ei.value.message and "vis" in ei.value.message and "hover" in ei.value.hint


def test_two_wiris_hover_on_ardupilot_and_distance_on_px4(tmp_path):
    def hover(doc):
        two_wiris(doc)
        survey(doc)["trigger"] = "hover"
    c = build(tmp_path, hover)
    caps = [it for it in c.items if it.command == m.MAV_CMD_IMAGE_START_CAPTURE]
    assert caps and all(it.param1 == 0 for it in caps)           # 0 = every AP_Camera instance
    assert {n for n, v, _ in c.params} >= {"CAM1_TYPE", "CAM2_TYPE"}
    def slow(doc):
        two_wiris(doc)
        # the Security needs 1.8 s between photos, and its 35 mm lens (1.94 cm/px at 40 m) a sharp image:
        # 1.9 m/s in its 10 ms time constant
        doc["vehicle"]["speed_mps"] = 1.8
    c = build(tmp_path, slow, firmware="px4")
    assert any(it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST for it in c.items)


def test_in_flight_setting_whose_condition_the_preflight_settings_meet_compiles(tmp_path):
    # range_max_c travels only with range_mode manual; the payload sets manual before flight, so an in-flight
    # step changing range_max_c alone is sent (the loader accepted it, the emitter refused it: "none of these
    # settings reaches wiris-pro by a command")
    def ch(doc, step_settings):
        doc["payloads"]["thermal"]["settings"] = {"range_mode": "manual", "range_min_c": 0, "range_max_c": 80}
        doc["mission"].insert(2, {"camera": {"payload": "thermal", "settings": step_settings}})
    for settings in ({"range_max_c": 90}, {"range_mode": "manual", "range_max_c": 90}):
        c = build(tmp_path, lambda d: ch(d, settings))
        user1 = [b for b in lua.decode(c.items) if b.command == "MAV_CMD_USER_1"]
        assert user1 and 90 in user1[-1].params, user1


def test_land_before_any_position_needs_lat_lon(tmp_path):
    with pytest.raises(PlanError, match="land needs lat/lon") as ei:
        build(tmp_path, lambda d: d.update(mission=[{"land": None}]))
    assert "lat" in ei.value.hint and "takeoff" in ei.value.hint
    assert str(tmp_path / "plan.yaml") in ei.value.where


def test_corridor_of_one_repeated_point_is_refused(tmp_path):
    def ch(doc):
        doc["mission"][1] = {"corridor": {"line": [[50.110, 14.500], [50.110, 14.500]], "width_m": 40,
                                          "payloads": ["thermal"], "altitude_m": 40,
                                          "overlap": {"front": 80, "side": 60}}}
    with pytest.raises(PlanError, match="corridor line has no length") as ei:
        build(tmp_path, ch)
    assert "different points" in ei.value.hint
    assert "plan.yaml:" in ei.value.where


def test_area_file_errors_keep_file_location_and_hint_through_the_compiler(tmp_path):
    (tmp_path / "field.geojson").write_text('{"type": "Polygon", "coordinates": [[[14.5], [14.505, 50.1]]]}')
    with pytest.raises(PlanError, match=r"position must be \[lon, lat\]") as ei:
        build(tmp_path, lambda d: survey(d).update(area="field.geojson"))
    assert ei.value.where == f"{tmp_path / 'field.geojson'}: $.coordinates[0][0]"
    assert "GeoJSON order" in ei.value.hint


LINE = [[50.110, 14.500], [50.113, 14.504]]


@pytest.mark.parametrize("planner,kwargs,where", [
    ("survey", {"speed_mps": 0}, "vehicle.speed_mps"),
    ("survey", {"turnaround_m": -1}, "turnaround_m"),
    ("survey", {"angle_deg": "north"}, "angle_deg"),
    ("survey", {"angle_deg": float("nan")}, "angle_deg"),
    ("corridor", {"line": LINE[:1]}, "corridor.line"),
    ("corridor", {"width_m": 0}, "corridor.width_m"),
])
def test_geometry_argument_errors_carry_a_hint(planner, kwargs, where):
    # the plan schema keeps these out of a plan file; library callers get the same where, what and hint
    from missions.geometry.area import load_area
    from missions.geometry.corridor import plan_corridor
    from missions.geometry.footprint import Footprint
    from missions.geometry.survey import plan_survey

    fp = Footprint(across_m=50.0, along_m=40.0)
    with pytest.raises(PlanError) as ei:
        if planner == "survey":
            plan_survey(load_area(SQUARE), fp, 80, 70, **kwargs)
        else:
            args = {"line": LINE, "width_m": 40, **kwargs}
            plan_corridor(args["line"], args["width_m"], fp, 80, 60)
    assert ei.value.where == where
    assert ei.value.hint and "e.g." in ei.value.hint


def _triangles_geojson(path: Path, n: int, lat0: float = 50.1105, lon0: float = 14.5005) -> None:
    """n separated triangles, 20 to 60 m across, 80 m apart, as one GeoJSON MultiPolygon (a parcel or crown export)."""
    import json
    import math
    cols = math.ceil(math.sqrt(n))
    m_lon = 111_320.0 * math.cos(math.radians(lat0))
    polys = []
    for k in range(n):
        cx, cy = (k % cols) * 80.0, (k // cols) * 80.0
        r = (20.0 + (k * 7) % 41) / 2.0
        turn = math.radians((k * 37) % 120)
        ring = [[lon0 + (cx + r * math.sin(turn + j * 2 * math.pi / 3)) / m_lon,
                 lat0 + (cy + r * math.cos(turn + j * 2 * math.pi / 3)) / 111_320.0] for j in range(3)]
        polys.append([ring + ring[:1]])
    path.write_text(json.dumps({"type": "MultiPolygon", "coordinates": polys}))


def test_an_area_of_1500_small_polygons_compiles_with_every_part_photographed(tmp_path):
    import numpy as np
    import shapely

    from missions.measure.coverage import _arrays, footprint_polygons
    from missions.geometry.optics import footprint
    _triangles_geojson(tmp_path / "crowns.geojson", 1500)
    c = build(tmp_path, lambda d: survey(d).update(area="crowns.geojson", angle_deg="auto", altitude_m=60))
    plan = c.intent[0]
    parts = np.array(list(plan.area.geometry.geoms))
    assert len(parts) == 1500
    fp = footprint(c.payloads[0], 60)
    xy, h, _span = _arrays(plan.photos)
    covered = shapely.union_all(footprint_polygons(xy, h, fp))
    assert (shapely.area(shapely.intersection(parts, covered)) / shapely.area(parts)).min() >= 0.995
    assert len({(l.part, l.line, l.v0) for l in plan.legs}) == len(plan.legs)     # every leg flown once
    assert any(w.code == "mission_split" for w in c.warnings)            # 9,000 items: in parts


def test_an_area_of_more_polygons_than_a_survey_plans_names_the_limit(tmp_path, monkeypatch):
    from missions.geometry import survey as planner
    monkeypatch.setattr(planner, "MAX_SURVEY_PARTS", 100)
    _triangles_geojson(tmp_path / "crowns.geojson", 101)
    with pytest.raises(PlanError, match="the area has 101 separate polygons, more than the 100 one survey can") as ei:
        build(tmp_path, lambda d: survey(d).update(area="crowns.geojson"))
    assert "crowns.geojson" in ei.value.where
    assert "merge or simplify" in ei.value.hint


def test_px4_params_turn_camera_trigger_off_without_a_triggered_survey(tmp_path):
    # PX4 SITL: with TRIG_MODE 4 three waypoint captures gave the camera 10 photos (each capture is also a
    # camera_trigger shot, sent on as IMAGE_START_CAPTURE + DO_DIGICAM_CONTROL); with TRIG_MODE 0, 3
    c = build(tmp_path, lambda d: survey(d).update(trigger="hover"), firmware="px4")
    params = {n: v for n, v, _ in c.params}
    assert params["TRIG_MODE"] == 0 and "TRIG_INTERFACE" not in params
    assert build(tmp_path, firmware="px4").params[1][:2] == ("TRIG_MODE", 4.0)


def test_px4_plane_ending_in_rtl_does_not_require_a_landing(tmp_path):
    # PX4 SITL (sihsim_airplane): a fixed-wing mission without a landing is rejected ("Landing waypoint/pattern
    # required", MIS_TKO_LAND_REQ 2 from rc.fw_defaults) and arming is refused
    import sitl_plans
    plane = sitl_plans.write_plan(tmp_path, "survey", name="plane", frame="plane", speed=12, firmware="px4")
    plane.write_text(plane.read_text().replace("altitude_m: 40", "altitude_m: 120")
                     .replace("front: 75", "front: 60"))
    params = {n: v for n, v, _ in compile_plan(plane).params}
    assert params["MIS_TKO_LAND_REQ"] == 0
    copter = compile_plan(sitl_plans.write_plan(tmp_path, "survey", name="copter", firmware="px4"))
    assert "MIS_TKO_LAND_REQ" not in {n for n, _, _ in copter.params}
