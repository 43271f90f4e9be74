"""QGroundControl .plan reading and writing: every corpus file (good ones read, broken ones refused
with a location), exact round trips, fence and rally, hostile input, and MAVSDK's own QGC importer
reading what we write."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from missions.formats import planfile, wpl
from missions.errors import PlanError
from missions.formats.itemcheck import item_problem
from missions.emit.items import MISSION_TYPE_FENCE, MISSION_TYPE_RALLY, MissionItem
from missions.formats.planfile import load_plan, read_plan, write_plan
from missions.formats.wpl import load_wpl, read_wpl, write_wpl
import corpus

CORPUS = corpus.PLANS

# MAVSDK's mission_import_test.cpp expectations for its own samples: items (no home row) or the
# fragment of our error's location.
GOOD = {"qgroundcontrol_sample.plan": 6, "qgroundcontrol_sample_with_survey.plan": 13,
        "qgroundcontrol_sample_with_digicam_control.plan": 1}
BROKEN = {
    "qgroundcontrol_sample_with_structured_scan.plan": "mission.items[1].complexItemType",
    "qgroundcontrol_sample_with_survey_missing_items.plan": "mission.items[1].TransectStyleComplexItem.Items",
    "qgroundcontrol_sample_with_survey_wrong_version.plan": "mission.items[1].version",
    "qgroundcontrol_sample_without_mission.plan": "qgroundcontrol_sample_without_mission.plan",
    "qgroundcontrol_sample_wrong_mission_version.plan": "mission.version",
    "qgroundcontrol_sample_wrong_overall_version.plan": "version",
}


def test_corpus_is_covered():
    plans = {p.name for p in CORPUS.glob("*.plan")}
    assert plans == set(GOOD) | set(BROKEN)


@pytest.mark.parametrize("name", sorted(GOOD))
def test_good_corpus_plans_read(name):
    items, fence, rally, home = load_plan(CORPUS / name)
    assert len(items) == GOOD[name] and fence == [] and rally == []
    raw = json.loads((CORPUS / name).read_text())
    assert home == pytest.approx(tuple(raw["mission"]["plannedHomePosition"]))


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_broken_corpus_plans_are_refused_with_location(name):
    with pytest.raises(PlanError) as err:
        load_plan(CORPUS / name)
    assert err.value.where.startswith(str(CORPUS / name))
    assert err.value.where.endswith(BROKEN[name])
    assert err.value.hint


def test_survey_items_are_the_stored_transect_items():
    items, *_ = load_plan(CORPUS / "qgroundcontrol_sample_with_survey.plan")
    raw = json.loads((CORPUS / "qgroundcontrol_sample_with_survey.plan").read_text())
    stored = raw["mission"]["items"][1]["TransectStyleComplexItem"]["Items"]
    assert [it.command for it in items[1:1 + len(stored)]] == [s["command"] for s in stored]
    first = stored[0]["params"]
    assert items[1].x == round(first[4] * 1e7) and items[1].y == round(first[5] * 1e7)
    assert math.isnan(items[1].param4)   # null -> NaN


def test_sample_values_exactly():
    items, _, _, _ = load_plan(CORPUS / "qgroundcontrol_sample.plan")
    takeoff = items[0]
    assert (takeoff.command, takeoff.frame, takeoff.param1, takeoff.x, takeoff.y, takeoff.z) == \
        (22, 3, 15.0, 473977507, 85456075, 50.0)
    assert items[2].command == 2000 and items[2].frame == 2 and items[2].param3 == 1


def sample_items():
    return [MissionItem(command=22, param1=15, param4=math.nan, x=473977507, y=85456075, z=50),
            MissionItem(command=16, param4=math.nan, x=-335000001, y=-700000009, z=42.125, frame=0),
            MissionItem(command=2000, frame=2, param3=1, param4=0.1),
            MissionItem(command=206, frame=2, param1=25.5, param3=1),
            MissionItem(command=16, frame=10, x=1, y=-1, z=30),
            MissionItem(command=20, frame=2, autocontinue=0)]


def fence_items():
    poly = [MissionItem(command=5001, frame=0, param1=3, x=x, y=y, mission_type=MISSION_TYPE_FENCE)
            for x, y in ((470000000, 80000000), (470010000, 80000000), (470010000, 80010000))]
    return poly + [MissionItem(command=5004, frame=0, param1=25.5, x=470005000, y=80005000,
                               mission_type=MISSION_TYPE_FENCE)]


def rally_items():
    return [MissionItem(command=5100, frame=3, x=470002000, y=80002000, z=30, mission_type=MISSION_TYPE_RALLY)]


def same(a, b):
    return len(a) == len(b) and all(x.same_on_wire(y) for x, y in zip(a, b))


def test_round_trip_with_fence_rally_and_home():
    text = write_plan(sample_items(), (47.1, 8.2, 488.5), firmware="ardupilot", vehicle="copter",
                      fence=fence_items(), rally=rally_items(), cruise_speed=12)
    items, fence, rally, home = read_plan(text, "x.plan")
    assert same(items, sample_items()) and same(fence, fence_items()) and same(rally, rally_items())
    assert home == (47.1, 8.2, 488.5)
    doc = json.loads(text)
    assert (doc["fileType"], doc["version"], doc["mission"]["version"], doc["geoFence"]["version"],
            doc["rallyPoints"]["version"]) == ("Plan", 1, 2, 2, 2)
    assert doc["mission"]["firmwareType"] == 3 and doc["mission"]["vehicleType"] == 2
    assert doc["mission"]["cruiseSpeed"] == 12 and doc["mission"]["globalPlanAltitudeMode"] == 0
    assert doc["mission"]["items"][0]["params"][3] is None          # NaN as null, like QGC
    assert doc["geoFence"]["polygons"][0]["version"] == 1 and doc["geoFence"]["circles"][0]["inclusion"] is False


def test_writer_is_deterministic_and_sorted_like_qt():
    a = write_plan(sample_items(), None, firmware="px4", vehicle="plane")
    assert a == write_plan(sample_items(), None, firmware="px4", vehicle="plane")
    doc = json.loads(a)
    assert list(doc) == sorted(doc) and doc["mission"]["plannedHomePosition"] == [0, 0, 0]


def test_corpus_round_trip_is_exact():
    for name in GOOD:
        items, fence, rally, home = load_plan(CORPUS / name)
        again = read_plan(write_plan(items, home, firmware="px4", vehicle="copter", fence=fence, rally=rally))
        assert same(again[0], items) and again[3] == pytest.approx(home)


def test_file_form_writes_atomically(tmp_path):
    class Compiled:
        items = tuple(sample_items())
        home = (47.0, 8.0, 400.0)
        firmware = "px4"
        frame = "copter"
        speed_mps = 7.5

    target = tmp_path / "m.plan"
    text = write_plan(target, Compiled(), items=sample_items()[:2])
    assert target.read_text() == text and len(read_plan(text)[0]) == 2
    assert [p.name for p in tmp_path.iterdir()] == ["m.plan"]


def test_a_written_file_has_ordinary_permissions_or_keeps_those_it_replaces(tmp_path):
    # mkstemp's temporary file is 0600: downloads (atomic_write) came out readable by their owner only
    import os

    umask = os.umask(0o022)
    try:
        target = tmp_path / "m.plan"
        planfile.atomic_write(target, "{}")
        assert target.stat().st_mode & 0o777 == 0o644
        target.chmod(0o640)
        planfile.atomic_write(target, "{}\n")
        assert target.stat().st_mode & 0o777 == 0o640 and target.read_text() == "{}\n"
    finally:
        os.umask(umask)


@pytest.mark.parametrize("mutate,where", [
    (lambda d: d.__setitem__("fileType", "Mission"), "fileType"),
    (lambda d: d.pop("geoFence"), "x.plan"),
    (lambda d: d.pop("rallyPoints"), "x.plan"),
    (lambda d: d["geoFence"].__setitem__("version", 3), "geoFence.version"),
    (lambda d: d["rallyPoints"].pop("version"), "rallyPoints"),   # QGC refuses it too (RallyPointController::load)
    (lambda d: d["mission"]["items"][0].pop("autoContinue"), "mission.items[0]"),
    (lambda d: d["mission"]["items"][0].__setitem__("params", 5), "mission.items[0].params"),
    (lambda d: d["mission"]["items"][0].__setitem__("params", [0, 0, 0, 0, 49.2]), "mission.items[0].params"),
    (lambda d: d["mission"]["items"][0].__setitem__("command", "22"), "mission.items[0].command"),
    (lambda d: d["mission"]["items"][0].__setitem__("type", "FancyItem"), "mission.items[0].type"),
    (lambda d: d["mission"]["items"][1]["params"].__setitem__(4, "47.1"), "mission.items[1].params[4]"),
    (lambda d: d["mission"]["items"][1]["params"].__setitem__(4, 1e12), "mission.items[1].params[4]"),
    (lambda d: d["mission"]["items"][1]["params"].__setitem__(0, 1e300), "mission.items[1].params[0]"),
    (lambda d: d["mission"].__setitem__("plannedHomePosition", [95, 0, 0]), "mission.plannedHomePosition"),
    (lambda d: d["rallyPoints"]["points"].append([1, 2]), "rallyPoints.points[1]"),
    (lambda d: d["geoFence"]["polygons"][0]["polygon"].pop(), "geoFence.polygons[0]"),
    (lambda d: d["mission"]["items"].__setitem__(0, []), "mission.items[0]"),
])
def test_content_errors_name_their_location(mutate, where):
    doc = json.loads(write_plan(sample_items(), (1, 2, 3), firmware="px4", vehicle="copter",
                                fence=fence_items(), rally=rally_items()))
    mutate(doc)
    with pytest.raises(PlanError) as err:
        read_plan(json.dumps(doc), "x.plan")
    assert err.value.where.endswith(where), str(err.value)
    assert err.value.hint, str(err.value)


@pytest.mark.parametrize("text,where", [
    ("{ not json", "x.plan:1:3"),
    ("", "x.plan:1:1"),
    ("[1, 2]", "x.plan"),
    ("[" * 100000 + "]" * 100000, "x.plan"),
])
def test_syntax_and_hostile_input(text, where):
    with pytest.raises(PlanError) as err:
        read_plan(text, "x.plan")
    assert err.value.where == where
    assert err.value.hint, str(err.value)


def test_size_and_encoding_limits(tmp_path):
    with pytest.raises(PlanError, match="UTF-8") as err:
        read_plan(b'{"fileType": "Plan\xff"}', "x.plan")
    assert err.value.hint
    for name, load, size, hint in (("big.plan", load_plan, 65, "2000-item .plan is about 1 MB"),
                                   ("big.waypoints", load_wpl, 17, "65535 items is about 6 MB")):
        big = tmp_path / name
        with big.open("wb") as fh:
            fh.seek(size * 1024 * 1024)
            fh.write(b"\0")
        with pytest.raises(PlanError, match="larger than") as err:
            load(big)
        assert err.value.where == str(big) and hint in err.value.hint
    for missing, load in ((tmp_path / "missing.plan", load_plan), (tmp_path / "missing.waypoints", load_wpl)):
        with pytest.raises(PlanError, match="cannot read") as err:
            load(missing)
        assert err.value.where == str(missing) and "check the path" in err.value.hint


# Every float at its longest repr, every integer at its widest: the largest item either writer makes.
LONGEST = -1.2345678901234567e-300
WIDEST_ITEM = MissionItem(command=65535, frame=3, param1=LONGEST, param2=LONGEST, param3=LONGEST, param4=LONGEST,
                          x=-2**31, y=-2**31, z=LONGEST)


def test_a_full_mission_as_either_writer_writes_it_can_be_read_again():
    # A vehicle may hold 65535 items (the download writes them): the read limits must take that file.
    home = (LONGEST, LONGEST, LONGEST)
    one, two = (len(write_plan([WIDEST_ITEM] * n, home, firmware="ardupilot", vehicle="copter")) for n in (1, 2))
    assert one + (two - one) * (65535 - 1) <= planfile.MAX_PLAN_BYTES
    one, two = (len(write_wpl([WIDEST_ITEM] * n, home)) for n in (1, 2))
    assert one + (two - one) * (65534 - 1) <= wpl.MAX_WPL_BYTES


def test_a_plan_too_large_to_read_back_is_not_written(monkeypatch):
    # fence and rally lists (65535 items each) could outgrow the limit: write_plan refuses what it could not read
    fence = [MissionItem(command=5003, frame=0, param1=50.0, x=471000000, y=81000000,
                         mission_type=MISSION_TYPE_FENCE)] * 100
    text = write_plan([WIDEST_ITEM], None, firmware="ardupilot", vehicle="copter", fence=fence)
    monkeypatch.setattr(planfile, "MAX_PLAN_BYTES", len(text) - 1)
    with pytest.raises(PlanError, match="more than the 0 MB this tool reads back") as err:
        write_plan([WIDEST_ITEM], None, firmware="ardupilot", vehicle="copter", fence=fence)
    assert "save the mission alone as .waypoints" in err.value.hint


def _wpl(*rows: str) -> str:
    return "\n".join(["QGC WPL 110", "0\t1\t0\t16\t0\t0\t0\t0\t47.1\t8.2\t488.5\t1", *rows]) + "\n"


def _row(**fields) -> str:
    """Row 1 of a WPL 110 file, with some of its 12 fields replaced."""
    row = dict(index="1", current="0", frame="3", command="16", p1="0", p2="0", p3="0", p4="0", lat="47.3977507",
               lon="8.5456075", alt="50", auto="1")
    row.update(fields)
    return "\t".join(row.values())


def _plan(mutate) -> str:
    doc = json.loads(write_plan(sample_items(), (1, 2, 3), firmware="px4", vehicle="copter",
                                fence=fence_items(), rally=rally_items()))
    mutate(doc)
    return json.dumps(doc)


def _item(d, key, value):
    d["mission"]["items"][0][key] = value


def _param(d, k, value):
    d["mission"]["items"][0]["params"][k] = value


@pytest.mark.parametrize("read,make,where,hint", [
    # .waypoints (QGC WPL 110)
    (read_wpl, lambda: _wpl(_row(p1="abc")), "x.waypoints:3", "every field of a row is a number"),
    (read_wpl, lambda: _wpl(_row(lat="")), "x.waypoints:3", "INDEX CURRENT FRAME COMMAND"),
    (read_wpl, lambda: _wpl(_row(frame="3.5")), "x.waypoints:3", "without decimals"),
    (read_wpl, lambda: _wpl(_row(current="2")), "x.waypoints:3", "current and autocontinue are 0 or 1"),
    (read_wpl, lambda: _wpl(_row(index="0")), "x.waypoints:3", "give every row its own index"),
    (read_wpl, lambda: _wpl(_row(p2="1e39")), "x.waypoints:3", "float32"),
    (read_wpl, lambda: _wpl(_row(lat="300")), "x.waypoints:3", "latitude -90..90"),
    (read_wpl, lambda: _wpl(_row(frame="1", lat="300000")), "x.waypoints:3", "at most ±214748 m"),
    (read_wpl, lambda: _wpl(_row(frame="2", lat="3000000000")), "x.waypoints:3", "32-bit whole numbers"),
    (read_wpl, lambda: _wpl(*(_row(index=str(i)) for i in range(1, 65536))), "x.waypoints:65537",
     "split the file"),
    (read_wpl, lambda: _wpl("# caf\xe9").encode("latin-1"), "x.waypoints", "save the file as UTF-8"),
    (read_wpl, lambda: "QGC WPL 110\n" + "#" * wpl.MAX_WPL_BYTES, "x.waypoints", "about 6 MB"),
    (read_wpl, lambda: (_wpl() + "#" * wpl.MAX_WPL_BYTES).encode(), "x.waypoints", "about 6 MB"),
    (read_wpl, lambda: "QGC WPL 100\n", "x.waypoints:1", "only QGC WPL 110"),
    # .plan (QGroundControl)
    (read_plan, lambda: _plan(lambda d: _item(d, "command", "22")), "x.plan: mission.items[0].command",
     "without quotes"),
    (read_plan, lambda: _plan(lambda d: _param(d, 4, "47.1")), "x.plan: mission.items[0].params[4]",
     "without quotes"),
    (read_plan, lambda: _plan(lambda d: _item(d, "command", 22.5)), "x.plan: mission.items[0].command",
     "MAV_CMD number"),
    (read_plan, lambda: _plan(lambda d: _item(d, "frame", 256)), "x.plan: mission.items[0].frame",
     "MAV_FRAME number"),
    (read_plan, lambda: _plan(lambda d: _param(d, 0, 1e39)), "x.plan: mission.items[0].params[0]", "float32"),
    (read_plan, lambda: _plan(lambda d: _param(d, 4, 300)), "x.plan: mission.items[0].params[4]",
     "latitude -90..90"),
    (read_plan, lambda: _plan(lambda d: (_item(d, "frame", 1), _param(d, 5, 300000))),
     "x.plan: mission.items[0].params[5]", "at most ±214748 m"),
    (read_plan, lambda: _plan(lambda d: d["mission"]["items"].extend(d["mission"]["items"][:1] * 65530)),
     "x.plan: mission.items[65535]", "split the plan"),
    (read_plan, lambda: _plan(lambda d: d["rallyPoints"]["points"][0].__setitem__(2, math.inf)),
     "x.plan: rallyPoints.points[0][2]", "finite number"),
    (read_plan, lambda: _plan(lambda d: d["mission"].__setitem__("plannedHomePosition", [1, 2])),
     "x.plan: mission.plannedHomePosition", "[latitude, longitude, altitude AMSL]"),
    (read_plan, lambda: _plan(lambda d: d["mission"]["items"][0].pop("frame")), "x.plan: mission.items[0]",
     "add 'frame'"),
    (read_plan, lambda: b'{"fileType": "Plan", "x": "caf\xe9"}', "x.plan", "UTF-8"),
    (read_plan, lambda: " " * (planfile.MAX_PLAN_BYTES + 1), "x.plan", "about 1 MB"),
    (read_plan, lambda: b" " * (planfile.MAX_PLAN_BYTES + 1), "x.plan", "about 1 MB"),
    (read_plan, lambda: "[" * 100000 + "]" * 100000, "x.plan", "nests about 8 levels"),
    (read_plan, lambda: "[1, 2]", "x.plan", "one JSON object"),
], ids=["wpl-not-a-number", "wpl-11-fields", "wpl-not-whole", "wpl-current-2", "wpl-index-twice", "wpl-float32",
        "wpl-lat-global", "wpl-x-local", "wpl-x-mission", "wpl-too-many-rows", "wpl-not-utf8", "wpl-too-large",
        "wpl-too-large-bytes", "wpl-header", "plan-command-string", "plan-lat-string", "plan-command-fraction",
        "plan-frame-256", "plan-float32", "plan-lat-global", "plan-y-local", "plan-too-many-items",
        "plan-infinity", "plan-home-short", "plan-missing-key", "plan-not-utf8", "plan-too-large",
        "plan-too-large-bytes", "plan-nested", "plan-not-an-object"])
def test_bad_files_are_refused_with_a_hint(read, make, where, hint):
    """Every way a .waypoints or .plan file can be wrong names the place and says what to do."""
    name = "x.waypoints" if read is read_wpl else "x.plan"
    with pytest.raises(PlanError) as err:
        read(make(), name)
    assert err.value.where == where, str(err.value)
    assert err.value.hint and hint in err.value.hint, str(err.value)
    assert str(err.value).endswith(f"\n  hint: {err.value.hint}")


def test_bad_writer_input():
    with pytest.raises(PlanError, match="unknown firmware"):
        write_plan(sample_items(), None, firmware="betaflight", vehicle="copter")
    with pytest.raises(PlanError, match="fence polygon"):
        write_plan([], None, firmware="px4", vehicle="copter", fence=fence_items()[:2])
    with pytest.raises(PlanError, match=r"mission item 1 \(command 16\) has param1 = inf, which a .plan file"):
        write_plan([MissionItem(command=16, param1=math.inf)], None, firmware="px4", vehicle="copter")
    with pytest.raises(PlanError, match=r"rally item 1 \(command 5100\) has z = -inf"):
        write_plan([], None, firmware="px4", vehicle="copter",
                   rally=[MissionItem(command=5100), MissionItem(command=5100, z=-math.inf)])
    with pytest.raises(PlanError, match=r"fence item 0 \(command 5004\) has param1 = inf"):
        write_plan([], None, firmware="px4", vehicle="copter", fence=[MissionItem(command=5004, param1=math.inf)])
    with pytest.raises(PlanError, match=r"home position \(47.0, 8.0, inf\) holds an infinite value"):
        write_plan([], (47.0, 8.0, math.inf), firmware="px4", vehicle="copter")


def test_writer_limits_have_a_hint():
    one = MissionItem(command=16)
    cases = [
        (lambda: write_plan([one] * 65536, None, firmware="px4", vehicle="copter"), "65536 mission items", "split"),
        (lambda: write_wpl([one] * 65535), "65535 items do not fit", "save a .plan instead"),
        (lambda: write_plan([one], None, firmware="px4", vehicle="copter", cruise_speed=math.inf),
         "an infinite value", "finite cruise_speed"),
        (lambda: write_plan([one], None, firmware="betaflight", vehicle="copter"), "unknown firmware", "ardupilot"),
        (lambda: write_plan([], None, firmware="px4", vehicle="copter", fence=fence_items()[:2]), "fence polygon",
         "param1 = N"),
        (lambda: write_wpl([one.with_(z=math.inf)]), "has z = inf", "finite value"),
    ]
    for write, message, hint in cases:
        with pytest.raises(PlanError, match=message) as err:
            write()
        assert hint in (err.value.hint or ""), str(err.value)


finite = st.floats(allow_nan=True, allow_infinity=False, width=32)
items_st = st.lists(st.builds(
    MissionItem, command=st.integers(0, 65535), frame=st.sampled_from([0, 2, 3, 10]),
    param1=finite, param2=finite, param3=finite, param4=finite,
    x=st.integers(-900000000, 900000000), y=st.integers(-1800000000, 1800000000), z=finite,
    autocontinue=st.integers(0, 1)), max_size=8)


@settings(max_examples=150, deadline=None)
@given(items_st)
def test_property_round_trip(items):
    # what the writer writes reads back the same; what the reader would refuse the writer refuses
    if any(item_problem(x) for x in items):
        with pytest.raises(PlanError, match=r"mission item \d+ \(.*\): .*, which a .plan file should not hold"):
            write_plan(items, None, firmware="px4", vehicle="copter")
        return
    assert same(read_plan(write_plan(items, None, firmware="px4", vehicle="copter"))[0], items)


@pytest.mark.peer
@pytest.mark.parametrize("autopilot", ["px4", "ardupilot"])
def test_mavsdk_imports_what_we_write(tmp_path, autopilot):
    import mission_peers

    home = (47.1, 8.2, 488.5)
    items = sample_items()
    text = write_plan(items, home, firmware=autopilot, vehicle="copter", fence=fence_items(), rally=rally_items())
    res = mission_peers.mavsdk_import_plan(text, tmp_path, autopilot=autopilot)
    assert res["ok"], res.get("error")
    mission = res["mission"]
    if autopilot == "ardupilot":
        # MAVSDK puts plannedHomePosition in as item 0 for ArduPilot, as QGC does on upload.
        h = mission.pop(0)
        assert (h.x, h.y, h.z) == (471000000, 82000000, 488.5)
    assert same(mission, items), [(a, b) for a, b in zip(mission, items) if not a.same_on_wire(b)]
    # MAVSDK marks fence and rally items autocontinue=0 (meaningless for them); the rest must match.
    assert same([f.with_(autocontinue=1) for f in res["fence"]], fence_items())
    assert same([r.with_(autocontinue=1) for r in res["rally"]], rally_items())


@pytest.mark.peer
def test_compiled_example_plan_imports_in_mavsdk(tmp_path):
    """The compiler's .plan output (written through write_plan's file form) is what MAVSDK reads."""
    import mission_peers
    from missions.compile import compile_plan

    root = Path(__file__).resolve().parents[2]
    compiled = compile_plan(str(root / "examples" / "waypoint-inspection.yaml"))
    target = tmp_path / "w.plan"
    write_plan(target, compiled)
    res = mission_peers.mavsdk_import_plan(target.read_text(), tmp_path, autopilot=compiled.firmware)
    assert res["ok"], res.get("error")
    mission = res["mission"][1:] if compiled.firmware == "ardupilot" else res["mission"]
    assert same(mission, list(compiled.items))


# -- positions must be real ones, and values no vehicle takes are refused (itemcheck) --------------------

def _simple(command: int, params: list, frame: int = 3, auto=True) -> dict:
    return {"type": "SimpleItem", "command": command, "frame": frame, "params": params, "autoContinue": auto,
            "doJumpId": 1}


def _plan_with(*simple) -> str:
    return _plan(lambda d: d["mission"].__setitem__("items", list(simple)))


@pytest.mark.parametrize("item,where,message,hint", [
    (_simple(16, [0, 0, 0, None, 95, 8.5, 50]), "params[4]", "MAV_CMD_NAV_WAYPOINT: latitude 95.0000000 is outside "
     "-90..90", "latitude -90..90, longitude -180..180"),
    (_simple(16, [0, 0, 0, None, 47, 200, 50]), "params[5]", "longitude 200.0000000 is outside -180..180",
     "longitude -180..180"),
    (_simple(16, [0, 0, 0, None, None, 8.5, 50]), "params[4]", "MAV_CMD_NAV_WAYPOINT: latitude is not set (null or "
     "NaN)", "needs a position"),
    (_simple(5100, [0, 0, 0, 0, 47, None, 50]), "params[5]", "longitude is not set", "needs a position"),
    (_simple(16, [0, 0, 0, None, 47, 8.5, 3.4e38]), "params[6]", "altitude 3.4e+38 is not a real altitude",
     "altitude in metres"),
    (_simple(16, [0, 0, 0, None, 47, 8.5, None]), "params[6]", "altitude nan is not a real altitude",
     "altitude in metres"),
    (_simple(16, [0, 0, 0, None, 47, 8.5, 50], frame=255), "frame", "frame 255 is not a MAV_FRAME", "MAV_FRAME"),
    (_simple(201, [3, 0, 0, 0, -91, 8.5, 50]), "params[4]", "MAV_CMD_DO_SET_ROI: latitude -91.0000000 is outside",
     "real position"),
])
def test_plan_positions_must_be_real(item, where, message, hint):
    with pytest.raises(PlanError) as err:
        read_plan(_plan_with(item), "x.plan")
    assert err.value.where == f"x.plan: mission.items[0].{where}", str(err.value)
    assert message in err.value.message and hint in err.value.hint, str(err.value)


def test_plan_items_without_a_position_keep_null_as_zero():
    # QGC writes 0 (or null) where a command has no position; a takeoff's 0, 0 is "where the vehicle is"
    # (ArduCopter takes off straight up), DO_SET_HOME with param1 = 1 uses the current position
    items, *_ = read_plan(_plan_with(_simple(178, [1, 5, -1, 0, None, None, None], frame=2),
                                     _simple(22, [15, 0, 0, None, None, None, 30]),
                                     _simple(179, [1, 0, 0, 0, None, None, 0], frame=0),
                                     _simple(16, [0, 0, 0, None, 0, 0, 50])), "x.plan")
    assert [(it.command, it.x, it.y) for it in items] == [(178, 0, 0), (22, 0, 0), (179, 0, 0), (16, 0, 0)]


@pytest.mark.parametrize("mutate,where,message", [
    (lambda d: d["rallyPoints"]["points"][0].__setitem__(2, 3.4e38), "rallyPoints.points[0][2]",
     "altitude 3.4e+38 is not a real altitude"),
    (lambda d: d["mission"]["plannedHomePosition"].__setitem__(2, -3.4e38), "mission.plannedHomePosition[2]",
     "home altitude -3.4e+38 is not a real altitude"),
])
def test_plan_rally_and_home_altitudes_must_be_real(mutate, where, message):
    with pytest.raises(PlanError) as err:
        read_plan(_plan(mutate), "x.plan")
    assert err.value.where == f"x.plan: {where}" and message in err.value.message and err.value.hint


@pytest.mark.parametrize("write", [
    lambda items, home: write_plan(items, home, firmware="px4", vehicle="copter"),
    lambda items, home: write_wpl(items, home)], ids=["plan", "wpl"])
@pytest.mark.parametrize("item,home,message", [
    (MissionItem(command=16, x=2**31 - 1, y=85456075, z=50), None,
     "mission item 1 (MAV_CMD_NAV_WAYPOINT): latitude 214.7483647 is outside -90..90"),
    (MissionItem(command=16, x=473977507, y=85456075, z=3.4e38), None, "altitude 3.4e+38 is not a real altitude"),
    (MissionItem(command=65535, frame=255, x=473977507, y=85456075), None,
     "mission item 1 (command 65535): frame 255 is not a MAV_FRAME"),
    (MissionItem(command=16, x=473977507, y=85456075, z=50, autocontinue=255), None,
     "autocontinue 255 is neither 0 nor 1"),
    (MissionItem(command=16, x=473977507, y=85456075, z=50), (95.0, 8.0, 0.0), "home latitude 95 is outside -90..90"),
])
def test_writers_refuse_what_their_readers_would(write, item, home, message):
    with pytest.raises(PlanError) as err:
        write([item], home)
    assert message in err.value.message and "file should not hold" in err.value.message and err.value.hint


def test_a_fence_circle_without_a_radius_is_not_written():
    # a vehicle's NaN radius would be written as "radius": null, which read_plan (and QGC) refuse
    circle = MissionItem(command=5003, frame=0, param1=math.nan, x=470000000, y=80000000, mission_type=MISSION_TYPE_FENCE)
    with pytest.raises(PlanError, match=r"fence item 0 \(MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION\): radius nan is not a "
                                        "positive number of metres") as err:
        write_plan([], None, firmware="px4", vehicle="copter", fence=[circle])
    assert "radius in metres" in err.value.hint
