"""Thermal-aware planning: the blur budget and speed_mps: auto, the sun over a timed flight, the PV inspection
profile (night, too fast, too coarse, glare, a compliant noon flight), overlaps up to 95 %, and bad input for
every new key (located message, exit 1, nothing written)."""

from __future__ import annotations

import copy
import datetime as dt
from pathlib import Path
import re

from click.testing import CliRunner
import pytest
import yaml

from missions.compile import compile_plan
from missions.errors import PlanError
from missions.measure.report import format_report, report
from missions.plan.load import parse_plan
from missions.thermal.pv import SOURCES, PvProfile
from missions.thermal.sun import Plane, clear_sky_poa_wm2, glare_angle_deg, sun_position, viewing_angle_deg
from wiris_tools.cli import cli

ROOT = Path(__file__).resolve().parents[2]
# a 330 m × 220 m field of modules near Prague; the WIRIS Pro with 13 mm at 40 m images 5.23 cm/px
SQUARE = [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]
NOON = "2026-06-14T13:00+02:00"          # solar noon there is 13:01 CEST
PV = {
    "version": 1, "name": "pv",
    "when": NOON, "when_wind_mps": 2,
    "vehicle": {"firmware": "ardupilot", "frame": "copter", "speed_mps": "auto"},
    "home": {"lat": 50.1098, "lon": 14.5002, "alt_amsl_m": 262},
    "payloads": {"thermal": {"camera": "wiris-pro", "lens_mm": 13, "component_id": 100,
                             "settings": {"range_mode": "manual", "emissivity": 0.85}}},
    "mission": [
        {"takeoff": {"alt_m": 40}},
        {"survey": {"area": SQUARE, "payloads": ["thermal"], "altitude_m": 40, "overlap": {"front": 80, "side": 70},
                    "profile": "pv-inspection", "target": {"tilt_deg": 25, "azimuth_deg": 180}}},
        {"rtl": {}},
    ],
}


def survey(doc: dict) -> dict:
    return doc["mission"][1]["survey"]


def write(tmp_path: Path, change=None) -> Path:
    doc = copy.deepcopy(PV)
    if change:
        change(doc)
    path = tmp_path / "plan.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def build(tmp_path: Path, change=None):
    path = write(tmp_path, change)
    return compile_plan(parse_plan(path.read_text(), str(path), tmp_path))


def error_of(tmp_path: Path, change) -> PlanError:
    with pytest.raises(PlanError) as ei:
        build(tmp_path, change)
    return ei.value


def line_of(path: Path, key: str) -> int:
    """1-based line of the first `key:` in the written plan."""
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if re.search(rf"\b{key}:", line))


def codes(compiled) -> set[str]:
    return {getattr(w, "code", str(w).split(":")[0]) for w in compiled.warnings}


# ------------------------------------------------------------------------------------------- the five cases

def test_a_compliant_noon_flight_passes(tmp_path):
    c = build(tmp_path)
    assert not {"glare", "pv_emissivity", "pv_range_mode", "pv_when_missing", "sun_below_horizon"} & codes(c)
    (row,) = c.sun
    assert 62.5 < row.sun_start.elevation_deg < 64.0              # Prague, mid-June, solar noon: ~63.2°
    assert 11.9 < row.solar_time_start_h < 12.1
    assert row.clear_sky_min_wm2 > 900 and row.viewing_angle_deg == pytest.approx(25.0)
    rep = report(c)
    assert rep.to_json()["sun"][0]["profile"] == "pv-inspection (module level)"
    assert "measure on site" in format_report(rep)


def test_a_night_time_flight_is_an_error_at_when(tmp_path):
    e = error_of(tmp_path, lambda d: d.update(when="2026-06-14T23:30+02:00"))
    assert "night-time flight" in e.message and "below the horizon" in e.message
    assert e.where.endswith(f":{line_of(write(tmp_path, lambda d: d.update(when='x')), 'when')}:7")
    assert "fly between" in e.hint


