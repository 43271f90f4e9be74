"""Compiled missions flown by PX4 1.16 SITL (SIH) in AUTO.MISSION from take-off to landing, with the WIRIS
emulator on the payload link and NAME.params given to PX4 at boot as written: the photos PX4 fires match the
report's prediction in number (1 % or 2), position (a few metres) and coverage (not below the report's minus
0.5 points), and each flight leaves its ULog in the SITL's folder.

A trigger of PX4's camera_trigger reaches the camera as IMAGE_START_CAPTURE and DO_DIGICAM_CONTROL (its
CAMERA_TRIGGER stream sends both), and a WIRIS takes a photo on each; PX4 also resends a command whose ACK is
late, which at a high simulated speed happens. So the shots PX4 fired are counted by the sequence number
camera_trigger puts in each IMAGE_START_CAPTURE, and placed where the camera took them: images within
SAME_SHOT_M of the one before are the same shot (a resend comes a few hundred simulated ms later)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from click.testing import CliRunner

import sitl_plans
from missions.compile import compile_plan
from wiris_tools.cli import cli
from wiris_tools.sitl.photos import check_photos
from wiris_tools.sitl.px4_flight import fly_compiled_px4

pytestmark = [pytest.mark.sitl, pytest.mark.slow]

SAME_SHOT_M = 2.0     # well under the trigger spacings flown here (6.8 m)


def _compile(plan: Path, out: Path) -> None:
    res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(out)])
    assert res.exit_code == 0, res.output


def _positions(photos) -> list[tuple[float, float, float]]:
    return [(p.position.lat / 1e7, p.position.lon / 1e7, p.position.relative_alt / 1e3) for p in photos]


def shots(positions: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
    """Consecutive images within SAME_SHOT_M of each other taken as one shot (the first of them)."""
    out: list[tuple[float, float, float]] = []
    for lat, lon, alt in positions:
        if out:
            plat, plon, _ = out[-1]
            dy = (lat - plat) * 111_320.0
            dx = (lon - plon) * 111_320.0 * math.cos(math.radians(lat))
            if math.hypot(dx, dy) < SAME_SHOT_M:
                continue
        out.append((lat, lon, alt))
    return out


def _fly(px4_dir, tmp_path, kind: str):
    path = sitl_plans.write_plan(tmp_path, kind, firmware="px4")
    _compile(path, tmp_path / "out")
    with fly_compiled_px4(px4_dir, tmp_path / "out", path.stem, workdir=tmp_path / "px4") as flight:
        images = _positions(flight.photos)
        logs = flight.sitl.ulogs()
        unknown = flight.unknown_params
        fired = flight.trigger_shots()
    check = check_photos(compile_plan(path), "thermal", shots(images))
    assert flight.upload["verified"]
    assert logs and logs[-1].stat().st_size > 100_000          # the flight's ULog, kept for the audit
    # MAV_1_CONFIG and SER_TEL2_BAUD name serial hardware SITL does not have (it starts its UDP links itself)
    assert set(unknown) <= {"MAV_1_CONFIG", "SER_TEL2_BAUD"}, unknown
    return check, images, fired


def _assert_matches(check) -> None:
    assert check.count_ok, check
    assert check.worst_offset_m < 5.0, check
    if not math.isnan(check.coverage_predicted):
        assert check.coverage_captured >= check.coverage_predicted - 0.005, check


def test_px4_survey_distance_triggered_matches_the_report(px4_dir, tmp_path):
    check, images, fired = _fly(px4_dir, tmp_path, "survey")
    assert abs(fired - check.predicted) <= max(2, 0.01 * check.predicted), (fired, check)
    _assert_matches(check)
    assert check.captured > 50
    assert len(images) > fired     # the WIRIS saved more images than PX4 fired shots (two commands each)


def test_px4_waypoint_captures_take_one_photo_each(px4_dir, tmp_path):
    # NAME.params turns camera_trigger off for a plan without a triggered survey (TRIG_MODE 0): each
    # IMAGE_START_CAPTURE of one image then reaches the camera as one DO_DIGICAM_CONTROL
    check, images, fired = _fly(px4_dir, tmp_path, "waypoints")
    _assert_matches(check)
    assert check.captured == 3 and len(images) == 3 and fired == 0     # camera_trigger off: no shots of its own
