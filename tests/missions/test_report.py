"""The report measures the emitted items: coverage, overlap, photos, time — re-derived, never taken from intent."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from handmade_mission import THERMAL, handmade
from missions.compiled import Compiled
from missions.emit.items import mavlink
from missions.emit.trigger_distance import ardupilot_metre
from missions.measure.flight import simulate
from missions.measure.report import report


def test_report_has_the_binding_fields():
    rep = report(handmade()).to_json()
    for key in ("plan", "firmware", "mission_items", "item_limit", "parts", "photos", "path_length_m",
                "flight_time_s", "area_m2", "gsd_cm", "coverage", "overlap", "warnings", "errors"):
        assert key in rep
    assert rep["mission_items"] == len(handmade().items)
    assert set(rep["overlap"]["thermal"]) == {"front_min", "side_min"}
    lo, hi = rep["gsd_cm"]["thermal"]
    assert lo == hi == pytest.approx(THERMAL.gsd_cm(40.0), rel=1e-3)



def test_the_report_is_a_frozen_value_and_its_json_keeps_the_documented_order():
    """check --json and NAME.report.json are the report's to_json(): plain JSON values, keys in this order."""
    import dataclasses
    import json

    rep = report(handmade())
    with pytest.raises(dataclasses.FrozenInstanceError):
        rep.errors = ()
    with pytest.raises(TypeError):
        rep.coverage["thermal"] = 0.0       # its tables are read-only too
    doc = rep.to_json()
    assert list(doc) == ["plan", "name", "firmware", "frame", "mission_items", "item_limit", "parts", "part_items",
                         "photos", "path_length_m", "climb_m", "flight_time_s", "flight_time_qgc_s",
                         "max_altitude_m", "area_m2", "gsd_cm", "coverage", "overlap", "areas", "warnings", "errors",
                         "speed_mps", "sun", "steps", "ground", "endurance", "sorties", "sorties_union"]
    assert doc["ground"] == "ground assumed flat at home elevation" and "terrain" not in doc
    assert list(doc["areas"][0]) == ["step", "kind", "area_m2", "altitude_m", "trigger", "requested", "coverage",
                                     "overlap", "photos", "outside_m", "over_gaps_m", "over_gaps_camera_m",
                                     "photos_in_zones"]
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc
    assert doc["overlap"]["thermal"] == {"front_min": rep.overlap["thermal"].front_min,
                                         "side_min": rep.overlap["thermal"].side_min}
    assert doc["warnings"] == [{"code": w.code, "message": w.message} for w in rep.warnings]

def test_full_lawnmower_covers_and_meets_the_overlap():
    rep = report(handmade())
    assert rep.coverage["thermal"] >= 0.995
    assert rep.overlap["thermal"].front_min == pytest.approx(0.8, abs=0.005)
    assert rep.overlap["thermal"].side_min == pytest.approx(0.7, abs=0.005)
    assert not rep.errors


def _without_lines(c, lines):
    """Drop the trigger-on items of some lines (the planner's intent is unchanged)."""
    ons = [i for i, it in enumerate(c.items)
           if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST and it.param1 > 0]
    drop = {ons[k] for k in lines}
    items = tuple(it for i, it in enumerate(c.items) if i not in drop)
    return Compiled(c.name, c.firmware, c.frame, c.home, c.speed_mps, items, (items,), c.item_limit,
                    c.payloads, c.areas, c.setup, intent=c.intent)