def test_a_too_fast_flight_names_the_fastest_sharp_speed(tmp_path):
    def fast(d):
        d["vehicle"]["speed_mps"] = 8
        survey(d)["overlap"]["front"] = 60     # photos 10.7 m apart: 1.3 s at 8 m/s, the interval holds
        del survey(d)["profile"]          # the blur budget holds for every thermal survey, profile or not
    e = error_of(tmp_path, fast)
    assert "fastest sharp speed is 5.2 m/s" in e.message           # 1 px of 5.23 cm in 10 ms
    assert e.where.endswith(f":{line_of(write(tmp_path, fast), 'speed_mps')}:14")
    assert "fly at 5.2 m/s or slower" in e.hint


def test_a_too_coarse_gsd_for_cell_level_says_how_low_to_fly(tmp_path):
    e = error_of(tmp_path, lambda d: survey(d).update(profile={"name": "pv-inspection", "level": "cell"}))
    assert "GSD 5.23 cm/px is too coarse for a cell level" in e.message
    assert "altitude_m: 22.9 or below" in e.hint and "longer lens" in e.hint


def test_a_glare_geometry_is_warned(tmp_path):
    # flat-ish rows (13°, facing south) at solar noon in June: the sun (63° up) mirrors straight up into a
    # nadir camera
    c = build(tmp_path, lambda d: survey(d)["target"].update(tilt_deg=13))
    assert "glare" in codes(c)
    assert c.sun[0].glare_min_deg < 2.0
    glare = next(w for w in c.warnings if getattr(w, "code", "") == "glare")
    assert "camera_pitch_deg" in glare.message


# ------------------------------------------------------------------------------------------ the other checks

@pytest.mark.parametrize("change,fragment,hint", [
    (lambda d: d.update(when="2026-06-14T18:30+02:00"), "solar time, outside the profile's 10:00-15:00",
     "fly between"),
    (lambda d: d.update(when="2026-12-15T12:00+01:00"), "only", "another hour or season"),
    (lambda d: d.update(when_wind_mps=6), "wind 6 m/s is above the profile's 4 m/s", "calmer day"),
    (lambda d: survey(d)["target"].update(tilt_deg=40), "40.0° off their normal", "camera_pitch_deg"),
    (lambda d: survey(d).update(profile={"name": "pv-inspection", "max_gsd_cm_module": 4}),
     "the profile asks for 4 cm/px", "altitude_m: 30.5"),
])
def test_profile_violations_say_what_to_change(tmp_path, change, fragment, hint):
    e = error_of(tmp_path, change)
    said = f"{e.message} {e.hint}"            # several problems: one message lists each with its hint
    assert fragment in said and hint in said


def test_winter_irradiance_estimate_is_below_the_profile(tmp_path):
    e = error_of(tmp_path, lambda d: d.update(when="2026-12-15T12:00+01:00"))
    assert "W/m²" in e.message and "measured on site" in e.message and "another hour or season" in e.hint


def test_a_pitched_camera_meets_the_viewing_angle(tmp_path):
    c = build(tmp_path, lambda d: survey(d)["target"].update(tilt_deg=40) or survey(d).update(camera_pitch_deg=20))
    assert c.sun[0].viewing_angle_deg == pytest.approx(20.0)


def test_radiometric_settings_against_the_profile_are_warned(tmp_path):
    c = build(tmp_path, lambda d: d["payloads"]["thermal"].update(settings={"emissivity": 0.98}))
    assert {"pv_emissivity", "pv_range_mode"} <= codes(c)


def test_a_profile_without_when_is_warned_and_still_checks_the_gsd(tmp_path):
    c = build(tmp_path, lambda d: d.pop("when"))
    assert "pv_when_missing" in codes(c) and c.sun == ()


def test_a_step_when_overrides_the_plan_when(tmp_path):
    c = build(tmp_path, lambda d: survey(d).update(when="2026-06-14T12:00+02:00"))
    assert c.sun[0].start == dt.datetime.fromisoformat("2026-06-14T12:00+02:00")


