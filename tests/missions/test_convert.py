"""`wiris mission convert IN -o OUT` on real public files (tests/data): .plan <-> .waypoints keep every item
(pymavlink's MAVWPLoader reads what it writes), fence and rally go where the target holds them, GeoJSON and
KML draw them; bad input and refused conversions exit 1 with a located message and write nothing."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner
from lxml import etree

from missions.emit.items import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, MissionItem
from missions.formats.planfile import load_plan_file, write_plan
from missions.formats.wpl import load_wpl_file
from wiris_tools.cli import cli

DATA = Path(__file__).resolve().parents[1] / "data"
MISSION_WPL = ["ardupilot_inf_loop.txt", "dronekit_mpmission.txt", "dronekit_save_mission_no_home.txt",
               "ardupilot_copter_mission_CHIAI.txt", "mavsdk_mission_planner_sample.txt"]


def same(a: list[MissionItem], b: list[MissionItem]) -> bool:
    """Items equal field by field (NaN equal to NaN); `current` is no part of a file's mission (QGC drops it)."""
    return [repr(it.with_(current=0)) for it in a] == [repr(it.with_(current=0)) for it in b]


def run(*args):
    return CliRunner().invoke(cli, ["mission", "convert", *map(str, args)])


@pytest.mark.parametrize("name", MISSION_WPL)
def test_waypoints_to_plan_and_back_keep_every_item(tmp_path, name):
    src = DATA / name
    read = load_wpl_file(src)
    r = run(src, "-o", tmp_path / "m.plan")
    assert r.exit_code == 0, r.output
    assert f"wrote {tmp_path / 'm.plan'}: {len(read.items)} mission items" in r.output
    assert all(f"warning: {n}" in r.output for n in read.notes)
    plan = load_plan_file(tmp_path / "m.plan")
    # a .plan always has a plannedHomePosition: QGC writes [0, 0, 0] for none
    assert same(plan.items, read.items) and plan.home == pytest.approx(read.home or (0, 0, 0))
    r = run(tmp_path / "m.plan", "-o", tmp_path / "back.waypoints")
    assert r.exit_code == 0, r.output
    back = load_wpl_file(tmp_path / "back.waypoints")
    assert same(back.items, read.items) and back.notes == ()          # the repaired file needs no repair
    from pymavlink import mavwp

    loader = mavwp.MAVWPLoader()
    assert loader.load(str(tmp_path / "back.waypoints")) == len(read.items) + 1    # our home row 0 first


