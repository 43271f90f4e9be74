"""`wiris mission upload` / `download` through click's CliRunner against vehicle_sim on 127.0.0.1:
.plan, .waypoints and capture plans, fence lists, --verify, --json, signing, and every way it can
go wrong (exit 1 with a located message, nothing written)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from missions.emit.items import MISSION_TYPE_FENCE, MissionItem
from missions.formats.planfile import load_plan, write_plan
from missions.formats.wpl import load_wpl, write_wpl
from wiris_tools.cli import cli
from wiris_tools.readback import compare_items
from wiris_tools.vehicle_sim import VehicleSim
import corpus

ROOT = Path(__file__).resolve().parents[2]
CORPUS = corpus.PLANS

ITEMS = [MissionItem(command=22, param1=15, param4=math.nan, x=473977507, y=85456075, z=50),
         MissionItem(command=16, param4=math.nan, x=473977711, y=85466122, z=50),
         MissionItem(command=2000, frame=2, param3=1),
         MissionItem(command=20, frame=2)]
FENCE = [MissionItem(command=5003, frame=0, param1=300.0, x=473977507, y=85456075, mission_type=MISSION_TYPE_FENCE)]
HOME = (47.3977507, 8.5456075, 488.9)


def run(*args):
    return CliRunner().invoke(cli, list(args))


@pytest.fixture
def plan_file(tmp_path):
    p = tmp_path / "m.plan"
    p.write_text(write_plan(ITEMS, HOME, firmware="px4", vehicle="copter", fence=FENCE))
    return p


@pytest.mark.parametrize("flavour", ["px4", "ardupilot"])
def test_upload_plan_verified_json(tmp_path, flavour):
    plan_file = tmp_path / "m.plan"     # made for the vehicle's firmware: another is refused (test_firmware_check)
    plan_file.write_text(write_plan(ITEMS, HOME, firmware=flavour, vehicle="copter", fence=FENCE))
    with VehicleSim(flavour=flavour, heartbeat_s=0.2) as sim:
        r = run("mission", "upload", str(plan_file), "--connect", f"udpout:127.0.0.1:{sim.port}", "--verify",
                "--json")
        assert r.exit_code == 0, r.output
        summary = json.loads(r.output)
        held = sim.items()
    assert summary["verified"] is True and summary["target_system"] == 1
    if flavour == "ardupilot":
        # ArduPilot's item 0 is home: the plan's plannedHomePosition goes there.
        assert summary["home_row"] and summary["items"] == 5
        assert (held[0].x, held[0].y, held[0].z) == (473977507, 85456075, pytest.approx(488.9, abs=1e-4))
        held = held[1:]
    compare_items(ITEMS, held)


def test_upload_fence_from_plan(plan_file):
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", str(plan_file), "--type", "fence", "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert r.exit_code == 0, r.output
        assert "uploaded 1 fence items" in r.output
        compare_items(FENCE, sim.items(MISSION_TYPE_FENCE))
        assert sim.items() == []


@pytest.mark.parametrize("flavour", ["px4", "ardupilot"])
def test_download_plan_and_waypoints(tmp_path, flavour):
    with VehicleSim(flavour=flavour) as sim:
        stored = ITEMS if flavour == "px4" else [ITEMS[1].with_(frame=0, z=488.9)] + ITEMS
        sim.set_items(stored)
        sim.set_items(FENCE, MISSION_TYPE_FENCE)
        url = f"udpout:127.0.0.1:{sim.port}"
        r1 = run("mission", "download", "--connect", url, "-o", str(tmp_path / "got.plan"))
        r2 = run("mission", "download", "--connect", url, "-o", str(tmp_path / "got.waypoints"), "--json")
    assert r1.exit_code == 0 and r2.exit_code == 0, r1.output + r2.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["got.plan", "got.waypoints"]  # no temporary file left
    items, fence, rally, home = load_plan(tmp_path / "got.plan")
    compare_items(ITEMS, items)
    compare_items(FENCE, fence)
    assert rally == []
    wp_items, wp_home = load_wpl(tmp_path / "got.waypoints")
    compare_items(ITEMS, wp_items)
    if flavour == "ardupilot":
        assert home == wp_home == pytest.approx((47.3977711, 8.5466122, 488.9))
    assert json.loads(r2.output)["items"] == {"mission": 4}


def test_upload_waypoints_file(tmp_path):
    f = tmp_path / "m.waypoints"
    f.write_text(write_wpl(ITEMS, HOME))
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", str(f), "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert r.exit_code == 0, r.output
        compare_items(ITEMS, sim.items())


def test_upload_capture_plan_compiles_on_the_fly():
    from missions.compile import compile_plan

    plan = ROOT / "examples" / "waypoint-inspection.yaml"      # an ArduPilot plan
    compiled = compile_plan(str(plan))
    with VehicleSim(flavour="ardupilot") as sim:
        r = run("mission", "upload", str(plan), "--connect", f"udpout:127.0.0.1:{sim.port}", "--verify")
        assert r.exit_code == 0, r.output
        held = sim.items()
    assert (held[0].x, held[0].y) == (round(compiled.home[0] * 1e7), round(compiled.home[1] * 1e7))
    compare_items(list(compiled.items), held[1:])


def test_capture_plan_with_errors_is_refused(tmp_path):
    plan = ROOT / "examples" / "waypoint-inspection.yaml"
    with VehicleSim(flavour="px4") as sim:
        # the plan changes a camera setting in flight, which PX4 cannot do: a located PlanError
        r = run("mission", "upload", str(plan), "--firmware", "px4", "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert r.exit_code == 1 and "waypoint-inspection.yaml:" in r.output and "Traceback" not in r.output
        assert "hint:" in r.output
        assert sim.stats["uploads"] == 0


def test_broken_plan_is_refused_before_connecting():
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", str(CORPUS / "qgroundcontrol_sample_wrong_mission_version.plan"),
                "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert r.exit_code == 1
        assert "mission.version" in r.output and "Traceback" not in r.output and "hint:" in r.output
        assert sim.stats["uploads"] == 0


def test_no_vehicle_is_exit_1_and_download_writes_nothing(tmp_path, plan_file):
    r = run("mission", "upload", str(plan_file), "--connect", "udpout:127.0.0.1:9", "--timeout", "0.3")
    assert r.exit_code == 1 and "no autopilot HEARTBEAT" in r.output and "hint:" in r.output
    out = tmp_path / "nothing.plan"
    r = run("mission", "download", "--connect", "udpout:127.0.0.1:9", "--timeout", "0.3", "-o", str(out))
    assert r.exit_code == 1 and not out.exists() and "hint:" in r.output


@pytest.mark.parametrize("out,text", [("m" * 250 + ".plan", "cannot write the file"),
                                      ("/proc/wiris.waypoints", "cannot write the file"),
                                      ("no-such-dir/got.plan", "directory does not exist")])
def test_download_checks_the_output_before_it_starts(tmp_path, out, text):
    target = tmp_path / out  # an absolute `out` stays itself
    with VehicleSim(flavour="px4") as sim:
        sim.set_items(ITEMS)
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(target))
        assert r.exit_code == 1 and text in r.output and "hint:" in r.output, r.output
        assert sim.stats["downloads"] == 0  # nothing fetched only to be lost at the last step
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


def strict_json(text: str):
    """json.loads refusing NaN and Infinity, which are not JSON (jq and JSON.parse refuse them)."""
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in JSON output"))


def test_download_json_of_a_nan_home_altitude_is_null(tmp_path):
    # ArduPilot's home row (item 0) as a vehicle may hold it before it has a position fix
    with VehicleSim(flavour="ardupilot") as sim:
        sim.set_items([MissionItem(command=16, frame=0, x=473977507, y=85456075, z=math.nan), *ITEMS])
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(tmp_path / "got.plan"),
                "--json")
    assert r.exit_code == 0, r.output
    assert strict_json(r.output)["home"] == [47.3977507, 8.5456075, None]
    assert load_plan(tmp_path / "got.plan")[3][:2] == (47.3977507, 8.5456075)


@pytest.mark.parametrize("flavour", ["px4", "ardupilot"])
@pytest.mark.parametrize("suffix,form", [(".plan", ".plan"), (".waypoints", "waypoint")])
def test_download_of_an_infinite_value_names_the_item_and_writes_nothing(tmp_path, flavour, suffix, form):
    # MAVLink floats carry +-inf and a vehicle stores what it was sent; neither file form can hold it
    held = [*ITEMS[:2], ITEMS[2].with_(param2=-math.inf), ITEMS[3]]
    if flavour == "ardupilot":
        held.insert(0, MissionItem(command=16, frame=0, x=473977507, y=85456075, z=488.9))  # the home row
    out = tmp_path / f"got{suffix}"
    with VehicleSim(flavour=flavour) as sim:
        sim.set_items(held)
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out))
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert f"{out}: mission item 3 (command 2000) has param2 = -inf, which a {form} file cannot hold" in r.output
    assert "hint: set a finite value" in r.output
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args,code,text", [
    (["mission", "upload", "m.kml", "--connect", "udpout:127.0.0.1:9"], 1, "unknown file type"),
    (["mission", "upload", "missing.plan", "--connect", "udpout:127.0.0.1:9"], 2, "does not exist"),
    (["mission", "download", "--connect", "udpout:127.0.0.1:9", "-o", "x.kml"], 2, ".plan or .waypoints"),
    (["mission", "upload", "m.waypoints", "--type", "fence", "--connect", "udpout:127.0.0.1:9"], 1, "not a fence"),
    (["mission", "upload", "m.plan", "--connect", "nonsense:1"], 1, "connection string"),
    (["mission", "upload", "m.yaml", "--type", "rally", "--connect", "udpout:127.0.0.1:9"], 1,
     "m.yaml: a capture plan compiles to a mission, not a rally list\n  hint: upload fence and rally from a .plan"),
    (["mission", "upload", "m.plan", "--type", "fence", "--connect", "udpout:127.0.0.1:9"], 1,
     "m.plan: the file holds no fence items\n  hint: check --type"),
    (["mission", "upload", str(ROOT / "examples" / "waypoint-inspection.yaml"), "--part", "2", "--connect",
      "udpout:127.0.0.1:9"], 1, "--sortie 2: the mission has 1 sortie(s)\n  hint: leave out --sortie"),
])
def test_usage_and_input_errors(tmp_path, monkeypatch, args, code, text):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.kml").write_text("<kml/>")
    (tmp_path / "m.yaml").write_text("name: m\n")
    (tmp_path / "m.waypoints").write_text(write_wpl(ITEMS, HOME))
    (tmp_path / "m.plan").write_text(write_plan(ITEMS, HOME, firmware="px4", vehicle="copter"))
    r = run(*args)
    assert r.exit_code == code, r.output
    assert text in r.output
    if code == 1:   # an input error (not a usage error) says what to do
        assert "\n  hint: " in r.output, r.output


def test_signed_vehicle_needs_the_key(tmp_path, plan_file):
    key = tmp_path / "key.txt"
    key.write_text("a passphrase for the link\n")
    from wiris_tools.signing import load_signing_key

    with VehicleSim(flavour="px4", signing_key=load_signing_key(key), heartbeat_s=0.2) as sim:   # plan_file's
        url = f"udpout:127.0.0.1:{sim.port}"
        r = run("mission", "upload", str(plan_file), "--connect", url, "--timeout", "0.6")
        assert r.exit_code == 1 and "signs its MAVLink 2 messages" in r.output and "--signing-key" in r.output
        wrong = tmp_path / "wrong.txt"
        wrong.write_text("not the passphrase")
        r = run("mission", "upload", str(plan_file), "--connect", url, "--timeout", "0.6", "--signing-key", str(wrong))
        assert r.exit_code == 1 and "no autopilot HEARTBEAT" in r.output
        r = run("mission", "upload", str(plan_file), "--connect", url, "--signing-key", str(key), "--verify")
        assert r.exit_code == 0, r.output
        assert sim.link.stats["rejected_signature"] > 0


class LossyFenceSim(VehicleSim):
    """A vehicle whose answer to the request for fence item 2 never gets through the radio."""

    def _handle(self, msg):
        if msg.get_type() == "MISSION_REQUEST_INT" and msg.mission_type == MISSION_TYPE_FENCE and msg.seq == 2:
            return
        super()._handle(msg)


class NoFenceSim(VehicleSim):
    """ArduPilot built without fences: GCS_Common.cpp handle_mission_request_list answers UNSUPPORTED."""

    def _handle(self, msg):
        if msg.get_type() == "MISSION_REQUEST_LIST" and msg.mission_type == MISSION_TYPE_FENCE:
            self._ack((msg.get_srcSystem(), msg.get_srcComponent()), 3, MISSION_TYPE_FENCE)  # UNSUPPORTED
            return
        super()._handle(msg)


SQUARE = [MissionItem(command=5001, frame=0, param1=4.0, x=473977507 + 1000 * (i % 2), y=85456075 + 1000 * (i // 2),
                      mission_type=MISSION_TYPE_FENCE) for i in range(4)]


def test_download_fails_and_writes_nothing_when_a_list_fails(tmp_path):
    out = tmp_path / "vehicle.plan"
    with LossyFenceSim(flavour="px4") as sim:
        sim.set_items(ITEMS)
        sim.set_items(SQUARE, MISSION_TYPE_FENCE)
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out))
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert "fence on system 1: the fence list could not be downloaded, so no file was written: item 2 of 4" in r.output
    assert "hint:" in r.output and "-o FILE.waypoints" in r.output
    assert list(tmp_path.iterdir()) == []


def test_download_of_a_vehicle_without_a_fence_list_writes_an_empty_one(tmp_path):
    out = tmp_path / "vehicle.plan"
    with NoFenceSim(flavour="ardupilot") as sim:
        sim.set_items([ITEMS[1].with_(frame=0, z=488.9), *ITEMS])
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out))
    assert r.exit_code == 0, r.output
    assert "note: fence not downloaded: the vehicle has no fence list" in r.output
    items, fence, rally, _home = load_plan(out)
    compare_items(ITEMS, items)
    assert fence == [] and rally == []


def test_download_from_a_mavlink1_vehicle_skips_fence_and_rally(tmp_path):
    out = tmp_path / "vehicle.plan"
    with VehicleSim(flavour="ardupilot", mavlink1=True) as sim:
        sim.set_items([ITEMS[1].with_(frame=0, z=488.9), *ITEMS])
        sim.set_items(SQUARE, MISSION_TYPE_FENCE)
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out), "--json")
    assert r.exit_code == 0, r.output
    summary = json.loads(r.output)
    assert summary["items"] == {"mission": 4, "fence": 0, "rally": 0}
    assert summary["notes"][0] == "fence not downloaded: the vehicle talks MAVLink 1, which cannot carry fence or " \
                                  "rally lists"
    compare_items(ITEMS, load_plan(out)[0])


HUGE = {"fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
        "mission": {"version": 2, "firmwareType": 12, "vehicleType": 2, "cruiseSpeed": 15, "hoverSpeed": 5,
                    "plannedHomePosition": [50.0, 14.0, 300],
                    "items": [{"type": "SimpleItem", "command": 16, "frame": 3, "params": [0, 0, 0, None, 50.001,
                                                                                           14.001, 40],
                               "autoContinue": True, "doJumpId": 1}]},
        "geoFence": {"version": 2, "polygons": [],
                     "circles": [{"circle": {"center": [50.0, 14.0], "radius": 1e39}, "inclusion": True,
                                  "version": 1}],
                     "breachReturn": [50.0, 14.0, 1e39]},
        "rallyPoints": {"version": 2, "points": [[50.0, 14.0, 1e39]]}}


@pytest.mark.parametrize("kind,where", [("rally", "rallyPoints.points[0][2]"),
                                        ("fence", "geoFence.circles[0].circle.radius")])
def test_upload_of_a_number_beyond_float32_is_refused_before_connecting(tmp_path, kind, where):
    doc = json.loads(json.dumps(HUGE))
    if kind == "rally":   # the fence is read first: keep only the number under test
        doc["geoFence"] = {"version": 2, "polygons": [], "circles": []}
    f = tmp_path / "huge.plan"
    f.write_text(json.dumps(doc))
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", str(f), "--type", kind, "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert sim.stats["requests"] == 0 and sim.link.stats.get("received", 0) == 0
    assert r.exit_code == 1 and f"{f}: {where}: 1E+39 is beyond the float32 range" in r.output, r.output
    assert "hint: radii and altitudes travel as float32" in r.output


@pytest.mark.parametrize("path,value", [("geoFence.breachReturn[2]", None), ("mission.plannedHomePosition[2]", 1e39),
                                        ("geoFence.circles[0].circle.radius", None)])
def test_plan_numbers_beyond_float32_are_located(path, value):
    doc = json.loads(json.dumps(HUGE))
    doc["rallyPoints"]["points"] = []
    if path != "geoFence.circles[0].circle.radius":
        doc["geoFence"]["circles"] = []
    if value is not None:
        doc["mission"]["plannedHomePosition"][2] = value
    from missions.errors import PlanError
    from missions.formats.planfile import read_plan

    with pytest.raises(PlanError) as err:
        read_plan(json.dumps(doc), "x.plan")
    assert err.value.where == f"x.plan: {path}" and "float32" in err.value.message and err.value.hint


def test_download_deadline_ends_a_vehicle_that_answers_rarely(tmp_path):
    from raw_peers import rarely_answering_vehicle, timed_call

    out = tmp_path / "vehicle.plan"
    veh, seen = rarely_answering_vehicle(65535)
    try:
        call = timed_call(lambda: run("mission", "download", "--connect", f"udpout:127.0.0.1:{veh.local_port}",
                                      "-o", str(out), "--deadline", "1.5"), limit_s=120)
    finally:
        veh.close()
    assert call.finished, "the download did not end"
    r = call.value
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert "did not finish within its deadline of 1.5 s (given)" in r.output and "of 65535 items had arrived" in r.output
    assert "hint: a slow or lossy link may need longer: raise it with --deadline SECONDS" in r.output
    assert list(tmp_path.iterdir()) == [] and seen["requests"] > 0


@pytest.mark.parametrize("value", ["0", "nan", "-3"])
def test_download_deadline_must_be_a_positive_number(value):
    r = run("mission", "download", "--connect", "udpout:127.0.0.1:9", "-o", "x.plan", "--deadline", value)
    assert r.exit_code == 2 and "--deadline" in r.output


@pytest.mark.parametrize("suffix", [".plan", ".waypoints"])
@pytest.mark.parametrize("hostile,text", [
    (MissionItem(command=65535, frame=255, x=2**31 - 1, y=85456075, z=3.4e38, autocontinue=255),
     "mission item 2 (command 65535): frame 255 is not a MAV_FRAME"),
    (MissionItem(command=16, x=2**31 - 1, y=85456075, z=50), "mission item 2 (MAV_CMD_NAV_WAYPOINT): latitude "
                                                             "214.7483647 is outside -90..90"),
    (MissionItem(command=16, x=473977507, y=85456075, z=3.4e38),
     "mission item 2 (MAV_CMD_NAV_WAYPOINT): altitude 3.4e+38 is not a real altitude"),
    (MissionItem(command=16, x=473977507, y=85456075, z=50, autocontinue=255),
     "mission item 2 (MAV_CMD_NAV_WAYPOINT): autocontinue 255 is neither 0 nor 1"),
])
def test_download_of_a_hostile_mission_names_the_item_and_writes_nothing(tmp_path, suffix, hostile, text):
    # what a download would write, upload must read: a vehicle's impossible values are refused before writing
    out = tmp_path / f"got{suffix}"
    with VehicleSim(flavour="px4") as sim:
        sim.set_items([ITEMS[1], hostile, ITEMS[3]])
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out))
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert f"{out}: {text}" in r.output and "file should not hold" in r.output and "hint: " in r.output, r.output
    assert list(tmp_path.iterdir()) == []


def test_download_of_a_hostile_home_writes_nothing(tmp_path):
    out = tmp_path / "got.plan"
    with VehicleSim(flavour="ardupilot") as sim:   # item 0 is ArduPilot's home
        sim.set_items([MissionItem(command=16, frame=0, x=-2**31, y=85456075, z=488.9), *ITEMS])
        r = run("mission", "download", "--connect", f"udpout:127.0.0.1:{sim.port}", "-o", str(out))
    assert r.exit_code == 1 and f"{out}: home latitude -214.748 is outside -90..90" in r.output, r.output
    assert list(tmp_path.iterdir()) == []


def test_upload_of_an_impossible_position_is_refused_before_connecting(tmp_path):
    doc = json.loads(write_plan(ITEMS, HOME, firmware="px4", vehicle="copter"))
    doc["mission"]["items"][1]["params"][4:6] = [95, 200]
    f = tmp_path / "far.plan"
    f.write_text(json.dumps(doc))
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", str(f), "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert sim.stats["requests"] == 0 and sim.link.stats.get("received", 0) == 0
    assert r.exit_code == 1 and f"{f}: mission.items[1].params[4]: MAV_CMD_NAV_WAYPOINT: latitude 95.0000000 is " \
                                "outside -90..90" in r.output, r.output
    assert "hint: a MAV_CMD_NAV_WAYPOINT needs a real position" in r.output
