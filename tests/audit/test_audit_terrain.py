"""Heights above the plan's DEM: the audit measures each captured photo's footprint at the camera's height
above the ground below it (home's elevation plus the logged height above home, less the DEM), not above home.
Synthetic GeoTIFFs from tests/terrain_dems.py; tlogs written as a ground station writes them."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import terrain_dems as T
from audit_logs import write_tlog
from missions.compile import compile_plan
from wiris_tools.audit.logs import read_log
from wiris_tools.audit.measure import audit_flight
from wiris_tools.cli import cli

SLOPE_PCT = 30.0          # rising to the east
HOME_AMSL = T.BASE_M      # home lies 250 m south of the centre, where the slope is at BASE_M


def _plans(tmp_path):
    T.write_dem(tmp_path / "dem.tif", T.slope(SLOPE_PCT, 90.0))
    area = T.square(150.0)
    over_dem = tmp_path / "dem.yaml"
    over_dem.write_text(T.plan_text("dem.tif", area, home_alt=HOME_AMSL))
    flat = tmp_path / "flat.yaml"
    flat.write_text(T.plan_text(None, area, home_alt=HOME_AMSL))
    return over_dem, flat


def _hag_by_formula(log) -> np.ndarray:
    """Each capture's height above the sloped ground, from the slope's own formula (not the DEM reader)."""
    from pyproj import Transformer
    tr = Transformer.from_crs("EPSG:4326", "EPSG:32633", always_xy=True)
    e0, _ = tr.transform(T.CENTRE[1], T.CENTRE[0])
    e = np.array([tr.transform(c.pose.lon, c.pose.lat)[0] for c in log.captures]) - e0
    ground = T.BASE_M + SLOPE_PCT / 100.0 * e
    return HOME_AMSL + np.array([c.pose.alt_rel_m for c in log.captures]) - ground


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    d = tmp_path_factory.mktemp("terrain")
    over_dem, flat = _plans(d)
    return over_dem, compile_plan(over_dem), flat, compile_plan(flat)


def test_a_flight_that_followed_the_dem_is_measured_above_it(plans, tmp_path):
    over_dem, dem_plan, _, _ = plans
    write_tlog(tmp_path / "f.tlog", dem_plan)
    log = read_log(tmp_path / "f.tlog")
    rel = np.array([c.pose.alt_rel_m for c in log.captures])
    assert rel.max() - rel.min() > 60           # above home the heights differ by the slope's rise
    audit = audit_flight(dem_plan, log, str(over_dem))
    (step,) = audit.steps
    hag = _hag_by_formula(log)
    assert step.heights.source == "dem"
    assert step.heights.min_m == pytest.approx(hag.min(), abs=0.3)
    assert step.heights.max_m == pytest.approx(hag.max(), abs=0.3)
    assert 59.5 < step.heights.min_m and step.heights.max_m < 66.5      # the plan's 60 m and its 10 % tolerance
    assert step.coverage >= 0.995 and audit.complete
    assert step.front_min >= 0.78 and step.side_min >= 0.68           # the request held over the ground


def test_a_flight_at_a_constant_height_above_home_leaves_the_uphill_side_short(plans, tmp_path):
    over_dem, dem_plan, flat, flat_plan = plans
    write_tlog(tmp_path / "f.tlog", flat_plan)          # flown as the plan without the DEM: 60 m above home
    log = read_log(tmp_path / "f.tlog")
    flat_audit = audit_flight(flat_plan, log, str(flat))
    assert flat_audit.complete and flat_audit.steps[0].heights.source == "home"    # what flat ground would say
    audit = audit_flight(dem_plan, log, str(over_dem))
    (step,) = audit.steps
    hag = _hag_by_formula(log)
    assert step.heights.min_m == pytest.approx(hag.min(), abs=0.3) and step.heights.min_m < 25
    assert step.heights.max_m == pytest.approx(hag.max(), abs=0.3) and step.heights.max_m > 95
    assert step.coverage < 0.97 and not audit.complete and step.gap_m2 > 1000
    assert step.side_min < 0.5
    # the gaps lie where the ground rises towards the camera: east of the centre
    lon_c = T.CENTRE[1]
    big = step.gaps[0]
    assert np.mean([lon for lat, lon in big.rings[0]]) > lon_c
    res = CliRunner().invoke(cli, ["mission", "audit", str(over_dem), str(tmp_path / "f.tlog"), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)["steps"][0]["height_above_ground"]
    assert out["source"] == "dem" and out["min_m"] == pytest.approx(step.heights.min_m, abs=0.01)
    text = CliRunner().invoke(cli, ["mission", "audit", str(over_dem), str(tmp_path / "f.tlog")]).output
    assert "m above the DEM" in text


def test_the_refly_of_the_uphill_gaps_flies_over_the_same_dem(plans, tmp_path):
    over_dem, _, _, flat_plan = plans
    write_tlog(tmp_path / "f.tlog", flat_plan)
    res = CliRunner().invoke(cli, ["mission", "audit", str(over_dem), str(tmp_path / "f.tlog"),
                                   "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    refly = tmp_path / "out" / "terrain-test-refly.yaml"
    refly_plan = compile_plan(refly)            # written elsewhere, its DEM found
    assert refly_plan.terrain is not None
    assert refly_plan.terrain.dem.files[0].path == str((over_dem.parent / "dem.tif").resolve())
