"""The PX4 backend of the SITL harness: a free instance (system id instance + 1) in its own folder, ready by
the home position and PX4's pre-arm health bit, parameters of either type set and kept over a restart, a
parameter PX4 lacks refused, parameters given at boot, ULogs kept, nothing left running after close()."""

from __future__ import annotations

import os

import pytest

from wiris_tools.errors import LinkError
from wiris_tools.sitl import PX4_DIR_VARIABLE, find_px4_dir

pytestmark = pytest.mark.sitl


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def test_px4_sets_int_and_float_parameters_that_survive_a_restart(start_vehicle):
    sitl = start_vehicle("px4", params={"TRIG_INTERFACE": 3})
    sitl.wait_ready()
    assert sitl.target_system == sitl.instance + 1
    assert sitl.get_param("TRIG_INTERFACE") == 3.0          # given at boot
    sitl.set_params({"TRIG_MODE": 4, "MPC_XY_CRUISE": 7.5}, reboot=True)
    sitl.wait_ready()
    assert sitl.get_param("TRIG_MODE") == 4.0              # an INT32, sent bytewise
    assert sitl.get_param("MPC_XY_CRUISE") == 7.5          # a FLOAT
    with pytest.raises(LinkError, match="SR2_POSITION"):
        sitl.set_params({"SR2_POSITION": 5})               # ArduPilot's name
    assert sitl.set_params({"SR2_POSITION": 5}, skip_unknown=True) == ["SR2_POSITION"]
    group = sitl._proc.pid
    sitl.close()
    assert not _group_alive(group)
    assert sitl.ulogs() and sitl.ulogs()[-1].suffix == ".ulg"   # one per boot, kept after close


def test_the_px4_folder_is_found_through_the_variable_or_not_at_all(tmp_path, monkeypatch):
    monkeypatch.setenv(PX4_DIR_VARIABLE, str(tmp_path))
    assert find_px4_dir() is None
    (tmp_path / "bin").mkdir()
    (tmp_path / "etc").mkdir()
    (tmp_path / "bin" / "px4").write_text("")
    assert find_px4_dir() == tmp_path.resolve()
