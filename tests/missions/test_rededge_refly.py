"""A RedEdge on a refly_90 survey: it shoots by itself on turnarounds and transits too, and those photos are no
side neighbours of the crossing pass's lines (the report read 36 % side overlap against 70 % requested)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from missions.compile import compile_plan
from missions.measure.report import report

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("payloads", ["[multispectral]", "[thermal, multispectral]"])
def test_a_rededge_refly_90_survey_reports_the_side_overlap_it_flies(tmp_path, payloads):
    shutil.copytree(EXAMPLES / "areas", tmp_path / "areas")
    text = (EXAMPLES / "field-multispectral.yaml").read_text()
    text = text.replace("      payloads: [thermal, multispectral]", f"      payloads: {payloads}\n      refly_90: true")
    (tmp_path / "p.yaml").write_text(text)
    c = compile_plan(tmp_path / "p.yaml")
    rep = report(c)
    (row,) = rep.areas
    ov = row.overlap["multispectral"]
    assert ov.side_min >= 0.695 and ov.front_min >= 0.745
    assert not [w for w in rep.warnings if w.code in ("side_overlap_low", "front_overlap_low")]
    # the photo count is still every photo it takes during the step, turnarounds included
    sim_photos = [p for p in c.flight_cache.sim.photos if "multispectral" in p.payloads]
    area = c.areas[0]
    assert row.photos["multispectral"] == sum(1 for p in sim_photos if area.items[0] <= p.item < area.items[1])
    assert len(area.line_items) > 0 and row.photos["multispectral"] > sum(
        1 for p in sim_photos if p.item in set(area.line_items))
