"""Plausible mistakes are errors, each said once with the right hint: overlaps written as fractions, altitudes
above the 120 m rule (unless the plan states a permit), component ids outside 100..105, setting names and values
with did-you-mean, and every problem of a plan reported in one pass, ordered by line."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from missions.compile import compile_plan
from missions.errors import PlanError
from missions.plan import load_plan
from wiris_tools.cli import cli

BASE = """\
version: 1
name: t
vehicle: {firmware: ardupilot, frame: copter, speed_mps: 5}
home: {lat: 50.1098, lon: 14.5002, alt_amsl_m: 262}
payloads:
  thermal:
    camera: wiris-pro
    lens_mm: 13
    component_id: 101
    settings: {layout: fullscreen}
mission:
  - takeoff: {alt_m: 30}
  - survey:
      area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]
      payloads: [thermal]
      altitude_m: 40
      overlap: {front: 80, side: 70}
  - rtl: {}
"""


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "plan.yaml"
    p.write_text(text, encoding="utf-8")
    return p


def problems_of(tmp_path: Path, text: str) -> list:
    with pytest.raises(PlanError) as ei:
        compile_plan(write(tmp_path, text))
    return list(ei.value.problems)


def line_of(where: str) -> int:
    return int(where.rsplit(":", 2)[1])


def test_an_overlap_written_as_a_fraction_is_an_error_saying_percent(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("{front: 80, side: 70}", "{front: 0.8, side: 0.7}"))
    assert [p.hint for p in probs] == ["write percent: 80", "write percent: 70"]
    assert all("percent" in p.message and p.where.endswith(":17:24") or p.where.endswith(":17:35") for p in probs)


def test_an_overlap_of_1_or_more_percent_is_taken(tmp_path):
    plan = load_plan(write(tmp_path, BASE.replace("side: 70", "side: 1")))
    assert plan.mission[1].side_pct == 1.0


def test_a_feet_altitude_is_one_error_at_its_line_with_the_permit_hint(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("altitude_m: 40", "altitude_m: 400"))
    assert len(probs) == 1
    p = probs[0]
    assert line_of(p.where) == 16 and "120 m" in p.message and "without a permit" in p.message
    assert "400 ft would be 122 m" in p.hint and "max_altitude_m" in p.hint


@pytest.mark.parametrize("where,edit", [
    ("takeoff", ("takeoff: {alt_m: 30}", "takeoff: {alt_m: 130}")),
    ("waypoint", ("  - rtl: {}", "  - waypoint: {lat: 50.1105, lon: 14.5010, alt_m: 125}\n  - rtl: {}")),
])
def test_every_written_altitude_is_held_to_the_ceiling(tmp_path, where, edit):
    probs = problems_of(tmp_path, BASE.replace(*edit))
    assert len(probs) == 1 and "alt_m" in probs[0].message and "120 m" in probs[0].message


def test_a_gsd_that_needs_more_than_120_m_is_an_error_at_gsd_cm(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("altitude_m: 40", "gsd_cm: 20"))
    assert len(probs) == 1 and line_of(probs[0].where) == 16 and "gsd_cm 20" in probs[0].message
    assert "max_altitude_m" in probs[0].hint


def test_a_stated_permit_allows_the_altitude_and_warns_once(tmp_path):
    text = (BASE.replace("speed_mps: 5}", "speed_mps: 5, max_altitude_m: 150}")
            .replace("altitude_m: 40", "altitude_m: 140")
            .replace("  - rtl: {}", "  - waypoint: {lat: 50.1105, lon: 14.5010, alt_m: 130}\n  - rtl: {}"))
    c = compile_plan(write(tmp_path, text))
    high = [w for w in c.warnings if w.code == "altitude_above_120m"]
    assert len(high) == 1 and "140 m" in high[0].message and "max_altitude_m: 150" in high[0].message


def test_an_altitude_above_the_permit_is_an_error(tmp_path):
    text = BASE.replace("speed_mps: 5}", "speed_mps: 5, max_altitude_m: 150}").replace("altitude_m: 40",
                                                                                       "altitude_m: 160")
    probs = problems_of(tmp_path, text)
    assert len(probs) == 1 and "vehicle.max_altitude_m of 150 m" in probs[0].message and "160 m" in probs[0].message


@pytest.mark.parametrize("cid", [1, 0, 99, 106])
def test_a_component_id_outside_the_camera_range_is_one_finding(tmp_path, cid):
    probs = problems_of(tmp_path, BASE.replace("component_id: 101", f"component_id: {cid}"))
    assert len(probs) == 1
    assert "100 to 105" in probs[0].hint and "whole number" not in probs[0].hint


def test_the_rededge_on_a_wiris_id_is_still_its_own_finding(tmp_path):
    text = BASE.replace("camera: wiris-pro\n    lens_mm: 13", "camera: rededge-mx")
    text = text.replace("    settings: {layout: fullscreen}\n", "")
    probs = problems_of(tmp_path, text)
    assert len(probs) == 1 and "only on 100" in probs[0].hint


# ----------------------------------------------------------------------------------------- setting names

def test_a_misspelt_option_gets_did_you_mean(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("{layout: fullscreen}", "{range_mode: manuel}"))
    assert len(probs) == 1 and probs[0].hint.startswith("did you mean 'manual'?")


def test_a_misspelt_flag_in_a_list_gets_did_you_mean(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("{layout: fullscreen}", "{capture: [radiometric_jpg]}"))
    assert len(probs) == 1 and probs[0].hint.startswith("did you mean 'radiometric_jpeg'?")


def test_the_plan_takes_the_names_wiris_camera_set_takes(tmp_path):
    """PARAM_EXT names and ground-station labels, any case, are the same settings as the plan names."""
    text = BASE.replace("{layout: fullscreen}", "{RANGE_MODE: Manual, Layout: FULLSCREEN}")
    plan = load_plan(write(tmp_path, text))
    same = load_plan(write(tmp_path, BASE.replace("{layout: fullscreen}", "{range_mode: manual, layout: fullscreen}")))
    assert plan.payloads[0].values == same.payloads[0].values
    assert dict(plan.payloads[0].settings) == {"range_mode": "Manual", "layout": "FULLSCREEN"}


def test_one_setting_under_two_names_is_an_error(tmp_path):
    probs = problems_of(tmp_path, BASE.replace("{layout: fullscreen}", "{layout: fullscreen, LAYOUT: pip}"))
    assert len(probs) == 1 and "given twice" in probs[0].message


def test_a_misspelt_setting_name_gets_did_you_mean_in_either_form(tmp_path):
    for wrong, right in (("range_mod", "range_mode"), ("RANGE_MOD", "range_mode")):
        probs = problems_of(tmp_path, BASE.replace("{layout: fullscreen}", "{%s: manual}" % wrong))
        assert len(probs) == 1 and probs[0].hint.startswith(f"did you mean {right!r}?"), probs


def test_every_option_name_means_one_option():
    """A key or label of one option must not be another option's key or label (any case): else a name
    would be ambiguous between the plan and `wiris camera set`."""
    from cdf.catalogue import catalogue

    for cam in catalogue().cameras:
        for s in cam.settings:
            for o in s.options:
                assert s.option_named(o.key) == o and s.option_named(o.name) == o, (cam.id, s.key, o)
        for s in cam.settings:
            assert cam.setting_named(s.param.lower()) == s and cam.setting_named(s.key.upper()) == s


# ----------------------------------------------------------------------------------------- the CLI

def test_compile_of_a_plan_with_mistakes_exits_1_and_writes_nothing(tmp_path):
    text = BASE.replace("{front: 80, side: 70}", "{front: 0.8, side: 70}").replace("altitude_m: 40",
                                                                                   "altitude_m: 400")
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(write(tmp_path, text)), "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert "write percent: 80" in r.output and "max_altitude_m" in r.output and "Traceback" not in r.output
    assert not out.exists()


# ----------------------------------------------------------------------------------------- one pass

MANY = """\
version: 1
vehicle: {firmware: ardupilot, frame: copter, speed_mps: 4.5}
home: {lat: 50.1098, lon: 14.5002, alt_amsl_m: 262}
payloads:
  thermal:
    camera: wiris-pro
    lens_mm: 13
    component_id: 1
    settings: {range_mode: manuel}
  other: {camera: wiris-pro, lens_mm: 13, component_id: 101}   # ArduPilot finds CAM2 at 101 (102 would be refused)
