"""PX4 ULogs through pyulog: PX4's public test log (tests/data/px4/README.md: pyulog's, BSD-3-Clause), and
ULogs written here with camera captures (pyulog writes what it reads)."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

import sitl_plans
from wiris_tools.audit.logs import read_log
from wiris_tools.cli import cli

PX4_LOG = Path(__file__).resolve().parents[1] / "data" / "px4" / "sample_px4_events.ulg"


def test_px4s_public_log_reads_its_track_and_modes():
    log = read_log(PX4_LOG)
    assert log.kind == "ulog"
    assert len(log.track) > 50 and abs(log.track[0].lat - 47.3977) < 0.01
    assert [m.mode for m in log.modes if m.armed] == ["AUTO_TAKEOFF", "AUTO_LOITER", "AUTO_RTL"]
    assert log.captures == () and log.triggers == ()


def test_a_ulog_without_camera_captures_says_so_and_exits_1(tmp_path):
    plan = sitl_plans.write_plan(tmp_path, "survey")
    res = CliRunner().invoke(cli, ["mission", "audit", str(plan), str(PX4_LOG)])
    assert res.exit_code == 1
    assert "no camera messages" in res.output and "camera_capture" in res.output
