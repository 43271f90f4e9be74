"""Sorties (missions.sorties): a mission longer than one battery, or than the item limit, flown as complete
missions whose union flies what the single mission flies."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from missions.compile import compile_plan
from missions.errors import PlanError
from missions.formats.outputs import write_outputs
from missions.formats.planfile import load_plan as read_plan_file
from missions.measure.flight import simulate
from missions.measure.report import report
from missions.plan.load import load_plan
from missions.sorties import DEFAULT_ENDURANCE_MIN

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _with_vehicle(plan, **changes):
    return dataclasses.replace(plan, vehicle=dataclasses.replace(plan.vehicle, **changes))


@pytest.fixture(scope="module")
def solar_25():
    """The bundled solar park on a 25 min battery (20 % reserve: 20 min a sortie), and the single mission."""
    plan = load_plan(EXAMPLES / "solar-park.yaml")
    single = compile_plan(plan)
    split = compile_plan(_with_vehicle(plan, endurance_min=25.0))
    return single, split, report(single), report(split)


def _solar_park_copy(tmp_path: Path, text: str) -> Path:
    """`text` as sp.yaml beside a copy of the examples' areas."""
    (tmp_path / "areas").mkdir()
    for f in (EXAMPLES / "areas").iterdir():
        (tmp_path / "areas" / f.name).write_bytes(f.read_bytes())
    plan = tmp_path / "sp.yaml"
    plan.write_text(text)
    return plan


def _complete(items, ending=m.MAV_CMD_NAV_RETURN_TO_LAUNCH):
    cmds = [it.command for it in items]
    assert cmds[0] == m.MAV_CMD_NAV_TAKEOFF and cmds[1] == m.MAV_CMD_DO_CHANGE_SPEED
    assert cmds[-1] == ending
    assert m.MAV_CMD_NAV_LOITER_UNLIM not in cmds            # no hovering "parts"