def test_coverage_falls_when_trigger_items_are_deleted():
    full = handmade()
    before = report(full)
    n_on = sum(1 for it in full.items if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST and it.param1 > 0)
    # seven neighbouring lines (side overlap 70 %: fewer leave no gap a footprint does not close)
    cut = _without_lines(full, range(n_on // 2 - 3, n_on // 2 + 4))
    after = report(cut)
    assert after.photos["thermal"] < before.photos["thermal"]
    assert after.coverage["thermal"] < before.coverage["thermal"] - 0.05
    assert any(w.code == "coverage_low" for w in after.warnings)
    # the stop items still shoot once each (param3 = 1): 18 photos, one per line end
    ends = report(_without_lines(full, range(n_on)))
    assert ends.photos["thermal"] == n_on
    # no trigger item at all: nothing photographed, nothing covered
    items = tuple(it for it in full.items if it.command != mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST)
    bare = Compiled(full.name, full.firmware, full.frame, full.home, full.speed_mps, items, (items,),
                    full.item_limit, full.payloads, full.areas, full.setup)
    none = report(bare)
    assert none.photos["thermal"] == 0 and none.coverage["thermal"] == 0.0


def test_photos_follow_the_distance_trigger():
    c = handmade()
    sim = simulate(c)
    trig = c.areas[0].trigger_distance_m
    # consecutive photos of one leg are one trigger distance apart as ArduPilot fires it: its 50 Hz check
    # shoots at the first step of travel at or past the distance (ArduPilot SITL: 870 photos where the exact
    # distance predicts 882 on powerline-corridor), so the spacing is the distance rounded up to whole steps, of
    # ArduPilot's metres: these north-south lines at 50.1° N fly 0.08 % shorter in true metres
    step = c.speed_mps / 50
    metre = ardupilot_metre(c.home[0]).north
    by_span: dict[int, list] = {}
    for p in sim.photos:
        by_span.setdefault(p.span, []).append(p)
    gaps = [math.hypot(b.x - a.x, b.y - a.y) for ps in by_span.values() for a, b in zip(ps, ps[1:])]
    assert trig < math.ceil(trig / step) * step < trig + step
    assert gaps and max(gaps) == pytest.approx(math.ceil(trig / step) * step * metre, rel=1e-5)
    assert min(gaps) >= 0.0
    assert all(p.alt_m == pytest.approx(40.0) for p in sim.photos)


def test_hover_capture_photos_and_hold_time():
    dist = report(handmade())
    hov_c = handmade(hover=True)
    hov = report(hov_c)
    captures = sum(1 for it in hov_c.items if it.command == mavlink.MAV_CMD_IMAGE_START_CAPTURE)
    assert hov.photos["thermal"] == captures
    # every hover point holds 2 s and stops: a hover survey takes longer than flying through
    assert hov.flight_time_s > dist.flight_time_s + 2 * captures
    assert hov.flight_time_qgc_s >= 2 * captures


def test_flight_time_model_is_not_shorter_than_qgc_statistic():
    rep = report(handmade())
    # QGC: horizontal distance / speed + holds; ours adds acceleration, corners and the climb
    assert rep.flight_time_s > rep.flight_time_qgc_s
    assert rep.flight_time_qgc_s == pytest.approx(rep.path_length_m / 6.0, rel=0.05)


def test_altitude_and_interval_warnings():
    high = report(handmade(alt=130.0))
    assert any(w.code == "altitude_above_120m" for w in high.warnings)
    fast = report(handmade(speed=12.0))
    assert any(w.code == "trigger_interval_short" for w in fast.warnings)
    slow = report(handmade(speed=4.0))
    assert not any(w.code == "trigger_interval_short" for w in slow.warnings)
    assert any(w.code == "assumed_optics" for w in slow.warnings)


def test_item_limit_error_when_a_part_is_too_long():
    c = handmade()
    small = Compiled(c.name, c.firmware, c.frame, c.home, c.speed_mps, c.items, (c.items,), 50,
                     c.payloads, c.areas, c.setup)
    rep = report(small)
    assert any(e.code == "item_limit" for e in rep.errors)


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _field_variant(tmp_path, external: bool):
    import shutil
    shutil.copytree(EXAMPLES / "areas", tmp_path / "areas")
    text = (EXAMPLES / "field-multispectral.yaml").read_text()
    if external:
        text = text.replace("    component_id: 100          # fixed",
                            "    settings: {auto_capture: external}\n    component_id: 100          # fixed")
    p = tmp_path / "field.yaml"
    p.write_text(text)
    return p


def test_rededge_in_overlap_mode_shoots_by_itself(tmp_path):
    from missions.compile import compile_plan
    c = compile_plan(_field_variant(tmp_path, external=False))
    sim = simulate(c)
    own = [p for p in sim.photos if "multispectral" in p.payloads]
    wiris = [p for p in sim.photos if "thermal" in p.payloads]
    assert own and all(p.cause == -1 for p in own)          # no mission item takes them
    assert wiris and all(p.cause >= 0 for p in wiris)
    # it shoots wherever it is at the survey altitude (in the turns too), never while climbing
    assert all(abs(p.alt_m - c.areas[0].altitude_m) <= 5.0 for p in own)
    assert report(c, sim).coverage["multispectral"] >= 0.995


def test_rededge_in_overlap_mode_shoots_above_its_target_too(tmp_path):
    """Above operatingAlt it keeps shooting ("when the sensor's altitude is below the Target Altitude Tolerance
    from the Target Altitude, the sensor stops capturing": nothing stops it higher up), so a second survey flown
    higher is photographed by it as well."""
    from missions.compile import compile_plan
    path = _field_variant(tmp_path, external=False)
    doc = yaml.safe_load(path.read_text())
    survey = next(s for s in doc["mission"] if "survey" in s)
    higher = {"survey": {**survey["survey"], "altitude_m": survey["survey"]["altitude_m"] + 30}}
    doc["mission"].insert(doc["mission"].index(survey) + 1, higher)
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    c = compile_plan(path)
    sim = simulate(c)
    low = survey["survey"]["altitude_m"]
    own = [p for p in sim.photos if "multispectral" in p.payloads]
    assert any(p.alt_m > low + 25 for p in own) and any(abs(p.alt_m - low) < 1 for p in own)
    assert all(p.alt_m >= low - max(10.0, 0.25 * low) - 1.0 for p in own)


def test_rededge_on_external_trigger_is_not_reached_by_ardupilot(tmp_path):
    from missions.compile import compile_plan
    plan = _field_variant(tmp_path, external=True)
    ap = report(compile_plan(plan))
    # ArduPilot's DO_SET_CAM_TRIGG_DIST drives its camera instances; the RedEdge is none of them
    assert ap.photos["multispectral"] == 0 and ap.coverage["multispectral"] == 0.0
    assert any(w.code == "coverage_low" and "multispectral" in w.message for w in ap.warnings)
    # PX4's camera_trigger sends to every camera component: the same photos as the WIRIS
    px4 = report(compile_plan(plan, firmware="px4"))
    assert px4.photos["multispectral"] == px4.photos["thermal"] > 0


INTERVAL_PLAN = """\
version: 1
name: iv
vehicle: {firmware: px4, frame: copter, speed_mps: 5}
home: {lat: 50.1102, lon: 14.5031, alt_amsl_m: 262}
payloads:
  thermal: {camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}
mission:
  - takeoff: {alt_m: 40}
  - survey:
      area: [[50.1110, 14.5040], [50.1110, 14.5060], [50.1120, 14.5060], [50.1120, 14.5040]]
      payloads: [thermal]
      altitude_m: 40
      overlap: {front: 70, side: 60}
      trigger: interval
  - rtl: {}
"""


def test_px4_interval_trigger_shoots_only_while_enabled(tmp_path):
    from missions.compile import compile_plan
    p = tmp_path / "iv.yaml"
    p.write_text(INTERVAL_PLAN)
    c = compile_plan(p)
    assert any(it.command == mavlink.MAV_CMD_DO_TRIGGER_CONTROL for it in c.items)
    sim = simulate(c)
    rep = report(c, sim)
    # no photo on the climb, the transit or the way home: all at survey altitude, inside the legs' spans
    assert sim.photos and all(abs(p.alt_m - 40.0) < 1e-6 for p in sim.photos)
    assert rep.coverage["thermal"] >= 0.995
    # on a straight leg, consecutive photos are the speed PX4 flies (missions.measure.flight) x interval apart
    from missions.measure.flight import PX4_MC_TRACKED_SPEED_RATIO
    interval = next(it.param1 for it in c.items if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL) / 1000
    gaps = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(sim.photos, sim.photos[1:]) if a.span == b.span]
    assert max(gaps) == pytest.approx(5.0 * PX4_MC_TRACKED_SPEED_RATIO * interval, rel=0.02)


def test_a_digicam_shot_fires_while_the_px4_trigger_is_stopped(tmp_path):
    # PX4's camera_trigger fires a DO_DIGICAM_CONTROL one-shot whatever DO_TRIGGER_CONTROL set (CameraTrigger::Run,
    # PX4-Autopilot 7704fe75): a shot placed after the last stop is one more photo, not swallowed by the stop
    from dataclasses import replace

    from missions.compile import compile_plan
    from missions.emit.items import FRAME_MISSION, MissionItem
    p = tmp_path / "iv.yaml"
    p.write_text(INTERVAL_PLAN)
    c = compile_plan(p)
    stop = max(i for i, it in enumerate(c.items)
               if it.command == mavlink.MAV_CMD_DO_TRIGGER_CONTROL and it.param1 == 0)
    shot = MissionItem(command=mavlink.MAV_CMD_DO_DIGICAM_CONTROL, frame=FRAME_MISSION, x=1)
    items = c.items[:stop + 1] + (shot,) + c.items[stop + 1:]
    with_shot = replace(c, items=items, parts=(items,))
    before, after = simulate(c).photos, simulate(with_shot).photos
    assert len(after) == len(before) + 1
    assert [ph.cause for ph in after].count(stop + 1) == 1  # taken by the inserted shot


def test_flight_time_of_one_leg_follows_the_stated_model():
    from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, MissionItem, deg_to_e7
    from missions.geometry.geo import LocalProjection
    from missions.measure.flight import ACCEL_MPS2, CLIMB_MPS, DESCENT_MPS, LAND_FINAL_M, LAND_MPS
    home = (50.0, 14.0, 300.0)
    lat, lon = LocalProjection(home[0], home[1]).point_to_latlon(0.0, 600.0)
    items = (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, FRAME_GLOBAL_RELATIVE_ALT, z=30.0),
             MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, FRAME_GLOBAL_RELATIVE_ALT, 10.0, x=deg_to_e7(lat),
                         y=deg_to_e7(lon), z=30.0),
             MissionItem(mavlink.MAV_CMD_NAV_LAND, FRAME_GLOBAL_RELATIVE_ALT))
    c = Compiled("leg", "ardupilot", "copter", home, 6.0, items, (items,), 700, (THERMAL,), (), ())
    rep = report(c)
    v, a = 6.0, ACCEL_MPS2
    expected = (30 / CLIMB_MPS                       # vertical take-off
                + 600 / v + v / a                    # accelerate, cruise, stop: v/a more than at constant speed
                + 10.0                               # hold
                + (30 - LAND_FINAL_M) / DESCENT_MPS + LAND_FINAL_M / LAND_MPS)
    assert rep.flight_time_s == pytest.approx(expected, rel=0.01)
    assert rep.flight_time_qgc_s == pytest.approx(600 / v + 10.0, rel=0.01)
    assert rep.path_length_m == pytest.approx(600.0, abs=0.5)
    assert not any(w.code == "no_landing" for w in rep.warnings)


