"""The SITL harness itself: a free instance and its own folder, ready to arm by the EKF and pre-arm flags,
parameters that survive a reboot, a tlog of the monitor link, and nothing left running after close()."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from pymavlink import mavutil

from wiris_tools.sitl import SITL_DIR_VARIABLE, find_sitl_dir

pytestmark = pytest.mark.sitl


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def test_two_harnesses_run_side_by_side_and_stop_without_leftovers(start_vehicle):
    a = start_vehicle()
    b = start_vehicle()
    assert a.instance != b.instance and a.workdir != b.workdir
    a.wait_ready()
    b.wait_ready()
    assert a.get_param("FRAME_CLASS") == 1.0   # quad, from the copter defaults
    groups = [a._proc.pid, b._proc.pid]
    a.close()
    b.close()
    assert not any(_group_alive(g) for g in groups)


def test_a_parameter_set_with_reboot_persists_and_the_tlog_records_the_link(start_vehicle):
    sitl = start_vehicle()
    sitl.wait_ready()
    sitl.set_params({"CAM1_TYPE": 6}, reboot=True)
    sitl.wait_ready()
    assert sitl.get_param("CAM1_TYPE") == 6.0
    sitl.close()
    log = mavutil.mavlink_connection(str(sitl.tlog))
    beats = 0
    while (msg := log.recv_match(type="HEARTBEAT")) is not None:
        beats += msg.get_srcComponent() == 1
    assert beats >= 2   # before and after the reboot


def test_a_parameter_the_firmware_lacks_is_an_error(start_vehicle):
    from wiris_tools.errors import LinkError
    sitl = start_vehicle()
    with pytest.raises(LinkError, match="SR2_POSITION"):
        sitl.set_params({"SR2_POSITION": 5})   # 4.7 names it MAV3_POSITION


def test_the_folder_is_found_through_the_variable_or_not_at_all(tmp_path, monkeypatch):
    monkeypatch.setenv(SITL_DIR_VARIABLE, str(tmp_path))
    assert find_sitl_dir() is None          # an empty folder is no SITL
    (tmp_path / "bin").mkdir()
    (tmp_path / "run-sitl").write_text("#!/bin/sh\n")
    assert find_sitl_dir() == tmp_path.resolve()
