"""no_fly, no_photo and exclude zones (missions.geometry.zones): no photo footprint touches a no-photo zone (the
camera goes off before and on again after, with each firmware's own items; hover and waypoint photos there are
dropped), no path (lines, turnarounds, transits, the way home) enters a no-fly zone, and the report's zone table
measures both on the re-flown items."""

from __future__ import annotations

from dataclasses import replace
import json
from pathlib import Path

from click.testing import CliRunner
import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon
import yaml

from missions.compile import compile_plan
from missions.emit.items import mavlink
from missions.errors import PlanError
from missions.geometry.zones import plan_zones
from missions.measure.flight import simulate
from missions.measure.report import footprint_ring, report
from missions.plan import parse_plan
from missions.plan.load import load_plan
from wiris_tools.cli import cli

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FIELD = [[50.1000, 14.5000], [50.1000, 14.5030], [50.1020, 14.5030], [50.1020, 14.5000]]
MIDDLE = [[50.1008, 14.5012], [50.1008, 14.5018], [50.1012, 14.5018], [50.1012, 14.5012]]
# between home (south) and the field: the straight way from home to the field and back crosses it
GATE = [[50.0990, 14.5000], [50.0990, 14.5030], [50.0994, 14.5030], [50.0994, 14.5000]]
HOME = {"lat": 50.0985, "lon": 14.5015, "alt_amsl_m": 250}


def _survey(**extra):
    return {"survey": {"area": FIELD, "payloads": ["thermal"], "altitude_m": 40,
                       "overlap": {"front": 80, "side": 70}, "angle_deg": 0, **extra}}


def _doc(steps, firmware="ardupilot", name="zones"):
    return {"version": 1, "name": name, "vehicle": {"firmware": firmware, "frame": "copter", "speed_mps": 4.5},
            "home": HOME,
            "payloads": {"thermal": {"camera": "wiris-pro", "imager": "thermal", "lens_mm": 13, "component_id": 100}},
            "mission": [{"takeoff": {"alt_m": 40}}, *steps, {"rtl": {}}]}


def _write(tmp_path, doc, name="zones"):
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def _compile(tmp_path, steps, **kw):
    path = _write(tmp_path, _doc(steps, **kw))
    return compile_plan(parse_plan(path.read_text(), str(path), tmp_path)), path


def _photographed_m2(compiled, zone_latlon, grow_m=0.0):
    """m² of the zone (grown by grow_m) under any footprint the re-flown items place — measured here, apart from
    the report's own table."""
    sim = simulate(compiled)
    lat = [p[0] for p in zone_latlon]
    lon = [p[1] for p in zone_latlon]
    x, y = sim.projection.to_xy(lat, lon)
    zone = Polygon(list(zip(x, y))).buffer(grow_m, join_style="mitre")
    fps = [Polygon(footprint_ring(ph, compiled.payload(n))) for ph in sim.photos for n in ph.payloads]
    return float(shapely.union_all(fps).intersection(zone).area) if fps else 0.0


def _trigger_items(compiled):
    return [it for it in compiled.items if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST]


# ------------------------------------------------------------------------------------------------ solar park