@pytest.mark.parametrize("frame", ["copter", "vtol"])
def test_a_vtol_keeps_its_speed_through_turns(frame):
    # a VTOL flies the mission fixed-wing: a right-angle corner costs a copter a stop (braking and accelerating
    # again: v/a more than at constant speed, as for the start and end of the flight), a VTOL nothing; both take
    # off and land vertically
    from missions.geometry.geo import LocalProjection
    from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, MissionItem, deg_to_e7
    from missions.measure.flight import (ACCEL_MPS2, CLIMB_MPS, DESCENT_MPS, LAND_FINAL_M, LAND_MPS,
                                         PX4_MC_TRACKED_SPEED_RATIO)
    home = (50.0, 14.0, 300.0)
    proj = LocalProjection(home[0], home[1])
    takeoff, land = ((mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_NAV_LAND) if frame == "copter" else
                     (mavlink.MAV_CMD_NAV_VTOL_TAKEOFF, mavlink.MAV_CMD_NAV_VTOL_LAND))
    items = [MissionItem(takeoff, FRAME_GLOBAL_RELATIVE_ALT, z=30.0)]
    for x, y in ((0.0, 600.0), (600.0, 600.0)):
        lat, lon = proj.point_to_latlon(x, y)
        items.append(MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, FRAME_GLOBAL_RELATIVE_ALT, x=deg_to_e7(lat),
                                 y=deg_to_e7(lon), z=30.0))
    items.append(MissionItem(land, FRAME_GLOBAL_RELATIVE_ALT))
    items = tuple(items)
    c = Compiled("corner", "px4", frame, home, 15.0, items, (items,), 500, (THERMAL,), (), ())
    # a PX4 multicopter is timed at the speed it tracks, below the commanded (missions.measure.flight)
    v = 15.0 * (PX4_MC_TRACKED_SPEED_RATIO if frame == "copter" else 1.0)
    a = ACCEL_MPS2 if frame == "copter" else 2 * ACCEL_MPS2
    corner = v / a if frame == "copter" else 0.0
    expected = (30 / CLIMB_MPS + 1200 / v + v / a + corner
                + (30 - LAND_FINAL_M) / DESCENT_MPS + LAND_FINAL_M / LAND_MPS)
    assert report(c).flight_time_s == pytest.approx(expected, rel=0.005)


