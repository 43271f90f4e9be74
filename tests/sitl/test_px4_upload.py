"""Upload into PX4 SITL (v1.16, SIH): every bundled example and plans of each kind, compiled for
`firmware: px4`, go in with `wiris mission upload --verify` (every item accepted, read back identical as PX4
keeps it, by wiris_tools.readback's PX4 tables); plans PX4 cannot fly are refused at compile time."""

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
# an in-flight range_mode change is USER_1, which PX4 rejects at upload: refused when compiling
REFUSED = {"waypoint-inspection": "cannot change in flight on PX4", "camera_change": "cannot change in flight on PX4"}


def _upload(url: str, path: Path, *extra: str):
    return CliRunner().invoke(cli, ["mission", "upload", str(path), "--connect", url, "--verify", "--json",
                                    "--firmware", "px4", *extra])


def _check(res, name: str) -> None:
    if name in REFUSED:
        assert res.exit_code == 1 and REFUSED[name] in res.output, res.output
        return
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output)
    assert summary["verified"] is True
    assert summary["autopilot"].lower().startswith("px4")
    assert summary["items"] >= 3


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_uploads_to_px4_and_reads_back_identical(px4_copter, example):
    _check(_upload(px4_copter.gcs_url, example), example.stem)


@pytest.mark.parametrize("kind", sorted(sitl_plans.STEPS))
def test_each_kind_of_plan_uploads_to_px4_and_reads_back_identical(px4_copter, tmp_path, kind):
    _check(_upload(px4_copter.gcs_url, sitl_plans.write_plan(tmp_path, kind, firmware="px4")), kind)


def test_a_plan_split_into_parts_uploads_to_px4_part_by_part(px4_copter, tmp_path):
    plan = sitl_plans.write_plan(tmp_path, "survey", name="parts", limit=20, firmware="px4")
    counts = []
    for part in (1, 2):
        res = _upload(px4_copter.gcs_url, plan, "--part", str(part))
        assert res.exit_code == 0, res.output
        summary = json.loads(res.output)
        assert summary["verified"] is True
        counts.append(summary["items"])
    assert all(1 < n <= 20 for n in counts)
