"""Fixtures that start ArduPilot SITL (the real firmware, see wiris_tools.sitl) for the tests in this folder.

The SITL folder comes from $WIRIS_SITL_DIR or ../shared/sitl beside the checkout; without one every test
here is skipped with that reason. Each module shares one SITL where it can (`copter` fixture); a test that
needs its own (a camera on the camera link, a plane) starts one with `start_vehicle`.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from wiris_tools.sitl import SitlOptions, find_sitl_dir, missing_sitl_reason, start_sitl

ROOT = Path(__file__).resolve().parents[2]
SPEEDUP = 20


@pytest.fixture(scope="session")
def sitl_dir() -> Path:
    found = find_sitl_dir(near=ROOT)
    if found is None:
        pytest.skip(missing_sitl_reason())
    return found


@pytest.fixture(scope="module")
def copter(sitl_dir, tmp_path_factory):
    """One copter SITL for a whole module, ready to arm."""
    with start_sitl("ardupilot", sitl_dir, SitlOptions(speedup=SPEEDUP,
                                                       workdir=tmp_path_factory.mktemp("sitl"))) as sitl:
        sitl.wait_ready()
        yield sitl


@pytest.fixture
def start_vehicle(sitl_dir, tmp_path):
    """start_vehicle(**SitlOptions fields) -> a started SITL, closed at the end of the test even on failure."""
    started = []

    def start(**options):
        options.setdefault("speedup", SPEEDUP)
        options.setdefault("workdir", tmp_path / f"sitl{len(started)}")
        sitl = start_sitl("ardupilot", sitl_dir, SitlOptions(**options))
        started.append(sitl)
        return sitl

    yield start
    for sitl in started:
        sitl.close()
