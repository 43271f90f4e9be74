"""`wiris sim ardupilot` (SITL with the WIRIS emulator on its camera link) and `wiris camera apply` from the
ground-station side of ArduPilot: each setup step reaches the emulated camera through the autopilot's
routing and is acknowledged, and the camera's state shows the plan's settings."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import sitl_plans
from wiris_tools.cli import cli
from wiris_tools.link import Link
from wiris_tools.sitl.flight import desk_sim

pytestmark = pytest.mark.sitl

ROOT = Path(__file__).resolve().parents[2]


def test_camera_apply_through_ardupilot_reaches_the_emulated_camera(sitl_dir, tmp_path):
    plan = sitl_plans.write_plan(tmp_path, "survey")          # range manual 10..60 °C before flight
    res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    with desk_sim(sitl_dir, speedup=10, workdir=tmp_path / "sitl") as sim:
        with sim.emulator.lock:
            before = dict(sim.emulator.state.values)
        res = CliRunner().invoke(cli, ["camera", "apply", str(tmp_path / "out" / "survey.setup.json"),
                                       "--connect", sim.sitl.gcs_url, "--json", "--timeout", "2", "--wait", "20"])
        assert res.exit_code == 0, res.output
        with sim.emulator.lock:
            after = dict(sim.emulator.state.values)
    out = json.loads(res.output)
    steps = json.loads((tmp_path / "out" / "survey.setup.json").read_text())["steps"]
    assert out["ok"] and len(out["completed"]) == len(steps) >= 2
    assert all(r["outcome"] != "SENT" for r in out["completed"]), out      # every step acknowledged
    changed = {k for k in after if after[k] != before.get(k)}
    assert changed, (before, after)        # the camera's settings moved, not only the ACKs came back


def test_wiris_sim_ardupilot_runs_until_told_and_leaves_nothing(sitl_dir, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-c", "from wiris_tools.entry import main; main()", "sim", "ardupilot",
                             "--sitl-dir", str(sitl_dir), "--speedup", "10", "--workdir", str(tmp_path / "w")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=ROOT)
    try:
        line = proc.stdout.readline()          # the first line: nothing before the URL (scripts read it)
        assert line.startswith("ground station: tcp:127.0.0.1:"), line
        with Link(line.split(": ", 1)[1].strip()) as link:
            link.wait_heartbeat(timeout=20, system=1, component=1)
            link.wait_heartbeat(timeout=20, system=1, component=100)   # the camera, routed by ArduPilot
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    assert proc.returncode == 0, proc.stderr.read()
    assert (tmp_path / "w" / "eeprom.bin").exists() and (tmp_path / "w" / "gcs.tlog").stat().st_size > 0
    assert subprocess.run(["pgrep", "-f", str(tmp_path / "w")], capture_output=True).returncode == 1