def test_night_without_profile_is_a_warning(tmp_path):
    def night(d):
        d["when"] = "2026-06-14T01:00+02:00"
        del survey(d)["profile"]
    assert "sun_below_horizon" in codes(build(tmp_path, night))


# ----------------------------------------------------------------------------------------------- the speed

def test_speed_auto_takes_the_tighter_of_interval_and_blur(tmp_path):
    c = build(tmp_path)
    # 80 % front at 40 m: a photo every 5.36 m; 1 s with 20 % margin -> 4.47; blur 1 px of 5.23 cm -> 5.23
    assert c.speed_mps == 4.4
    auto = next(w for w in c.warnings if getattr(w, "code", "") == "speed_auto")
    assert "4.4 m/s" in auto.message and "1 s between photos" in auto.message
    # at 60 % front the photos are 10.7 m apart: the blur budget is tighter
    c = build(tmp_path, lambda d: survey(d)["overlap"].update(front=60))
    assert c.speed_mps == 5.2
    assert "time constant" in next(w for w in c.warnings if getattr(w, "code", "") == "speed_auto").message


def test_speed_auto_is_capped_by_max_speed(tmp_path):
    c = build(tmp_path, lambda d: d["vehicle"].update(max_speed_mps=3))
    assert c.speed_mps == 3.0
    assert "vehicle.max_speed_mps" in next(w for w in c.warnings if getattr(w, "code", "") == "speed_auto").message


def test_a_larger_blur_budget_allows_a_faster_speed(tmp_path):
    c = build(tmp_path, lambda d: d["vehicle"].update(speed_mps=8) or survey(d).update(blur_px=2)
              or survey(d)["overlap"].update(front=60))
    assert c.speed_mps == 8


def test_an_explicit_speed_above_max_speed_is_an_error(tmp_path):
    e = error_of(tmp_path, lambda d: d["vehicle"].update(speed_mps=4, max_speed_mps=3))
    assert "above vehicle.max_speed_mps 3" in e.message


def test_hover_holds_long_enough_for_the_time_constant(tmp_path):
    from missions.compiler.lines import hover_hold_s
    from missions.compiled import PayloadInfo

    slow = PayloadInfo("t", "wiris-pro", "thermal", 100, 13, (10.9, 8.7), (640, 512), min_interval_s=1.0,
                       time_constant_ms=1000.0)
    assert hover_hold_s(slow) == pytest.approx(6.0)            # 5 time constants + the capture interval


# ------------------------------------------------------------------------------------------------ overlaps

def test_overlaps_up_to_95_percent_are_planned_and_measured(tmp_path):
    def dense(d):
        survey(d)["overlap"] = {"front": 95, "side": 90}
        survey(d)["area"] = [[50.1100, 14.5000], [50.1100, 14.5012], [50.1108, 14.5012], [50.1108, 14.5000]]
        d["vehicle"]["speed_mps"] = 1.2
        del survey(d)["profile"]
    c = build(tmp_path, dense)
    (area,) = c.areas
    along = 8.704 * 40 / 13                                       # 26.8 m footprint along track
    assert area.trigger_distance_m == pytest.approx(along * 0.05, rel=1e-3)
    ov = report(c).overlap["thermal"]
    assert ov.front_min >= 0.949 and ov.side_min >= 0.899


# --------------------------------------------------------------------------------------------- sun module

def test_sun_and_clear_sky_agree_with_pvlib():
    """Reference values computed once with pvlib 0.16.1 (solarposition.get_solarposition, apparent elevation;
    irradiance.get_total_irradiance, isotropic sky, albedo 0.2, fed this module's ASHRAE DNI/DHI)."""
    when = dt.datetime.fromisoformat("2026-06-14T13:01+02:00")
    sun = sun_position(50.07, 14.73, when)
    assert sun.elevation_deg == pytest.approx(63.21, abs=0.02)
    for tilt, pvlib_poa in ((0, 885.447), (13.3, 955.276), (25, 980.846)):
        assert clear_sky_poa_wm2(when, sun, Plane(tilt, 180)) == pytest.approx(pvlib_poa, abs=0.1)
    assert clear_sky_poa_wm2(when, sun_position(50.07, 14.73, when.replace(hour=1)), Plane(0, 180)) == 0.0


