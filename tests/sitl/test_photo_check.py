"""The photo check the SITL flights are judged by (wiris_tools.sitl.photos), on the report's own photos: no SITL
needed. Photos taken exactly where the report predicts must measure the report's coverage, zones included."""

from __future__ import annotations

from pathlib import Path

import pytest

from missions.compile import compile_plan
from missions.measure.flight import simulate
from wiris_tools.sitl.photos import check_photos

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("example", ["solar-park", "field-multispectral"])
def test_photos_taken_where_predicted_measure_the_reports_coverage(example):
    # solar-park's substation is an exclude zone: the report measures coverage on the 100,287 m² that can be
    # covered; measured on the whole area the same photos read 98.2 % (the SITL table showed that as a shortfall)
    compiled = compile_plan(EXAMPLES / f"{example}.yaml")
    payload = compiled.areas[0].payloads[0]
    sim = simulate(compiled)
    lat, lon = sim.projection.to_latlon([p.x for p in sim.photos], [p.y for p in sim.photos])
    taken = [(float(la), float(lo), p.alt_m) for p, la, lo in zip(sim.photos, lat, lon) if payload in p.payloads]
    check = check_photos(compiled, payload, taken)
    assert check.count_ok and check.worst_offset_m < 1e-3
    assert check.coverage_captured == pytest.approx(check.coverage_predicted, abs=0.001), check