@pytest.fixture(scope="module")
def small_full():
    c = handmade(size_m=120.0)
    return c, report(c)


def test_removing_trigger_items_never_adds_coverage(small_full):
    from hypothesis import given, settings, strategies as st

    full, rep = small_full
    ons = [i for i, it in enumerate(full.items)
           if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST and it.param1 > 0]

    @settings(max_examples=8, deadline=None, derandomize=True)
    @given(st.sets(st.sampled_from(range(len(ons))), min_size=1))
    def check(drop):
        cut = _without_lines(full, sorted(drop))
        r = report(cut)
        assert r.photos["thermal"] < rep.photos["thermal"]
        assert r.coverage["thermal"] <= rep.coverage["thermal"] + 1e-9

    check()


def test_flying_over_a_hole_is_reported():
    # the hand-written lawn-mower flies straight through a 40 m hole in the middle of the area
    rep = report(handmade(size_m=160.0, hole_m=40.0))
    row = rep.areas[0]
    assert row.path.over_gaps_m > 40.0
    assert any(w.code == "path_over_exclusion" for w in rep.warnings)
    clean = report(handmade(size_m=160.0))
    assert clean.areas[0].path.over_gaps_m == 0.0
    assert not any(w.code == "path_over_exclusion" for w in clean.warnings)