def test_view_and_glare_geometry():
    assert viewing_angle_deg(Plane(30, 180), 0) == pytest.approx(30)
    assert viewing_angle_deg(Plane(30, 180), 30) == pytest.approx(0, abs=1e-6)
    # a sun straight along the normal of modules the camera views head-on: the camera sees its reflection
    plane = Plane(30, 180)
    from missions.thermal.sun import SunPosition
    assert glare_angle_deg(SunPosition(60, 180), plane, 30) == pytest.approx(0, abs=1e-6)
    assert glare_angle_deg(SunPosition(10, 0), plane, 0) is None          # behind the modules


def test_every_profile_number_is_documented_with_its_source():
    doc = (ROOT / "docs" / "pv-inspection.md").read_text()
    profile = PvProfile()
    for name in SOURCES:
        value = getattr(profile, name)
        assert f"`{name}`" in doc, name
        row = next(line for line in doc.splitlines() if line.startswith(f"| `{name}` |"))
        assert (f"{value:g}" if isinstance(value, float) else str(value)) in row, name
    assert set(PvProfile.OVERRIDABLE) <= set(SOURCES)


# ------------------------------------------------------------------------------------------------ bad input

BAD = {
    "when-text": (lambda d: d.update(when="tomorrow noon"), "is not an ISO 8601 date and time"),
    "when-no-offset": (lambda d: d.update(when="2026-06-14T11:30"), "has no UTC offset"),
    "when-no-time": (lambda d: d.update(when="2026-06-14"), "gives a date but no time of day"),
    "step-when": (lambda d: survey(d).update(when="noon"), "is not an ISO 8601"),
    "wind": (lambda d: d.update(when_wind_mps=-1), "when_wind_mps"),
    "blur": (lambda d: survey(d).update(blur_px=0), "blur_px"),
    "tilt": (lambda d: survey(d)["target"].update(tilt_deg=100), "tilt_deg"),
    "target-missing-key": (lambda d: survey(d).update(target={"tilt_deg": 20}), "azimuth_deg"),
    "pitch": (lambda d: survey(d).update(camera_pitch_deg="down"), "camera_pitch_deg"),
    "profile-name": (lambda d: survey(d).update(profile="pv"), "not a profile"),
    "profile-level": (lambda d: survey(d).update(profile={"name": "pv-inspection", "level": "row"}), "profile"),
    "profile-override": (lambda d: survey(d).update(profile={"name": "pv-inspection", "min_sun": 3}), "profile"),
    "profile-no-target": (lambda d: survey(d).pop("target"), "needs the modules' plane"),
    "profile-window": (lambda d: survey(d).update(profile={"name": "pv-inspection", "solar_time_from_h": 16}),
                       "is above solar_time_to_h"),
    "speed-text": (lambda d: d["vehicle"].update(speed_mps="fast"), "must be a number of m/s or auto"),
    "max-speed": (lambda d: d["vehicle"].update(max_speed_mps=100), "max_speed_mps"),
}


@pytest.mark.parametrize("key", sorted(BAD))
def test_bad_thermal_keys_exit_1_located_and_write_nothing(tmp_path, key):
    change, fragment = BAD[key]
    plan = write(tmp_path, change)
    out = tmp_path / "out"
    out.mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    r = CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert "Traceback" not in r.output
    assert re.search(rf"{plan.name}:\d+:\d+", r.output), r.output
    assert fragment in r.output, r.output
    assert "hint:" in r.output
    assert list(out.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == before
