"""The generated Lua bridge in SITL's real Lua engine: NAME.lua in scripts/, SCR_ENABLE=1 from NAME.params;
the plan's in-flight camera change (range mode to auto after the survey) reaches the emulated camera as the
manual's USER_1 after the survey's photos and before the next step's, and the camera's state shows it."""

from __future__ import annotations

import threading

import pytest
from click.testing import CliRunner

import sitl_plans
from cdf.catalogue import catalogue
from missions.compile import compile_plan
from missions.measure.flight import simulate
from wiris_tools.cli import cli
from wiris_tools.sitl.flight import fly_compiled

pytestmark = [pytest.mark.sitl, pytest.mark.slow]


class _Arrivals:
    """USER_1 commands the camera receives from the autopilot, with how many photos it had taken by then."""

    def __init__(self, emulator) -> None:
        self.emulator = emulator
        self.seen: list[int] = []
        self._lock = threading.Lock()
        emulator.link.subscribe(self._on, types="COMMAND_LONG", src_system=1, src_component=1)

    def _on(self, m) -> None:
        if m.command == 31010:   # MAV_CMD_USER_1: the WIRIS's range/emissivity command (manual §6.3.2.1)
            with self._lock:
                self.seen.append(self.emulator.state.image_count)


def test_the_bridge_sends_the_in_flight_change_between_the_survey_and_the_next_capture(sitl_dir, tmp_path):
    plan = sitl_plans.write_plan(tmp_path, "camera_change")      # manual range before flight, auto after the survey
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(out)])
    assert res.exit_code == 0, res.output
    compiled = compile_plan(plan)
    survey_end = compiled.areas[0].items[1]
    before = sum(1 for p in simulate(compiled).photos if p.item < survey_end)
    auto = catalogue().get("wiris-pro").setting("range_mode").check("auto")
    watched = {}

    def set_up_and_watch(flight) -> None:
        res = CliRunner().invoke(cli, ["camera", "apply", str(out / "camera-change.setup.json"), "--connect",
                                       flight.sitl.gcs_url, "--timeout", "2", "--wait", "20"])
        assert res.exit_code == 0, res.output
        with flight.emulator.lock:
            watched["mode_before"] = flight.emulator.state.value("range_mode")
        watched["arrivals"] = _Arrivals(flight.emulator)

    with fly_compiled(sitl_dir, out, "camera-change", workdir=tmp_path / "sitl",
                      before_flight=set_up_and_watch) as flight:
        with flight.emulator.lock:
            mode_after = flight.emulator.state.value("range_mode")
            taken = flight.emulator.state.image_count
        texts = flight.sitl.statustext
    assert any("camera bridge for camera-change running" in t for t in texts), texts[-10:]
    seen = watched["arrivals"].seen
    assert seen, texts[-10:]
    assert all(count == before for count in seen), (seen, before)   # after the survey, before the next capture
    assert taken == before + 1
    assert watched["mode_before"] != auto and mode_after == auto