def _compile_yaml(tmp_path, survey: dict, firmware: str = "ardupilot"):
    from missions.compile import compile_plan
    from missions.plan import parse_plan
    doc = {"version": 1, "name": "t", "vehicle": {"firmware": firmware, "frame": "copter", "speed_mps": 4.5},
           "home": {"lat": 50.0995, "lon": 14.5, "alt_amsl_m": 250},
           "payloads": {"thermal": {"camera": "wiris-pro", "imager": "thermal", "lens_mm": 13, "component_id": 100}},
           "mission": [{"takeoff": {"alt_m": 40}}, *({k: v} for k, v in survey.items()), {"rtl": {}}]}
    path = tmp_path / "plan.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return compile_plan(parse_plan(path.read_text(), str(path), tmp_path))


def test_hover_photos_of_two_lines_are_no_front_pair(tmp_path):
    # An L-shaped field flown in hover mode (the reviewer's hover-L plan): at the inner corner the next line is
    # reached through a detour that arrives with the old line's heading, beside the last stop. That pair was
    # measured as front overlap: 30 %, the side overlap, against 50 % requested and flown.
    L = [[50.1, 14.5], [50.0999999, 14.504193], [50.1010788, 14.504193], [50.1010788, 14.5016773],
         [50.1022476, 14.5016773], [50.1022476, 14.5]]
    c = _compile_yaml(tmp_path, {"survey": {"area": L, "payloads": ["thermal"], "altitude_m": 40,
                                            "overlap": {"front": 50, "side": 30}, "angle_deg": "auto",
                                            "trigger": "hover"}})
    sim = simulate(c)
    # every front pair (consecutive photos of one span) lies along its heading, one ahead of the other
    for p, q in zip(sim.photos, sim.photos[1:]):
        if p.span == q.span:
            h = math.radians(p.heading_deg)
            dx, dy = q.x - p.x, q.y - p.y
            assert dx * math.sin(h) + dy * math.cos(h) > 0
            assert abs(dx * math.cos(h) - dy * math.sin(h)) < 0.1
    assert report(c, sim).overlap["thermal"].front_min >= 0.49


