"""PX4 ULogs through pyulog: PX4's public test log (tests/data/px4/README.md: pyulog's, BSD-3-Clause), and
ULogs written here with camera captures (pyulog writes what it reads)."""

from __future__ import annotations

from pathlib import Path

import pytest

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


# A PX4 v1.16 SITL (SIH) flight of sitl_plans' "survey" with the WIRIS emulator on the payload link, its ULog
# cut to the topics the audit reads (tests/data/README.md says how); read here with pyulog on its own too.
SITL_LOG = PX4_LOG.parent / "px4_sitl_survey_camera_capture.ulg"


def _pyulog(name: str):
    from pyulog import ULog
    return ULog(str(SITL_LOG), [name]).get_dataset(name).data


def test_a_real_px4_sitl_ulog_with_camera_capture_is_audited(tmp_path):
    from missions.compile import compile_plan
    from wiris_tools.audit.measure import audit_flight

    cap, trig, home = _pyulog("camera_capture"), _pyulog("camera_trigger"), _pyulog("home_position")
    ok = int((cap["result"] == 1).sum())
    plan = sitl_plans.write_plan(tmp_path, "survey", firmware="px4")
    compiled = compile_plan(plan)
    log = read_log(SITL_LOG)
    assert len(log.captures) == ok == len(cap["seq"]) == 75
    assert len(log.triggers) == len(set(trig["seq"].tolist())) == 75     # one trigger is logged twice
    audit = audit_flight(compiled, log, str(plan))
    (step,) = audit.steps
    assert audit.captured == audit.triggered == 75 and audit.failed == 0
    assert audit.triggered_not_captured == () and audit.captured_not_triggered == ()
    assert step.captured == 75 and step.missing_planned <= 2
    assert step.coverage >= 0.995 and audit.complete
    # heights above home: camera_capture's AMSL altitude less home's
    above = cap["alt"] - home["alt"][-1]
    assert step.heights.source == "home"
    assert step.heights.min_m == pytest.approx(float(above.min()), abs=0.5)
    assert step.heights.max_m == pytest.approx(float(above.max()), abs=0.5)
    assert 39.0 < step.heights.min_m < step.heights.max_m < 41.0
    # a real flight: the lines' photos overlap less than planned where the copter swings (never zero)
    assert 0.6 < step.front_min < step.requested_front
    assert 0.4 < step.side_min < step.requested_side + 0.05
    # PX4 numbers the mission from 0 and flies its RTL item in AUTO_RTL: the mission was flown to its end
    assert audit.flight.last_item == len(compiled.items)
    assert audit.flight.modes == ("AUTO_MISSION", "AUTO_RTL")
    assert audit.flight.left_plan == () and audit.flight.sorties == 1