def test_the_solar_park_on_a_25_min_battery_flies_in_sorties_that_each_fit_and_together_cover_it(solar_25):
    single, split, rep1, rep = solar_25
    assert len(split.sorties) >= 3 and split.parts == tuple(s.items for s in split.sorties)
    for s in split.sorties:
        _complete(s.items)
        flown = simulate(dataclasses.replace(split, items=s.items, parts=(s.items,), sorties=()))
        assert flown.flight_time_s <= 25 * 60 * 0.8
        assert flown.flight_time_s == pytest.approx(s.flight_time_s)
        # its own camera trigger: on and off within the sortie
        dist = [it.param1 for it in s.items if it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
        assert dist and dist[0] > 0 and dist[-1] == 0
    # consecutive lines, every line of the single mission flown once
    lines = [(s.first_line, s.last_line) for s in split.sorties]
    assert lines[0][0] == 1 and all(b[0] == a[1] + 1 for a, b in zip(lines, lines[1:]))
    assert sum(s.photos for s in split.sorties) >= rep1.photos["thermal"]
    # the union of the sorties, measured from their own items, covers what the single mission covers
    union = rep.sorties
    assert union.coverage["thermal"] >= rep1.coverage["thermal"] - 1e-9
    assert union.overlap["thermal"].side_min >= rep1.overlap["thermal"].side_min - 0.005
    assert union.overlap["thermal"].front_min >= rep1.overlap["thermal"].front_min - 0.005
    assert any(w.code == "mission_split" and "25 min" in w.message for w in split.warnings)
    rows = rep.to_json()["sorties"]
    assert [r["file"] for r in rows] == [f"solar-park.sortie{k}.plan" for k in range(1, len(rows) + 1)]
    assert set(rows[0]) == {"file", "flight_time_s", "photos", "items", "first_line", "last_line"}
    assert rep.to_json()["endurance"] == {"endurance_min": 25.0, "reserve_pct": 20.0, "assumed": False,
                                          "usable_s": 1200.0}


def test_sortie_files_are_written_and_read_back_as_the_sorties(solar_25, tmp_path):
    _single, split, _rep1, rep = solar_25
    written = {p.name for p in write_outputs(split, tmp_path, rep)}
    for s in split.sorties:
        name = f"solar-park.sortie{s.number}.plan"
        assert name in written and f"solar-park.sortie{s.number}.waypoints" in written
        items = read_plan_file(tmp_path / name)[0]
        assert len(items) == len(s.items) and all(a.same_on_wire(b) for a, b in zip(items, s.items))
    doc = json.loads((tmp_path / "solar-park.report.json").read_text())
    assert len(doc["sorties"]) == len(split.sorties) and doc["sorties_union"]["coverage"]["thermal"] > 0.99


def test_without_endurance_the_frame_default_is_only_warned_about(solar_25):
    single, _split, rep1, _rep = solar_25
    assert not single.sorties and len(single.parts) == 1
    (w,) = [w for w in single.warnings if w.code == "longer_than_battery"]
    assert f"{DEFAULT_ENDURANCE_MIN['copter']:g} min" in w.message and "vehicle.endurance_min" in w.message
    assert rep1.to_json()["endurance"]["assumed"] is True and rep1.to_json()["sorties"] == []


def test_the_item_limit_forces_sorties_each_a_complete_mission():
    plan = _with_vehicle(load_plan(EXAMPLES / "solar-park.yaml"), max_mission_items=60)
    c = compile_plan(plan)
    assert len(c.sorties) > 4 and all(len(s.items) <= 60 for s in c.sorties)
    for s in c.sorties:
        _complete(s.items)
    rep = report(c)
    assert rep.sorties.coverage["thermal"] >= 0.999


def _strip(tmp_path: Path, length_m: float, lat0: float, lon0: float) -> Path:
    """A 10 m wide strip of `length_m` east-west centred on (lat0, lon0): a single line for a WIRIS at 40 m."""
    dlon = length_m / 2 / (111_320.0 * math.cos(math.radians(lat0)))
    dlat = 5.0 / 111_320.0
    ring = [[lon0 - dlon, lat0 - dlat], [lon0 + dlon, lat0 - dlat], [lon0 + dlon, lat0 + dlat],
            [lon0 - dlon, lat0 + dlat], [lon0 - dlon, lat0 - dlat]]
    path = tmp_path / "strip.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    return path


def test_a_line_longer_than_a_battery_is_cut_at_a_photo_position_and_resumed_there(tmp_path):
    lat0, lon0 = 50.07, 14.72
    _strip(tmp_path, 1000.0, lat0, lon0)
    doc = (EXAMPLES / "solar-park.yaml").read_text()
    doc = doc.replace("areas/solar-park.geojson", "strip.geojson").replace("exclude: [areas/substation.geojson]", "")
    doc = doc.replace("home: {lat: 50.0696267, lon: 14.7263,", f"home: {{lat: {lat0 - 50 / 111_320.0}, lon: {lon0},")
    doc = doc.replace("speed_mps: 4.5 ", "endurance_min: 8\n  speed_mps: 4.5 ")
    (tmp_path / "p.yaml").write_text(doc)
    c = compile_plan(tmp_path / "p.yaml")
    assert len(c.sorties) == 2
    first, second = c.sorties
    assert (first.first_line, first.last_line, second.first_line, second.last_line) == (1, 1, 1, 1)
    cut = [it for it in first.items if it.comment.startswith("sortie end: a photo position")]
    resume = [it for it in second.items if it.comment.startswith("sortie start: where")]
    assert len(cut) == 1 and len(resume) == 1 and (cut[0].x, cut[0].y) == (resume[0].x, resume[0].y)
    on = [it for it in second.items if it.command == m.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
    assert on[0].param1 > 0 and on[0].param3 == 1.0            # a photo at once where the line resumes
    for s in c.sorties:
        _complete(s.items)
        assert s.flight_time_s <= 8 * 60 * 0.8
    rep = report(c)
    single = report(compile_plan(_with_vehicle(load_plan(tmp_path / "p.yaml"), endurance_min=None)))
    assert rep.sorties.coverage["thermal"] >= single.coverage["thermal"] - 1e-9
    assert rep.sorties.overlap["thermal"].front_min >= 0.795


def test_a_sortie_that_cannot_reach_its_lines_on_one_battery_is_an_error(tmp_path):
    plan = _with_vehicle(load_plan(EXAMPLES / "solar-park.yaml"), endurance_min=2.0)
    with pytest.raises(PlanError) as ei:
        compile_plan(plan)
    assert "battery" in ei.value.message and "endurance_min" in ei.value.hint and ei.value.where


def test_check_prints_the_sortie_table_and_upload_takes_a_sortie_file(tmp_path):
    from click.testing import CliRunner

    from wiris_tools.cli import cli
    from wiris_tools.readback import compare_items
    from wiris_tools.vehicle_sim import VehicleSim

    doc = (EXAMPLES / "solar-park.yaml").read_text().replace("speed_mps: 4.5 ", "endurance_min: 25\n  speed_mps: 4.5 ")
    plan = _solar_park_copy(tmp_path, doc)
    r = CliRunner().invoke(cli, ["mission", "check", str(plan)])
    assert r.exit_code == 0, r.output
    table = r.output[r.output.index("sortie  file"):].splitlines()
    assert table[1].split()[:2] == ["1", "solar-park.sortie1.plan"] and table[3].split()[0] == "3"
    assert "union of the sorties, thermal: coverage 100.00 %" in r.output
    out = tmp_path / "out"
    assert CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(out)]).exit_code == 0
    sortie = out / "solar-park.sortie2.plan"
    with VehicleSim(flavour="ardupilot", heartbeat_s=0.2) as sim:
        r = CliRunner().invoke(cli, ["mission", "upload", str(sortie), "--connect", f"udpout:127.0.0.1:{sim.port}",
                                     "--verify", "--json"])
        assert r.exit_code == 0, r.output
        held = sim.items()
    assert json.loads(r.output)["verified"] is True
    compare_items(list(read_plan_file(sortie)[0]), held[1:])
    r = CliRunner().invoke(cli, ["mission", "upload", str(plan), "--connect", "udpout:127.0.0.1:9"])
    assert r.exit_code == 1 and "flown in 3 sorties" in r.output and "--sortie 1..3" in r.output