# A strip 7 m wide (east-west) and 55 m long, flown in hover mode with east-west lines: each line is shorter than a
# footprint is long and holds one photo.
STRIP = {"survey": {"area": [[50.1, 14.5], [50.1, 14.5001], [50.1005, 14.5001], [50.1005, 14.5]],
                    "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 30, "side": 60},
                    "angle_deg": 90, "trigger": "hover"}}


def _off_line_deg(heading: float, line: float = 90.0) -> float:
    """Angle between a heading and a line's direction, either way along it (a footprint turned by 180° is the same)."""
    return abs((heading - line + 90.0) % 180.0 - 90.0)


@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
def test_a_one_photo_hover_line_is_shot_along_the_line(tmp_path, firmware):
    # Reached straight from the previous line, the vehicle faced across the line at its only photo (both autopilots
    # face the waypoint they fly to and keep that heading while hovering): the footprints, longer across than along,
    # stood turned and covered 96 %. The route now arrives along each line; PX4 also gets the line's heading as the
    # waypoint's yaw.
    from pyproj import Geod

    c = _compile_yaml(tmp_path, STRIP, firmware)
    sim = simulate(c)
    assert len(sim.photos) >= 2 and len({round(p.y, 1) for p in sim.photos}) == len(sim.photos)   # one per line
    assert report(c, sim).areas[0].coverage["thermal"] == 1.0
    assert all(_off_line_deg(p.heading_deg) < 0.01 for p in sim.photos)
    # in the mission: the vehicle comes to each photo from a position on its line, metres before it
    geod = Geod(ellps="WGS84")
    navs = [it for it in c.items if it.frame != mavlink.MAV_FRAME_MISSION]
    shots = [k for k, it in enumerate(navs) if it.command == mavlink.MAV_CMD_NAV_WAYPOINT and it.param1 > 0]
    assert len(shots) == len(sim.photos)
    for k in shots:
        before, at = navs[k - 1], navs[k]
        bearing, _back, dist = geod.inv(before.lon, before.lat, at.lon, at.lat)
        assert dist > 2.0 and _off_line_deg(bearing) < 0.05
        if firmware == "px4":
            assert _off_line_deg(at.param4) < 0.01
        else:
            assert math.isnan(at.param4)


@pytest.mark.parametrize("firmware,flown", [("ardupilot", False), ("px4", True)])
def test_a_waypoints_yaw_is_flown_on_px4_only(tmp_path, firmware, flown):
    # the same mission with every hover waypoint told to face north: PX4 turns the camera across the lines (and the
    # report says so), ArduPilot's AP_Mission drops the yaw at upload and the photos stay along the lines
    from dataclasses import replace

    c = _compile_yaml(tmp_path, STRIP, firmware)
    north = tuple(it.with_(param4=0.0) if it.command == mavlink.MAV_CMD_NAV_WAYPOINT and it.param1 > 0 else it
                  for it in c.items)
    sim = simulate(replace(c, items=north, parts=(north,)))
    off = [_off_line_deg(p.heading_deg) for p in sim.photos]
    assert off
    if flown:
        assert all(a > 89.9 for a in off)
    else:
        assert all(a < 0.01 for a in off)