mission:
  - takeoff: {alt_m: 40}
  - survey:
      area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030]]
      payloads: [thermal]
      altitude_m: 400
      overlap: {front: 0.8, side: 0.7}
  - waypoint: {lat: 14.5002, lon: 50.1098, alt_m: 40}
  - survey:
      area: areas/nothere.geojson
      payloads: [other]
      altitude_m: 40
      overlap: {front: 80, side: 70}
  - survey:
      area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030]]
      payloads: [other]
      gsd_cm: 30
      overlap: {front: 80, side: 70}
  - land: {lat: 14.5002, lon: 50.1098}
"""


def test_every_problem_of_every_stage_is_reported_at_once_ordered_by_line(tmp_path):
    """Schema (component id), catalogue (setting value), meaning (altitude, overlap, area file) and the
    compiler's own stages (swapped coordinates, a GSD's altitude) in one run: no rounds of fixing."""
    probs = problems_of(tmp_path, MANY)
    lines = [line_of(p.where) for p in probs]
    assert lines == sorted(lines)
    found = {line_of(p.where): p for p in probs}
    assert set(found) == {8, 9, 16, 17, 18, 20, 27, 29}, [str(p) for p in probs]
    assert "100 to 105" in found[8].hint
    assert found[9].hint.startswith("did you mean 'manual'?")
    assert "120 m" in found[16].message
    assert [p.hint for p in probs if line_of(p.where) == 17] == ["write percent: 80", "write percent: 70"]
    assert "swapped" in found[18].hint and "swapped" in found[29].hint
    assert "nothere.geojson" in found[20].message
    assert "gsd_cm 30" in found[27].message
    assert all(p.hint for p in probs)


def test_a_step_of_a_payload_with_a_problem_is_not_checked_twice(tmp_path):
    """The survey of the payload with a bad setting is skipped by the later stages (no second finding about
    it), the other payload's steps are still checked."""
    probs = problems_of(tmp_path, MANY.replace("altitude_m: 400", "altitude_m: 40").replace(
        "{front: 0.8, side: 0.7}", "{front: 80, side: 70}"))
    assert sorted({line_of(p.where) for p in probs}) == [8, 9, 18, 20, 27, 29]


def test_check_prints_every_problem_and_exits_1(tmp_path):
    r = CliRunner().invoke(cli, ["mission", "check", str(write(tmp_path, MANY))])
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert "9 problems in the plan" in r.output and r.output.count("hint:") == 9


def test_a_problem_outside_steps_and_payloads_stops_before_the_compiler(tmp_path):
    """A bad vehicle leaves nothing to compile: its problem is reported with the other loading ones."""
    probs = problems_of(tmp_path, MANY.replace("speed_mps: 4.5", "speed_mps: fast"))
    assert any(line_of(p.where) == 2 for p in probs)
    assert not any("swapped" in (p.hint or "") for p in probs)