@pytest.mark.parametrize("key,value", [("endurance_min", 0), ("reserve_pct", 95), ("endurance_min", "long")])
def test_a_bad_battery_is_refused_at_its_key(tmp_path, key, value):
    doc = (EXAMPLES / "solar-park.yaml").read_text().replace("speed_mps: 4.5 ", f"{key}: {value}\n  speed_mps: 4.5 ")
    plan = _solar_park_copy(tmp_path, doc)
    with pytest.raises(PlanError) as ei:
        load_plan(plan)
    assert "sp.yaml:13:" in ei.value.where and key in ei.value.message and ei.value.hint


def test_the_maps_tell_the_sorties_apart(solar_25):
    from missions.formats import geojson, kml, preview

    _single, split, _rep1, rep = solar_25
    sim = simulate(split)
    fc = geojson.feature_collection(split, sim, rep)
    feats = [f for f in fc["features"] if f["properties"]["kind"] == "sortie"]
    assert [f["properties"]["sortie"] for f in feats] == [1, 2, 3]
    for f, s in zip(feats, split.sorties):
        line = f["geometry"]["coordinates"]
        home = [round(split.home[1], 7), round(split.home[0], 7)]
        assert line[0][:2] == home and line[-1][:2] == home            # each from home back home
        assert f["properties"]["file"] == f"solar-park.sortie{s.number}.plan"
    text = kml.render_kml(fc)
    assert "<name>Sorties</name>" in text and "#sortie0" in text and "#sortie2" in text
    svg = preview.render_svg(preview.build_picture(split, sim, rep))
    assert all(c in svg for c in preview.SORTIE_COLOURS[:3]) and "sortie 3 (green)" in svg


def test_lines_are_numbered_by_the_triggered_camera_beside_a_rededge():
    """A RedEdge shoots by itself through turns and transits: its own stretches do not number the lines."""
    plan = _with_vehicle(load_plan(EXAMPLES / "field-multispectral.yaml"), endurance_min=25.0)
    c = compile_plan(plan)
    lines = [(s.first_line, s.last_line) for s in c.sorties]
    assert len(lines) == 2 and lines[0][0] == 1 and lines[1][0] == lines[0][1] + 1
    assert lines[1][1] == len(c.intent[0].legs)
