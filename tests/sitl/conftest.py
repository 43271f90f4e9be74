"""Fixtures that start ArduPilot or PX4 SITL (the real firmwares, see wiris_tools.sitl) for the tests here.

ArduPilot's folder comes from $WIRIS_SITL_DIR or ../shared/sitl beside the checkout, PX4's from
$WIRIS_PX4_SITL_DIR or ../shared/px4-sitl; a test needing one that is absent is skipped with that reason. Each module shares one SITL where it can (`copter` fixture); a test that
needs its own (a camera on the camera link, a plane) starts one with `start_vehicle`.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from wiris_tools.sitl import (SitlOptions, find_px4_dir, find_sitl_dir, missing_px4_reason, missing_sitl_reason,
                              start_sitl)

ROOT = Path(__file__).resolve().parents[2]
SPEEDUP = 20
PX4_SPEEDUP = 5       # PX4 times a mission transfer out in simulated time: at 10x a loaded machine misses it


@pytest.fixture(scope="session")
def sitl_dir() -> Path:
    found = find_sitl_dir(near=ROOT)
    if found is None:
        pytest.skip(missing_sitl_reason())
    return found


@pytest.fixture(scope="session")
def px4_dir() -> Path:
    found = find_px4_dir(near=ROOT)
    if found is None:
        pytest.skip(missing_px4_reason())
    return found


@pytest.fixture(scope="session")
def firmware_dir(request):
    """firmware_dir("ardupilot" | "px4") -> that SITL's folder, or the test is skipped with the reason."""
    def find(firmware: str) -> Path:
        return request.getfixturevalue("px4_dir" if firmware == "px4" else "sitl_dir")
    return find


@pytest.fixture(scope="module")
def px4_copter(px4_dir, tmp_path_factory):
    """One PX4 quadrotor (SIH) for a whole module, ready to arm."""
    with start_sitl("px4", px4_dir, SitlOptions(speedup=PX4_SPEEDUP,
                                                workdir=tmp_path_factory.mktemp("px4"))) as sitl:
        sitl.wait_ready()
        yield sitl


@pytest.fixture(scope="module")
def copter(sitl_dir, tmp_path_factory):
    """One copter SITL for a whole module, ready to arm."""
    with start_sitl("ardupilot", sitl_dir, SitlOptions(speedup=SPEEDUP,
                                                       workdir=tmp_path_factory.mktemp("sitl"))) as sitl:
        sitl.wait_ready()
        yield sitl


@pytest.fixture
def start_vehicle(firmware_dir, tmp_path):
    """start_vehicle(firmware="ardupilot" | "px4", **SitlOptions fields) -> a started SITL of that firmware,
    closed at the end of the test even on failure (skipped when that firmware's SITL is absent)."""
    started = []

    def start(firmware: str = "ardupilot", **options):
        options.setdefault("speedup", PX4_SPEEDUP if firmware == "px4" else SPEEDUP)
        options.setdefault("workdir", tmp_path / f"sitl{len(started)}")
        sitl = start_sitl(firmware, firmware_dir(firmware), SitlOptions(**options))
        started.append(sitl)
        return sitl

    yield start
    for sitl in started:
        sitl.close()