@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
def test_solar_park_photographs_none_of_its_substation(firmware):
    plan = load_plan(EXAMPLES / "solar-park.yaml")
    c = compile_plan(plan, firmware=firmware)
    (sub,) = plan_zones(plan)
    ring = list(sub.polygon.outer)
    # before: 1,092 of its 1,199 m² under the footprints of 70 photos (and photos_in_zones said 0)
    assert _photographed_m2(c, ring) == 0.0
    assert _photographed_m2(c, ring, grow_m=sub.margin_m) == 0.0     # not even its 2 m margin
    rep = report(c)
    (row,) = rep.areas[0].zones
    assert (row.kind, row.name, row.photographed_m2, row.flown_inside_m) == \
        ("exclude", "areas/substation.geojson", 0.0, 0.0)
    assert row.area_m2 == pytest.approx(1200, abs=5) and row.lost_m2 > 0 and row.margin_m == 2.0
    a = rep.areas[0]
    # coverage is measured on what can be covered; what the zone costs is in the table
    assert a.coverable_m2 < a.area_m2 and rep.coverage["thermal"] >= 0.995
    assert not any(w.code in ("zone_photographed", "zone_flown_over", "coverage_low") for w in rep.warnings)
    # the camera goes off mid-line and comes back with the firmware's own item: distance 0, then d with a photo now
    trig = _trigger_items(c)
    offs = [t for t in trig if t.param1 == 0]
    ons = [t for t in trig if t.param1 > 0]
    assert len(ons) == len(offs) and all(t.param3 == 1 for t in ons)
    legs = sum(1 for it in c.intent[0].camera_spans)
    assert len(ons) > legs                      # lines split around the substation
    json.dumps(rep.to_json())                   # the table is in the JSON report
    assert rep.to_json()["areas"][0]["zones"][0]["photographed_m2"] == 0.0


def test_the_report_measures_a_zone_photographed_when_the_items_ignore_it(tmp_path):
    # the same field compiled without its no-photo zone, measured against the zone: the table is measured on the
    # items, so it shows what they would photograph (and warns)
    with_zone, _ = _compile(tmp_path, [_survey(no_photo=[MIDDLE])])
    without, _ = _compile(tmp_path, [_survey()])
    blind = replace(without, areas=tuple(replace(a, zones=z.zones) for a, z in zip(without.areas, with_zone.areas)))
    (row,) = report(blind).areas[0].zones
    assert row.photographed_m2 > 1000
    assert any(w.code == "zone_photographed" for w in report(blind).warnings)
    (row,) = report(with_zone).areas[0].zones
    assert row.photographed_m2 == 0.0


# ------------------------------------------------------------------------------------------------ no_photo

def test_no_photo_zone_is_flown_over_with_the_camera_off(tmp_path):
    c, _ = _compile(tmp_path, [_survey(no_photo=[MIDDLE])])
    assert _photographed_m2(c, MIDDLE, grow_m=2.0) == 0.0
    rep = report(c)
    (row,) = rep.areas[0].zones
    assert row.kind == "no_photo" and row.flown_inside_m > 0 and row.photographed_m2 == 0.0 and row.lost_m2 > 0
    assert any(w.code == "zone_camera_off" for w in rep.warnings)
    assert not any(w.code == "zone_flown_over" for w in rep.warnings)    # may be flown over
    assert rep.coverage["thermal"] >= 0.995


def test_a_zone_margin_of_the_plans_own_keeps_footprints_that_far(tmp_path):
    c, _ = _compile(tmp_path, [_survey(no_photo=[MIDDLE], zone_margin_m=8)])
    assert _photographed_m2(c, MIDDLE, grow_m=8.0) == 0.0
    assert report(c).areas[0].zone_margin_m == 8.0


def test_px4_interval_triggering_keeps_out_too(tmp_path):
    c, _ = _compile(tmp_path, [_survey(no_photo=[MIDDLE], trigger="interval")], firmware="px4")
    assert _photographed_m2(c, MIDDLE) == 0.0
    offs = [it for it in c.items if it.command == mavlink.MAV_CMD_DO_TRIGGER_CONTROL and it.param1 == 0]
    assert len(offs) > len(c.intent[0].camera_spans)


def test_hover_photos_that_would_see_the_zone_are_dropped(tmp_path):
    c, _ = _compile(tmp_path, [_survey(no_photo=[MIDDLE], trigger="hover")])
    assert _photographed_m2(c, MIDDLE) == 0.0
    w = [w for w in c.warnings if w.code == "zone_photo_dropped"]
    assert len(w) == 1 and "dropped" in w[0].message


