"""The audit of tlogs written as a ground station writes them, from a compiled plan's flight with the faults of
the field: what it finds is exactly what was dropped."""

from __future__ import annotations


from pathlib import Path

import pytest


import sitl_plans  # noqa: E402
from audit_logs import Faults, write_tlog  # noqa: E402

from missions.compile import compile_plan
from wiris_tools.audit.logs import read_log
from wiris_tools.audit.measure import audit_flight


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    path = sitl_plans.write_plan(d, "survey")
    return path, compile_plan(path)


def test_a_full_flight_is_complete(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled)
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    (step,) = audit.steps
    assert audit.captured == audit.triggered == facts["photos"]
    assert audit.triggered_not_captured == ()
    assert step.missing_planned == 0
    assert step.coverage >= 0.995 and audit.complete
    assert step.front_min == pytest.approx(0.75, abs=0.02)
    assert audit.flight.left_plan == ()


def test_every_fifth_capture_dropped_is_found_exactly(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(drop_every=5))
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert list(audit.triggered_not_captured) == facts["dropped"]
    assert audit.captured == facts["photos"] - len(facts["dropped"])
    assert audit.steps[0].missing_planned >= len([k for k in facts["dropped"]]) - 2


def test_rtl_cut_short_is_said_and_leaves_a_gap(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(rtl_after=20))
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert audit.triggered == 20
    assert any("RTL before the mission's end" in s for s in audit.flight.left_plan)
    assert audit.steps[0].coverage < 0.9 and audit.steps[0].gaps
    assert not audit.complete


def _union_coverage(compiled, audit, refly_compiled) -> float:
    """Coverage of the original area by the captured footprints and the refly's predicted ones."""
    import numpy as np
    import shapely

    from missions.geometry.footprint import Footprint
    from missions.measure.coverage import footprint_polygons
    from missions.measure.flight import simulate
    from missions.measure.report import area_geometry

    proj = simulate(compiled).projection
    sim = simulate(refly_compiled)
    geom = area_geometry(compiled.areas[0].area, proj)
    info = compiled.payload("thermal")
    lat, lon = sim.projection.to_latlon(np.array([p.x for p in sim.photos]), np.array([p.y for p in sim.photos]))
    x, y = proj.to_xy(lat, lon)
    refly = footprint_polygons(np.column_stack([x, y]), np.radians([p.heading_deg for p in sim.photos]),
                               Footprint(*info.footprint_m(refly_compiled.areas[0].altitude_m)))
    union = shapely.union_all([audit.steps[0].footprints.polygons, *refly])
    return float(shapely.intersection(geom, union).area / geom.area)


def test_cli_audit_writes_the_gap_map_and_a_refly_that_closes_the_gaps(survey, tmp_path):
    import json

    from click.testing import CliRunner

    from wiris_tools.cli import cli

    path, compiled = survey
    write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(stop_after=25))
    res = CliRunner().invoke(cli, ["mission", "audit", str(path), str(tmp_path / "f.tlog"), "-o",
                                   str(tmp_path / "out"), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["complete"] is False and out["steps"][0]["gaps"] >= 1
    gaps = json.loads((tmp_path / "out" / "survey.gaps.geojson").read_text())
    assert gaps["features"] and all(f["properties"]["kind"] == "gap" for f in gaps["features"])
    assert (tmp_path / "out" / "survey.audit.png").read_bytes()[:4] == b"\x89PNG"
    refly = tmp_path / "out" / "survey-refly.yaml"
    assert (tmp_path / "out" / "survey-refly" / "survey-refly.plan").exists()
    refly_compiled = compile_plan(refly)
    assert refly_compiled.areas[0].altitude_m == compiled.areas[0].altitude_m
    assert refly_compiled.areas[0].front_overlap == compiled.areas[0].front_overlap
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert _union_coverage(compiled, audit, refly_compiled) >= 0.995


def test_a_complete_flight_writes_no_refly(survey, tmp_path):
    from click.testing import CliRunner

    from wiris_tools.cli import cli

    path, compiled = survey
    write_tlog(tmp_path / "f.tlog", compiled)
    res = CliRunner().invoke(cli, ["mission", "audit", str(path), str(tmp_path / "f.tlog"), "-o", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    assert "complete" in res.output and "INCOMPLETE" not in res.output
    assert not (tmp_path / "o" / "survey-refly.yaml").exists()


def test_photos_in_an_exclusion_zone_are_counted(survey, tmp_path):
    # the same field with an exclusion in its middle; the flight flew the plan without it, camera on throughout
    path, compiled = survey
    text = path.read_text(encoding="utf-8").replace(
        "      payloads: [thermal]\n",
        "      exclude: [[[50.0812, 14.4214], [50.0812, 14.4220], [50.0815, 14.4220], [50.0815, 14.4214]]]\n"
        "      payloads: [thermal]\n", 1)
    zoned = tmp_path / "zoned.yaml"
    zoned.write_text(text, encoding="utf-8")
    zoned_compiled = compile_plan(zoned)
    write_tlog(tmp_path / "f.tlog", compiled)
    audit = audit_flight(zoned_compiled, read_log(tmp_path / "f.tlog"), str(zoned))
    assert audit.steps[0].photos_in_zones > 0
    write_tlog(tmp_path / "g.tlog", zoned_compiled)      # flown as planned: the camera is off over the zone
    assert audit_flight(zoned_compiled, read_log(tmp_path / "g.tlog"), str(zoned)).steps[0].photos_in_zones == 0
