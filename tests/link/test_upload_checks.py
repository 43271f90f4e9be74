"""`wiris mission upload`'s checks against the project's vehicle_sim on real UDP sockets (127.0.0.1), both
firmwares: a file made for the other firmware is refused (--force uploads it), a capture plan compiles for the
vehicle, a fence saved as WPL goes up as a fence only with --type fence, a too-big mission points at the part
files the compiler wrote, and the readers' repairs are printed as warnings."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from missions.emit.items import MISSION_TYPE_FENCE, MissionItem
from missions.formats.planfile import write_plan
from missions.formats.wpl import load_wpl_file
from wiris_tools.cli import cli
from wiris_tools.readback import compare_items
from wiris_tools.transfer import split_files_beside
from wiris_tools.vehicle_sim import VehicleSim

DATA = Path(__file__).resolve().parents[1] / "data"
ITEMS = [MissionItem(command=22, param1=15, param4=math.nan, x=473977507, y=85456075, z=50),
         MissionItem(command=16, param4=math.nan, x=473977711, y=85466122, z=50),
         MissionItem(command=20, frame=2)]
HOME = (47.3977507, 8.5456075, 488.9)
OTHER = {"px4": "ardupilot", "ardupilot": "px4"}
LABEL = {"px4": "PX4", "ardupilot": "ArduPilot"}

TWO_FIRMWARE_PLAN = """version: 1
name: two-fw
vehicle: {firmware: FIRMWARE, frame: copter, speed_mps: 5}
home: {lat: 50.1098, lon: 14.5002, alt_amsl_m: 262}
payloads:
  thermal: {camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 101}
mission:
  - takeoff: {alt_m: 30}
  - waypoint: {lat: 50.1105, lon: 14.5040, alt_m: 30, hold_s: 5, capture: thermal}
  - rtl: {}
"""


def run(*args):
    return CliRunner().invoke(cli, list(args))


def url(sim) -> str:
    return f"udpout:127.0.0.1:{sim.port}"


@pytest.mark.parametrize("vehicle", ["px4", "ardupilot"])
def test_a_plan_for_the_other_firmware_is_refused_and_force_uploads_it(tmp_path, vehicle):
    made_for = OTHER[vehicle]
    plan = tmp_path / "m.plan"
    plan.write_text(write_plan(ITEMS, HOME, firmware=made_for, vehicle="copter"))
    with VehicleSim(flavour=vehicle, heartbeat_s=0.2) as sim:
        r = run("mission", "upload", str(plan), "--connect", url(sim))
        assert r.exit_code == 1 and "Traceback" not in r.output
        assert f"{plan}: the file was made for {LABEL[made_for]} but system 1 reports {LABEL[vehicle]}" in r.output
        assert "--force" in r.output and "hint:" in r.output
        assert sim.stats["uploads"] == 0 and sim.items() == []
        r = run("mission", "upload", str(plan), "--connect", url(sim), "--force")
        assert r.exit_code == 0, r.output
        assert "note: uploaded with --force: the file was made for" in r.output
        held = sim.items()
    compare_items(ITEMS, held[1:] if vehicle == "ardupilot" else held)


@pytest.mark.parametrize("vehicle", ["px4", "ardupilot"])
def test_a_plan_for_this_firmware_or_for_none_uploads(tmp_path, vehicle):
    for firmware in (vehicle, None):     # None: firmwareType 0 (generic), which says nothing to check
        plan = tmp_path / f"{firmware}.plan"
        plan.write_text(write_plan(ITEMS, HOME, firmware=firmware, vehicle="copter"))
        with VehicleSim(flavour=vehicle) as sim:
            r = run("mission", "upload", str(plan), "--connect", url(sim))
            assert r.exit_code == 0, r.output
            assert "note:" not in r.output


@pytest.mark.parametrize("vehicle", ["px4", "ardupilot"])
def test_a_capture_plan_compiles_for_the_vehicle(tmp_path, vehicle):
    from missions.compile import compile_plan

    plan = tmp_path / "two.yaml"
    plan.write_text(TWO_FIRMWARE_PLAN.replace("FIRMWARE", OTHER[vehicle]))
    expected = compile_plan(str(plan), firmware=vehicle)
    with VehicleSim(flavour=vehicle) as sim:
        r = run("mission", "upload", str(plan), "--connect", url(sim), "--verify")
        assert r.exit_code == 0, r.output
        assert f"note: compiled for {LABEL[vehicle]}, the firmware the vehicle reports" in r.output
        held = sim.items()
        compare_items(list(expected.items), held[1:] if vehicle == "ardupilot" else held)
        # naming the other firmware on purpose is a mismatch like a file's
        r = run("mission", "upload", str(plan), "--connect", url(sim), "--firmware", OTHER[vehicle])
        assert r.exit_code == 1 and f"made for {LABEL[OTHER[vehicle]]}" in r.output and "--force" in r.output


@pytest.mark.parametrize("vehicle", ["px4", "ardupilot"])
def test_a_fence_saved_as_wpl_uploads_as_a_fence_only(tmp_path, vehicle):
    fence_file = tmp_path / "fence.txt"
    shutil.copy(DATA / "ardupilot_rover_bendyruler_fence.txt", fence_file)
    with VehicleSim(flavour=vehicle) as sim:
        r = run("mission", "upload", str(fence_file), "--connect", url(sim))
        assert r.exit_code == 1 and "the file holds a fence list (10 rows), not a mission" in r.output
        assert "--type fence" in r.output and sim.stats["uploads"] == 0
        r = run("mission", "upload", str(fence_file), "--type", "fence", "--connect", url(sim), "--verify")
        assert r.exit_code == 0, r.output
        assert "uploaded 10 fence items" in r.output
        compare_items(load_wpl_file(fence_file).items, sim.items(MISSION_TYPE_FENCE))
        assert sim.items() == []
        mission = tmp_path / "m.waypoints"
        shutil.copy(DATA / "dronekit_mpmission.txt", mission)
        r = run("mission", "upload", str(mission), "--type", "fence", "--connect", url(sim))
        assert r.exit_code == 1 and "holds a mission list" in r.output and "hint:" in r.output


def test_repairs_are_warned_and_the_repaired_mission_is_uploaded(tmp_path):
    src = tmp_path / "inf_loop.txt"
    shutil.copy(DATA / "ardupilot_inf_loop.txt", src)
    with VehicleSim(flavour="ardupilot") as sim:
        r = run("mission", "upload", str(src), "--connect", url(sim), "--verify")
        assert r.exit_code == 0, r.output
        assert f"warning: {src}:5: row index 4 read as 3" in r.output
        assert [it.command for it in sim.items()] == [16, 19, 177, 16]


def compiled_in_parts(tmp_path) -> Path:
    """A survey compiled with a 40-item limit: NAME.plan holds it whole, NAME.sortie1..N.plan the sorties."""
    from missions.compile import compile_plan
    from missions.formats.outputs import write_outputs

    shutil.copy(Path(__file__).resolve().parents[1] / "missions" / "plans" / "areas" / "field.geojson", tmp_path)
    plan = tmp_path / "big.yaml"
    plan.write_text("""version: 1