def test_a_waypoint_capture_that_would_see_the_zone_is_dropped(tmp_path):
    steps = [_survey(no_photo=[MIDDLE]), {"waypoint": {"lat": 50.1010, "lon": 14.5015, "alt_m": 40,
                                                       "capture": "thermal"}}]
    c, _ = _compile(tmp_path, steps)
    assert not any(it.command == mavlink.MAV_CMD_IMAGE_START_CAPTURE for it in c.items)
    assert any(w.code == "zone_photo_dropped" and "waypoint" in w.message for w in c.warnings)
    assert _photographed_m2(c, MIDDLE) == 0.0


def test_a_rededge_cannot_keep_out_of_a_no_photo_zone(tmp_path):
    doc = _doc([_survey(no_photo=[MIDDLE], payloads=["thermal", "ms"])])
    doc["payloads"]["thermal"]["component_id"] = 101
    doc["payloads"]["ms"] = {"camera": "rededge-mx"}
    path = _write(tmp_path, doc)
    with pytest.raises(PlanError) as e:
        compile_plan(parse_plan(path.read_text(), str(path), tmp_path))
    assert "RedEdge" in e.value.message and "zones.yaml:" in e.value.where and e.value.hint


# ------------------------------------------------------------------------------------------------ no_fly

def test_transits_and_the_way_home_go_round_a_no_fly_zone(tmp_path):
    straight, _ = _compile(tmp_path, [_survey()])
    c, _ = _compile(tmp_path, [_survey(no_fly=[GATE])])
    vias = [it for it in c.items if it.comment.startswith("via")]
    assert len(vias) >= 2                   # out and home again
    (row,) = report(c).areas[0].zones
    assert row.kind == "no_fly" and row.flown_inside_m == 0.0
    # measured apart from the table: the re-flown path from take-off to home never enters the zone
    sim = simulate(c)
    x, y = sim.projection.to_xy([p[0] for p in GATE], [p[1] for p in GATE])
    gate = Polygon(list(zip(x, y))).buffer(-0.05)
    assert shapely.LineString(sim.xy).intersection(gate).length == 0.0
    before = simulate(straight)
    assert shapely.LineString(before.xy).intersection(gate).length > 20     # the straight way crossed it


def test_a_no_fly_zone_round_home_cannot_be_avoided(tmp_path):
    ring = [[50.0980, 14.5005], [50.0980, 14.5025], [50.0995, 14.5025], [50.0995, 14.5005]]
    with pytest.raises(PlanError) as e:
        _compile(tmp_path, [_survey(no_fly=[ring])])
    assert "no_fly zone 'step 1 no_fly[0]'" in e.value.message and "inside" in e.value.message
    # one pass: the flight out and the way home both start inside it, each a located problem with a hint
    assert "zones.yaml:" in e.value.message and all(p.hint for p in e.value.problems)


def test_a_corridor_across_a_no_fly_zone_goes_round_it_with_the_camera_off(tmp_path):
    zone = [[50.0999, 14.5014], [50.0999, 14.5016], [50.1001, 14.5016], [50.1001, 14.5014]]
    corridor = {"corridor": {"line": [[50.1000, 14.5000], [50.1000, 14.5030]], "width_m": 40,
                             "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 80, "side": 60},
                             "no_fly": [zone]}}
    c, _ = _compile(tmp_path, [corridor])
    rep = report(c)
    (row,) = rep.areas[0].zones
    # photos may see a no-fly zone: the lines beside it do
    assert row.kind == "no_fly" and row.flown_inside_m == 0.0 and row.photographed_m2 > 0
    assert any(w.code == "zone_detour" for w in c.warnings)
    sim = simulate(c)
    x, y = sim.projection.to_xy([p[0] for p in zone], [p[1] for p in zone])
    core = Polygon(list(zip(x, y))).buffer(-0.05)
    assert shapely.LineString(sim.xy).intersection(core).length == 0.0


