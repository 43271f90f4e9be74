"""Upload into ArduPilot SITL: every bundled example and plans of each kind go in with `wiris mission upload
--verify` (every item accepted, read back identical as the firmware keeps it), through the SITL's second
ground-station port while the harness holds the first."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

import sitl_plans
from wiris_tools.cli import cli

pytestmark = pytest.mark.sitl

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.yaml"))


def _upload(url: str, path: Path, *extra: str) -> dict:
    res = CliRunner().invoke(cli, ["mission", "upload", str(path), "--connect", url, "--verify", "--json",
                                   "--firmware", "ardupilot", *extra])
    assert res.exit_code == 0, res.output
    return json.loads(res.output)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_uploads_and_reads_back_identical(copter, example):
    summary = _upload(copter.gcs_url, example)
    assert summary["verified"] is True
    assert summary["autopilot"].lower().startswith("ardupilot")
    assert summary["items"] >= 3


@pytest.mark.parametrize("kind", sorted(set(sitl_plans.STEPS) - sitl_plans.PX4_ONLY))
def test_each_kind_of_plan_uploads_and_reads_back_identical(copter, tmp_path, kind):
    summary = _upload(copter.gcs_url, sitl_plans.write_plan(tmp_path, kind))
    assert summary["verified"] is True


def test_a_plan_split_into_parts_uploads_part_by_part(copter, tmp_path):
    plan = sitl_plans.write_plan(tmp_path, "survey", name="parts", limit=20)
    counts = []
    for part in (1, 2):
        summary = _upload(copter.gcs_url, plan, "--part", str(part))
        assert summary["verified"] is True
        counts.append(summary["items"])
    assert all(1 < n <= 20 for n in counts)