name: big
vehicle: {firmware: px4, frame: copter, speed_mps: 6, max_mission_items: 40}
home: {lat: 50.1098, lon: 14.5002, alt_amsl_m: 262}
payloads:
  thermal: {camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 101}
mission:
  - takeoff: {alt_m: 40}
  - survey: {area: field.geojson, payloads: [thermal], altitude_m: 60, overlap: {front: 80, side: 70}}
  - rtl: {}
""")
    write_outputs(compile_plan(str(plan)), tmp_path / "out")
    return tmp_path / "out" / "big.plan"


def test_a_mission_too_big_for_the_vehicle_points_at_its_part_files(tmp_path):
    whole = compiled_in_parts(tmp_path)
    parts = split_files_beside(whole)
    assert len(parts) >= 3 and [p.name for p in parts] == [f"big.sortie{k}.plan" for k in range(1, len(parts) + 1)]
    with VehicleSim(flavour="px4", item_limit=40) as sim:
        r = run("mission", "upload", str(whole), "--connect", url(sim))
        assert r.exit_code == 1 and "MAV_MISSION_NO_SPACE" in r.output
        assert ", ".join(p.name for p in parts) in r.output and "one at a time" in r.output
        r = run("mission", "upload", str(parts[0]), "--connect", url(sim))
        assert r.exit_code == 0, r.output
    with VehicleSim(flavour="px4", item_limit=10) as sim:   # fewer than a part: split it finer
        r = run("mission", "upload", str(parts[0]), "--connect", url(sim))
        assert r.exit_code == 1 and "max_mission_items" in r.output and "big.sortie2.plan" not in r.output


def test_a_too_big_file_without_parts_says_how_to_get_them(tmp_path):
    plan = tmp_path / "m.plan"
    plan.write_text(write_plan(ITEMS * 4, HOME, firmware="px4", vehicle="copter"))
    with VehicleSim(flavour="px4", item_limit=5) as sim:
        r = run("mission", "upload", str(plan), "--connect", url(sim))
    assert r.exit_code == 1 and "no room for 12 mission items" in r.output and "max_mission_items" in r.output


def test_split_files_beside_finds_parts_and_sorties_in_order(tmp_path):
    for name in ("a.plan", "a.part10.plan", "a.part2.plan", "a.sortie1.plan", "a.part1.waypoints", "ab.part1.plan",
                 "a.partx.plan"):
        (tmp_path / name).write_text("")
    assert [p.name for p in split_files_beside(tmp_path / "a.plan")] == ["a.part2.plan", "a.part10.plan",
                                                                         "a.sortie1.plan"]
    assert [p.name for p in split_files_beside(tmp_path / "a.part2.plan")] == ["a.part10.plan", "a.sortie1.plan"]
    assert [p.name for p in split_files_beside(tmp_path / "a.waypoints")] == ["a.part1.waypoints"]
    assert [p.name for p in split_files_beside(tmp_path / "a.yaml")] == ["a.part2.plan", "a.part10.plan",
                                                                        "a.sortie1.plan"]