def test_a_way_round_that_does_not_exist_is_an_error_naming_the_zone(tmp_path):
    # a no-fly ring round the whole field: its lines cannot be reached from home
    outer = [[50.0996, 14.4990], [50.0996, 14.5040], [50.1024, 14.5040], [50.1024, 14.4990]]
    inner = [[50.0998, 14.4995], [50.0998, 14.5035], [50.1022, 14.5035], [50.1022, 14.4995]]
    (tmp_path / "ring.geojson").write_text(json.dumps({"type": "Polygon", "coordinates": [
        [[lon, lat] for lat, lon in outer + outer[:1]], [[lon, lat] for lat, lon in inner[::-1] + inner[-1:]]]}))
    with pytest.raises(PlanError) as e:
        _compile(tmp_path, [_survey(no_fly=["ring.geojson"])])
    assert "cannot be routed around no_fly zone 'ring.geojson'" in e.value.message and e.value.hint


def test_a_corridor_keeps_its_photos_out_of_a_no_photo_zone(tmp_path):
    zone = [[50.09995, 14.5014], [50.09995, 14.5016], [50.10005, 14.5016], [50.10005, 14.5014]]
    corridor = {"corridor": {"line": [[50.1000, 14.5000], [50.1000, 14.5030]], "width_m": 40,
                             "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 80, "side": 60},
                             "no_photo": [zone]}}
    c, _ = _compile(tmp_path, [corridor])
    assert _photographed_m2(c, zone, grow_m=2.0) == 0.0
    (row,) = report(c).areas[0].zones
    assert row.photographed_m2 == 0.0 and row.kind == "no_photo"


def test_plan_zones_lists_every_zone_with_its_kind(tmp_path):
    path = _write(tmp_path, _doc([_survey(no_fly=[GATE], no_photo=[MIDDLE], exclude=[MIDDLE])]))
    zones = plan_zones(load_plan(path))
    assert [(z.kind, z.name, z.step) for z in zones] == [
        ("no_fly", "step 1 no_fly[0]", 1), ("no_photo", "step 1 no_photo[0]", 1), ("exclude", "step 1 exclude[0]", 1)]
    assert [(z.keeps_path_out, z.keeps_photos_out) for z in zones] == [(True, False), (False, True), (True, True)]
    assert all(z.where.startswith(f"{path}:") for z in zones)


# ------------------------------------------------------------------------------------------------ bad input

BAD = {
    "no_fly_not_a_list": ({"no_fly": 5}, "no_fly"),
    "no_photo_two_points": ({"no_photo": [[[50.1, 14.5], [50.1, 14.501]]]}, "at least 3"),
    "exclude_missing_file": ({"exclude": ["nowhere.geojson"]}, "nowhere.geojson"),
    "no_fly_self_intersecting": ({"no_fly": [[[50.1, 14.5], [50.101, 14.501], [50.1, 14.501], [50.101, 14.5]]]},
                                 "intersects itself"),
    "zone_margin_negative": ({"zone_margin_m": -1}, "zone_margin_m"),
    "zone_margin_text": ({"zone_margin_m": "2 m"}, "zone_margin_m"),
    "no_photo_bad_point": ({"no_photo": [[[50.1, 14.5], [50.1, 14.501], [95, 14.5]]]}, "no_photo"),
}