def test_plan_to_waypoints_keeps_the_mission_and_home(tmp_path):
    src = DATA / "mavsdk_qgroundcontrol_sample.plan"
    r = run(src, "-o", tmp_path / "m.waypoints", "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.output) == {"file": str(tmp_path / "m.waypoints"), "items": {"mission": 6}, "warnings": []}
    plan, back = load_plan_file(src), load_wpl_file(tmp_path / "m.waypoints")
    assert same(back.items, plan.items) and back.home == pytest.approx(plan.home, abs=1e-7)


def test_a_fence_wpl_becomes_the_plans_geofence_and_back(tmp_path):
    src = DATA / "ardupilot_rover_bendyruler_fence.txt"
    fence = load_wpl_file(src).items
    assert run(src, "-o", tmp_path / "f.plan", "--firmware", "ardupilot").exit_code == 0
    plan = load_plan_file(tmp_path / "f.plan")
    assert plan.items == [] and plan.firmware == 3
    assert [(it.command, it.x, it.y, it.param1) for it in plan.fence] == \
        [(it.command, it.x, it.y, it.param1) for it in fence]
    doc = json.loads((tmp_path / "f.plan").read_text())
    assert [len(p["polygon"]) for p in doc["geoFence"]["polygons"]] == [8]
    assert [c["circle"]["radius"] for c in doc["geoFence"]["circles"]] == [20, 20]
    r = run(tmp_path / "f.plan", "-o", tmp_path / "f.txt")
    assert r.exit_code == 0 and "10 fence items" in r.output
    again = load_wpl_file(tmp_path / "f.txt")
    assert again.mission_type == MISSION_TYPE_FENCE and again.home is None
    assert [(it.command, it.x, it.y, it.param1) for it in again.items] == \
        [(it.command, it.x, it.y, it.param1) for it in fence]


def full_plan(tmp_path) -> Path:
    p = tmp_path / "full.plan"
    items = [MissionItem(command=22, x=473977507, y=85456075, z=30), MissionItem(command=16, x=473987507,
                                                                                   y=85466075, z=30)]
    fence = [MissionItem(command=5003, param1=150.0, x=473977507, y=85456075, mission_type=MISSION_TYPE_FENCE)]
    rally = [MissionItem(command=5100, frame=3, x=473967507, y=85446075, z=20, mission_type=MISSION_TYPE_RALLY)]
    p.write_text(write_plan(items, (47.3977507, 8.5456075, 488.0), firmware="px4", vehicle="copter",
                            fence=fence, rally=rally))
    return p


def test_a_plan_with_fence_and_rally_goes_to_waypoints_one_list_at_a_time(tmp_path):
    src = full_plan(tmp_path)
    out = tmp_path / "m.waypoints"
    r = run(src, "-o", out)
    assert r.exit_code == 1 and f"error: {out}: a WPL 110 file holds one list" in r.output
    assert "2 mission, 1 fence, 1 rally" in r.output and "--type" in r.output and not out.exists()
    for kind, mission_type in (("mission", 0), ("fence", MISSION_TYPE_FENCE), ("rally", MISSION_TYPE_RALLY)):
        r = run(src, "-o", tmp_path / f"{kind}.txt", "--type", kind)
        assert r.exit_code == 0, r.output
        assert load_wpl_file(tmp_path / f"{kind}.txt").mission_type == mission_type


def test_geojson_and_kml_draw_mission_fence_and_rally(tmp_path):
    src = full_plan(tmp_path)
    assert run(src, "-o", tmp_path / "m.geojson").exit_code == 0
    kinds = [f["properties"]["kind"] for f in json.loads((tmp_path / "m.geojson").read_text())["features"]]
    assert kinds == ["home", "waypoint", "waypoint", "path", "fence", "rally"]
    fence = json.loads((tmp_path / "m.geojson").read_text())["features"][4]
    ring = fence["geometry"]["coordinates"][0]
    assert len(ring) == 73 and ring[0] == ring[-1] and fence["properties"]["radius_m"] == 150
    assert run(src, "-o", tmp_path / "m.kml").exit_code == 0
    doc = etree.parse(str(tmp_path / "m.kml"))
    names = doc.xpath("//k:Placemark/k:name/text()", namespaces={"k": "http://www.opengis.net/kml/2.2"})
    assert names == ["path", "home", "1 MAV_CMD_NAV_TAKEOFF", "2 MAV_CMD_NAV_WAYPOINT", "fence inclusion",
                     "rally point 0"]
    # a real QGC fence file, drawn
    assert run(DATA / "qgc_ce_geofence_rd_2.plan", "-o", tmp_path / "q.kml").exit_code == 0
    doc = etree.parse(str(tmp_path / "q.kml"))
    assert len(doc.xpath("//k:Polygon", namespaces={"k": "http://www.opengis.net/kml/2.2"})) == 2


@pytest.mark.parametrize("make,args,where,text", [
    (lambda d: d / "a.plan", ["-o", "OUT/x.yaml"], "OUT/x.yaml", "cannot write a '.yaml' file"),
    (lambda d: d / "plan.yaml", ["-o", "OUT/x.plan"], "IN", "compile a capture plan"),
    (lambda d: d / "a.plan", ["-o", "IN"], "IN", "the output is the input file"),
    (lambda d: d / "a.plan", ["-o", "OUT/x.plan", "--type", "rally"], "IN", "holds no rally items"),
    (lambda d: d / "dup.txt", ["-o", "OUT/x.plan"], "IN:4", "row index 1 appears twice"),
    (lambda d: d / "broken.plan", ["-o", "OUT/x.waypoints"], "IN:1:2", "not valid JSON"),
    (lambda d: d / "empty.plan", ["-o", "OUT/x.waypoints"], "IN", "holds no mission, fence or rally items"),
    (lambda d: d / "a.plan", ["-o", "OUT/missing/x.plan"], "OUT/missing/x.plan", "cannot write"),
])
def test_bad_input_and_refused_conversions_write_nothing(tmp_path, make, args, where, text):
    src_dir, out_dir = tmp_path / "in", tmp_path / "out"
    src_dir.mkdir()
    out_dir.mkdir()
    shutil.copy(DATA / "mavsdk_qgroundcontrol_sample.plan", src_dir / "a.plan")
    shutil.copy(DATA / "qgc_ce_geofence_rd_2.plan", src_dir / "empty.plan")
    (src_dir / "empty.plan").write_text((src_dir / "empty.plan").read_text().replace('"inclusion": true', '"x": 1')
                                        .replace('"polygons": [', '"polygons": [], "old": ['))
    (src_dir / "plan.yaml").write_text("version: 1\n")
    (src_dir / "broken.plan").write_text("{]")
    lines = (DATA / "dronekit_mpmission.txt").read_text().splitlines(keepends=True)
    (src_dir / "dup.txt").write_text("".join(lines[:3] + [lines[2]] + lines[3:]))
    src = make(src_dir)
    args = [str(src) if a == "IN" else a.replace("OUT", str(out_dir)) for a in args]
    before = sorted(p.name for p in src_dir.iterdir())
    r = run(src, *args)
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    where = where.replace("IN", str(src)).replace("OUT", str(out_dir))
    assert f"error: {where}: " in r.output and text in r.output and "hint:" in r.output, r.output
    assert list(out_dir.iterdir()) == [] and sorted(p.name for p in src_dir.iterdir()) == before


def test_mavsdk_imports_the_conversion_of_a_qgc3_save_it_refuses(tmp_path):
    """MAVSDK's QGC importer refuses the 3.x save (its geoFence version 1); converted to a current .plan, the
    same mission imports, item for item."""
    import mission_peers

    src = DATA / "qgc3_devguide_mission.plan"
    assert not mission_peers.mavsdk_import_plan(src.read_text(), tmp_path / "a")["ok"]
    assert run(src, "-o", tmp_path / "new.plan").exit_code == 0
    res = mission_peers.mavsdk_import_plan((tmp_path / "new.plan").read_text(), tmp_path / "b")
    assert res["ok"], res.get("error")
    assert [(it.command, it.x, it.y, it.z) for it in res["mission"]] == \
        [(it.command, it.x, it.y, it.z) for it in load_plan_file(src).items]
