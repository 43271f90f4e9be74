"""`wiris camera set` takes the names a capture plan takes (range_mode, manual) besides the definition's
(RANGE_MODE, Manual), any case, with did-you-mean on names and values; against the emulator over UDP."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from wiris_tools.cli import cli
from wiris_tools.emulate.runner import start_emulator


@pytest.fixture(scope="module")
def pro():
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0") as emu:
        yield emu


def cam_set(emu, *args):
    return CliRunner().invoke(cli, ["camera", "set", *args, "--connect", f"udpout:127.0.0.1:{emu.link.local_port}"])


@pytest.mark.parametrize("name,value,held,wire", [
    ("range_mode", "Manual", "RANGE_MODE = 1 (Manual)", ("range_mode", 1)),
    ("range_mode", "span", "RANGE_MODE = 2 (Span)", ("range_mode", 2)),
    ("Range_Mode", "AUTO", "RANGE_MODE = 0 (Automatic)", ("range_mode", 0)),
    ("layout", "fullscreen", "LAYOUT = 2 (Fullscreen)", ("layout", 2)),
    ("emissivity", "0.9", "EMISSIVITY = 0.9", None),
])
def test_plan_names_and_values_set_the_same_setting(pro, name, value, held, wire):
    r = cam_set(pro, name, value)
    assert r.exit_code == 0, r.output
    assert held in r.output
    if wire:
        with pro.lock:
            assert pro.state.value(wire[0]) == wire[1]


@pytest.mark.parametrize("name,value,hint", [
    ("range_mode", "manuel", "did you mean 'manual'?"),
    ("RANGE_MODE", "Manul", "did you mean 'Manual'?"),
    ("range_mod", "manual", "did you mean range_mode?"),
    ("RANGE_MOD", "manual", "did you mean RANGE_MODE?"),
])
def test_near_misses_get_did_you_mean_and_change_nothing(pro, name, value, hint):
    with pro.lock:
        before = dict(pro.state.values)
    r = cam_set(pro, name, value)
    assert r.exit_code == 1 and hint in r.output and "Traceback" not in r.output, r.output
    with pro.lock:
        assert pro.state.values == before
