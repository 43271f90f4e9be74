"""The example plans of examples/: each compiles on its firmware without errors, reaches ≥ 99.5 % measured
coverage, and its files are read back exactly — .plan by MAVSDK's QGroundControl importer (a real third-party
reader), .waypoints by missions.formats.wpl."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import mission_peers
from missions.compile import compile_plan
from missions.emit.items import FRAME_GLOBAL, MissionItem, mavlink
from missions.formats.outputs import write_outputs
from missions.measure.flight import simulate
from missions.measure.report import report
from missions.formats.wpl import read_wpl

EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.yaml"))


def test_there_are_examples_of_each_kind():
    names = {p.stem for p in EXAMPLES}
    assert {"solar-park", "field-multispectral", "powerline-corridor", "waypoint-inspection"} <= names


@pytest.fixture(scope="module")
def compiled_examples(tmp_path_factory):
    out = tmp_path_factory.mktemp("examples")
    result = {}
    for path in EXAMPLES:
        c = compile_plan(path)
        sim = simulate(c)
        rep = report(c, sim, plan_path=str(path))
        files = write_outputs(c, out, rep=rep, sim=sim)
        result[path.stem] = (c, rep, {p.name: p for p in files})
    return result


@pytest.mark.parametrize("name", [p.stem for p in EXAMPLES])
def test_example_compiles_and_covers(compiled_examples, name):
    c, rep, files = compiled_examples[name]
    assert rep.to_json()["errors"] == []
    assert len(c.parts) == 1 and len(c.items) <= c.item_limit
    for payload, cov in rep.coverage.items():
        assert cov >= 0.995, (payload, cov)
    for payload, n in rep.photos.items():
        assert n > 0, payload
    assert f"{c.name}.plan" in files and f"{c.name}.report.json" in files


def test_examples_use_what_they_advertise(compiled_examples):
    sp = compiled_examples["solar-park"][0]
    assert sp.firmware == "ardupilot" and sp.areas and sp.areas[0].area.geometry.interiors is not None
    fm = compiled_examples["field-multispectral"][0]
    assert {p.component_id for p in fm.payloads} == {100, 101}
    assert compiled_examples["powerline-corridor"][0].firmware == "px4"
    assert compiled_examples["powerline-corridor"][0].home[0] < 0          # southern hemisphere
    wp = compiled_examples["waypoint-inspection"][0]
    assert wp.lua                                                        # the in-flight change needs the bridge


@pytest.mark.parametrize("name", [p.stem for p in EXAMPLES])
def test_waypoints_file_round_trips(compiled_examples, name):
    c, _rep, files = compiled_examples[name]
    items, home = read_wpl(files[f"{c.name}.waypoints"].read_text(), f"{c.name}.waypoints")
    assert len(items) == len(c.items)
    assert all(a.same_on_wire(b) for a, b in zip(items, c.items))
    assert home[0] == pytest.approx(c.home[0], abs=1e-7) and home[1] == pytest.approx(c.home[1], abs=1e-7)


def _same(got: MissionItem, want: MissionItem) -> bool:
    def eq(a: float, b: float) -> bool:
        return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-6, abs=1e-6)

    return (got.command == want.command and got.frame == want.frame and got.x == want.x and got.y == want.y
            and got.autocontinue == want.autocontinue
            and all(eq(a, b) for a, b in zip((got.param1, got.param2, got.param3, got.param4, got.z),
                                               (want.param1, want.param2, want.param3, want.param4, want.z))))


@pytest.mark.peer
@pytest.mark.parametrize("name", [p.stem for p in EXAMPLES])
def test_mavsdk_imports_exactly_the_compiled_items(compiled_examples, name, tmp_path):
    c, _rep, files = compiled_examples[name]
    res = mission_peers.mavsdk_import_plan(files[f"{c.name}.plan"].read_text(), tmp_path, autopilot=c.firmware)
    assert res["ok"], res.get("error")
    want = list(c.items)
    # MAVSDK's importer puts plannedHomePosition in as item 0 when it knows the vehicle is ArduPilot, as QGC does
    # on upload; in 4.1.0 that knowledge sometimes arrives after the import (a race in the offline set-up), so
    # the home row is checked when it is there and never counted as one of ours.
    if c.firmware == "ardupilot" and len(res["mission"]) == len(want) + 1:
        lat, lon, alt = c.home
        home = MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, FRAME_GLOBAL, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)
        got_home, got = res["mission"][0], res["mission"][1:]
        assert got_home.command == home.command and abs(got_home.x - home.x) <= 1 and abs(got_home.y - home.y) <= 1
        assert got_home.z == pytest.approx(alt)
    else:
        got = res["mission"]
    assert len(got) == len(want)
    bad = [(i, g, w) for i, (g, w) in enumerate(zip(got, want)) if not _same(g, w)]
    assert not bad, bad[:3]