@pytest.mark.parametrize("key", sorted(BAD))
def test_bad_zone_keys_exit_1_located_and_write_nothing(tmp_path, key):
    extra, fragment = BAD[key]
    path = _write(tmp_path, _doc([_survey(**extra)]), name=key)
    out = tmp_path / "out"
    out.mkdir()
    r = CliRunner().invoke(cli, ["mission", "compile", str(path), "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert "Traceback" not in r.output and f"{path.name}:" in r.output and "hint:" in r.output
    assert fragment in r.output
    assert list(out.iterdir()) == []


def test_a_round_no_fly_zone_of_many_vertices_is_still_gone_round(tmp_path):
    # a 30 m circle drawn with 720 points between home and the field: routed round a simpler outline containing it
    import math
    ring = [[50.0992 + 0.00027 * math.sin(t), 14.5015 + 0.00042 * math.cos(t)]
            for t in (2 * math.pi * k / 720 for k in range(720))]
    north = {"waypoint": {"lat": 50.1000, "lon": 14.5015, "alt_m": 40}}    # home, the circle, this: one line
    c, _ = _compile(tmp_path, [north, _survey(no_fly=[ring])])
    (row,) = report(c).areas[0].zones
    assert row.flown_inside_m == 0.0
    assert any(it.comment.startswith("via") for it in c.items)


def test_a_fixed_wing_is_told_to_shrink_its_acceptance_radius(tmp_path):
    doc = _doc([_survey(no_photo=[MIDDLE], turnaround_m=30, altitude_m=100, overlap={"front": 60, "side": 60})])
    doc["vehicle"] = {"firmware": "px4", "frame": "vtol", "speed_mps": 9}
    path = _write(tmp_path, doc)
    c = compile_plan(parse_plan(path.read_text(), str(path), tmp_path))
    w = next(w for w in c.warnings if w.code == "zone_camera_off")
    assert "NAV_ACC_RAD" in w.message and "WP_RADIUS" in w.message


@pytest.mark.parametrize("extra,fragment", [({"exclude": 5}, "exclude"), ({"no_photo": ["gone.kml"]}, "gone.kml"),
                                            ({"zone_margin_m": 1000}, "zone_margin_m")])
def test_bad_zone_keys_of_a_corridor_exit_1_located(tmp_path, extra, fragment):
    corridor = {"corridor": {"line": [[50.1000, 14.5000], [50.1000, 14.5030]], "width_m": 40,
                             "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 80, "side": 60}, **extra}}
    path = _write(tmp_path, _doc([corridor]))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(path), "-o", str(out)])
    assert r.exit_code == 1 and f"{path.name}:" in r.output and fragment in r.output and "hint:" in r.output
    assert not out.exists() or list(out.iterdir()) == []


# ------------------------------------------------------------------------------------------------ property

from hypothesis import given, settings, strategies as st  # noqa: E402

from missions.geometry.footprint import Footprint  # noqa: E402
from missions.geometry.zones import CameraPoint, keep_photos_out  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(st.floats(-60, 60), st.floats(-60, 60), st.floats(5, 40), st.floats(5, 40), st.floats(0, 179),
       st.floats(3, 12), st.integers(1, 3))
def test_no_position_with_the_camera_on_sees_the_zone(zx, zy, zw, zh, heading, trig, lines):
    # straight lines across a square with a rectangular zone somewhere: wherever the camera is on (not only where
    # the photos fall), a footprint along the line keeps clear of the zone
    import math
    fp = Footprint(20.0, 16.0)
    zone = shapely.box(zx, zy, zx + zw, zy + zh)
    d = (math.sin(math.radians(heading)), math.cos(math.radians(heading)))
    n = (d[1], -d[0])
    points, spans = [], []
    for k in range(lines):
        o = (k - lines // 2) * 15.0
        a = (-100 * d[0] + o * n[0], -100 * d[1] + o * n[1])
        b = (100 * d[0] + o * n[0], 100 * d[1] + o * n[1])
        spans.append((len(points), len(points) + 1))
        points += [CameraPoint(*a, "entry"), CameraPoint(*b, "exit")]
    cam = keep_photos_out(points, spans, zone, fp, trig, hover=False)
    centres = []
    for s0, s1 in cam.spans:
        line = np.array([(p.x, p.y) for p in cam.points[s0:s1 + 1]])
        for a, b in zip(line[:-1], line[1:]):
            t = np.linspace(0, 1, max(2, int(np.hypot(*(b - a)) / 0.25)))[:, None]
            centres.append(a + (b - a) * t)
    if not centres:
        return
    c = np.concatenate(centres)
    da, dc = np.array(d) * fp.along_m / 2, np.array(n) * fp.across_m / 2
    rings = np.stack([c - da - dc, c + da - dc, c + da + dc, c - da + dc, c - da - dc], axis=1)
    assert shapely.area(shapely.intersection(shapely.polygons(rings), zone)).max() < 1e-6
