"""Capture-plan loader: every named bad case gets a located problem with a hint; every problem is reported."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from missions.errors import PlanError
from missions.plan import MAX_PLAN_BYTES, load_plan, parse_plan
from missions.plan.schema import plan_schema

PLANS = Path(__file__).resolve().parent / "plans"
LOC = re.compile(r"^(?P<file>.+):(?P<line>\d+):(?P<col>\d+)$")

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


def problems_of(text: str, tmp_path: Path) -> list:
    p = tmp_path / "plan.yaml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(PlanError) as ei:
        load_plan(p)
    probs = ei.value.problems
    for pr in probs:
        assert pr.where.startswith(str(p)), pr
    return list(probs)


def one(text: str, tmp_path: Path, needle: str):
    probs = problems_of(text, tmp_path)
    hits = [p for p in probs if needle in p.message]
    assert hits, [str(p) for p in probs]
    return hits[0]


def line_col(where: str) -> tuple[int, int]:
    m = LOC.match(where)
    assert m, where
    return int(m["line"]), int(m["col"])


def test_good_plan_loads_with_locations():
    plan = load_plan(PLANS / "good.yaml")
    assert plan.name == "good-survey"
    assert [p.name for p in plan.payloads] == ["thermal", "multispectral"]
    thermal = plan.payload("thermal")
    assert thermal.value("layout") == 2 and thermal.value("capture") == 0x01 | 0x08
    # the location of a value is its own line and column in the file
    text = (PLANS / "good.yaml").read_text().splitlines()
    line, col = line_col(plan.where("mission", 1, "survey", "altitude_m"))
    assert text[line - 1][col - 1:].startswith("60")


def test_unknown_key_did_you_mean(tmp_path):
    p = one(BASE.replace("overlap: {front: 80, side: 70}", "overlap: {front: 80, side: 70}\n      refly90: true"),
            tmp_path, "unknown key 'refly90'")
    assert "refly_90" in p.hint
    assert line_col(p.where) == (18, 7)


def test_wrong_unit_names_the_unit_key(tmp_path):
    p = one(BASE.replace("altitude_m: 40", "altitude: 40"), tmp_path, "unknown key 'altitude'")
    assert "altitude_m" in p.hint
    p = one(BASE.replace("speed_mps: 5", "speed_kmh: 18"), tmp_path, "unknown key 'speed_kmh'")
    assert "speed_mps" in p.hint and "unit" in p.hint


def test_setting_value_not_in_catalogue_lists_allowed_values(tmp_path):
    p = one(BASE.replace("layout: fullscreen", "layout: full"), tmp_path, "'full' is not a choice")
    for option in ("inspection", "security", "fullscreen", "blended"):
        assert option in p.hint


def test_setting_out_of_range_uses_catalogue_message(tmp_path):
    p = one(BASE.replace("layout: fullscreen", "emissivity: 1.5"), tmp_path, "emissivity")
    assert "out of range" in p.message and "0.5" in p.hint and "1" in p.hint


def test_unknown_setting_did_you_mean(tmp_path):
    p = one(BASE.replace("layout: fullscreen", "pallete: 3"), tmp_path, "no setting 'pallete'")
    assert "'palette'" in p.hint


def test_when_condition_of_a_slot(tmp_path):
    p = one(BASE.replace("layout: fullscreen", "range_min_c: 10"), tmp_path, "range_min_c takes effect only")
    assert "range_mode: manual" in p.hint


REDEDGE_ONLY = BASE.replace("    camera: wiris-pro\n    lens_mm: 13\n    component_id: 101\n"
                            "    settings: {layout: fullscreen}", "    camera: rededge-mx\n    settings: {SETTINGS}")


def test_rededge_exposure_settings_load_and_need_manual_mode(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text(REDEDGE_ONLY.replace("SETTINGS", "exposure_mode: manual, shutter_divisor: 2000, iso: iso200"))
    assert load_plan(path).payload("thermal").values == (("exposure_mode", 4), ("shutter_divisor", 2000), ("iso", 2))
    p = one(REDEDGE_ONLY.replace("SETTINGS", "shutter_divisor: 2000"), tmp_path, "shutter_divisor takes effect only")
    assert "exposure_mode: manual" in p.hint


def test_rededge_manual_exposure_needs_every_field_of_the_message(tmp_path):
    # DIGICAM_CONFIGURE has no "keep" value: manual mode without a gain would send a made-up one
    text = REDEDGE_ONLY.replace("SETTINGS", "exposure_mode: manual, shutter_divisor: 2000")
    p = one(text, tmp_path, "exposure_mode: manual also needs iso")
    assert "DIGICAM_CONFIGURE" in p.message and "add `iso`" in p.hint
    assert line_col(p.where) == (8, 31)             # at the value that asks for manual mode
    assert len(problems_of(text, tmp_path)) == 1


@pytest.mark.parametrize("alt,word", [(1, "below the 2 m minimum"), (1.5, "below"), (501, "above the 500 m maximum")])
def test_altitude_limits(tmp_path, alt, word):
    one(BASE.replace("altitude_m: 40", f"altitude_m: {alt}"), tmp_path, word)


@pytest.mark.parametrize("front", [100, 150])
def test_overlap_100_percent_or_more(tmp_path, front):
    p = one(BASE.replace("front: 80", f"front: {front}"), tmp_path, "front overlap")
    assert "100" in p.message


def test_overlap_above_planner_limit(tmp_path):
    one(BASE.replace("side: 70", "side: 97"), tmp_path, "above the 95 %")


def test_unknown_payload(tmp_path):
    p = one(BASE.replace("payloads: [thermal]", "payloads: [thermla]"), tmp_path, "unknown payload 'thermla'")
    assert "'thermal'" in p.hint


def test_unknown_camera_id(tmp_path):
    p = one(BASE.replace("camera: wiris-pro", "camera: wiris-por"), tmp_path, "unknown camera 'wiris-por'")
    assert "wiris-pro" in p.hint


def test_altitude_and_gsd_both(tmp_path):
    one(BASE.replace("altitude_m: 40", "altitude_m: 40\n      gsd_cm: 3"), tmp_path, "both altitude_m and gsd_cm")
    one(BASE.replace("      altitude_m: 40\n", ""), tmp_path, "needs altitude_m or gsd_cm")


REDEDGE = """
  ms:
    camera: rededge-mx
"""


def test_wiris_and_rededge_on_component_100(tmp_path):
    text = BASE.replace("component_id: 101", "component_id: 100").replace("mission:", REDEDGE.lstrip("\n") + "mission:")
    text = text.replace("    camera: rededge-mx\n", "    camera: rededge-mx\n    component_id: 100\n")
    p = one(text, tmp_path, "both on component 100")
    assert "101..105" in p.hint and "RedEdge" in p.message


def test_unspecified_wiris_moves_off_100_next_to_rededge(tmp_path):
    text = BASE.replace("    component_id: 101\n", "").replace("mission:", REDEDGE.lstrip("\n") + "mission:")
    plan = parse_plan(text, str(tmp_path / "p.yaml"), tmp_path)
    assert plan.payload("ms").component_id == 100
    assert plan.payload("thermal").component_id == 101
    assert any("101" in n for n in plan.notes)


def test_rededge_cannot_move(tmp_path):
    text = BASE.replace("mission:", REDEDGE.lstrip("\n") + "mission:").replace(
        "    camera: rededge-mx\n", "    camera: rededge-mx\n    component_id: 102\n")
    one(text, tmp_path, "cannot use component id 102")


def test_every_problem_reported_in_position_order(tmp_path):
    text = (BASE.replace("speed_mps: 5", "speed: 5").replace("layout: fullscreen", "layout: nope")
            .replace("altitude_m: 40", "altitude_m: 900").replace("payloads: [thermal]", "payloads: [x]"))
    probs = problems_of(text, tmp_path)
    assert len(probs) >= 5    # missing speed_mps, unknown speed, layout, altitude, payload
    positions = [line_col(p.where) for p in probs]
    assert positions == sorted(positions)
    with pytest.raises(PlanError) as ei:
        parse_plan(text, "x.yaml", tmp_path)
    assert f"{len(ei.value.problems)} problems" in str(ei.value)


def test_area_file_relative_to_plan(tmp_path):
    sub = tmp_path / "sub"
    (sub / "areas").mkdir(parents=True)
    shutil.copy(PLANS / "areas" / "field.geojson", sub / "areas" / "field.geojson")
    text = BASE.replace("area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]",
                        "area: areas/field.geojson")
    (sub / "p.yaml").write_text(text)
    plan = load_plan(sub / "p.yaml")
    assert plan.mission[1].area == "areas/field.geojson" and Path(plan.base_dir) == sub.resolve()
    (tmp_path / "p.yaml").write_text(text)
    one(text, tmp_path, "area file 'areas/field.geojson' not found")


def test_area_name_the_system_refuses_is_a_located_problem(tmp_path):
    # Path.is_file() raises for a name longer than NAME_MAX (255 bytes) instead of answering False
    long = "x" * 300 + ".geojson"
    text = BASE.replace("area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]",
                        f"area: {long}")
    p = one(text, tmp_path, "cannot be looked up")
    assert line_col(p.where) == (14, 13) and "relative to the plan file" in p.hint


@pytest.mark.parametrize("exclude", ["5", "0.5", "true", "{a: 1}", "areas/one.geojson"])
def test_exclude_of_the_wrong_type_is_the_schemas_finding(tmp_path, exclude):
    text = BASE.replace("      payloads: [thermal]\n", f"      exclude: {exclude}\n      payloads: [thermal]\n", 1)
    p = one(text, tmp_path, "exclude must be a list")
    assert line_col(p.where)[0] == 15


def test_yaml_syntax_error_located(tmp_path):
    p = one(BASE.replace("home: {lat", "home: [lat"), tmp_path, "invalid YAML")
    assert line_col(p.where)[0] >= 4


def test_duplicate_key(tmp_path):
    one(BASE.replace("name: t\n", "name: t\nname: u\n"), tmp_path, "duplicate key 'name'")


def test_alias_bomb_is_capped(tmp_path):
    bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
        f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
        for i in range(8))
    one(bomb, tmp_path, "more than")


def test_size_cap(tmp_path):
    with pytest.raises(PlanError, match="larger than"):
        parse_plan("#" * (MAX_PLAN_BYTES + 1), "big.yaml", tmp_path)


def test_yaml11_booleans_stay_words(tmp_path):
    plan = parse_plan(BASE.replace("layout: fullscreen", "alarm_mode: off"), "p.yaml", tmp_path)
    assert plan.payload("thermal").value("alarm_mode") == 0


def test_not_a_mapping(tmp_path):
    one("- just\n- a list\n", tmp_path, "a plan is a mapping")


def test_schema_is_valid_and_lists_steps():
    import jsonschema

    s = plan_schema()
    jsonschema.Draft202012Validator.check_schema(s)
    assert set(s["properties"]["mission"]["items"]["properties"]) == {
        "takeoff", "survey", "corridor", "waypoint", "camera", "rtl", "land"}


def test_land_needs_both_coordinates(tmp_path):
    one(BASE.replace("  - rtl: {}", "  - land: {lat: 50.11}"), tmp_path, "both lat and lon")


def test_a_value_yaml_reads_as_infinite_is_reported_once(tmp_path):
    # `.inf` is a float in YAML: one problem at that spot, not also "name must be text, got nothing"
    probs = problems_of(BASE.replace("name: t", "name: .inf"), tmp_path)
    assert [p.message for p in probs] == ["'.inf' is not a finite number"]
    assert "quote" in probs[0].hint
    # in an inline area, not also "area must be a file path or a list of points"
    probs = problems_of(BASE.replace("[50.1100, 14.5030]", "[50.1100, .nan]", 1), tmp_path)
    assert [p.message for p in probs] == ["'.nan' is not a finite number"]


@pytest.mark.parametrize("written, hint", [('"40"', "remove the quotes: 40"), ("40m", "write the number alone (40)"),
                                           ("40 m", "write the number alone (40)")])
def test_a_number_written_as_text_gets_a_hint_that_fixes_it(tmp_path, written, hint):
    p = one(BASE.replace("altitude_m: 40", f"altitude_m: {written}"), tmp_path, "must be a number")
    assert p.hint.startswith(hint), p


def test_a_mapping_of_the_wrong_type_hints_its_keys(tmp_path):
    p = one(BASE.replace("home: {lat: 50.1098, lon: 14.5002, alt_amsl_m: 262}", "home: 262"), tmp_path,
            "home must be a mapping")
    assert p.hint == ("the take-off point, alt_amsl_m its elevation (from terrain.dem when left out): "
                      "write {lat: ..., lon: ...}")
    p = one(BASE.replace("  - rtl: {}", "  - rtl: 1"), tmp_path, "rtl must be")
    assert p.message.endswith("must be a mapping or nothing, got 1")  # not "object or null"
    assert "write {}" in p.hint


@pytest.mark.parametrize("frame,needle", [("plane", "a plane cannot hover"), ("vtol", "fixed-wing flight")])
def test_hover_refused_for_fixed_wing_flight(tmp_path, frame, needle):
    """After NAV_VTOL_TAKEOFF a VTOL flies the mission as a plane (no transition back is emitted): ArduPlane drops
    NAV_WAYPOINT's hold time and PX4 flies through, so hover-and-capture would photograph nothing it promised."""
    text = BASE.replace("frame: copter", f"frame: {frame}").replace("overlap: {front: 80, side: 70}",
                                                                      "overlap: {front: 80, side: 70}\n      trigger: hover")
    p = one(text, tmp_path, needle)
    assert "trigger: distance" in p.hint


# ------------------------------------------------------------------ physical ranges, numbers, echoed values

@pytest.mark.parametrize("frame,speed,message", [
    ("copter", "1e-9", "vehicle.speed_mps 1e-09 is below the minimum of 0.5"),     # YAML 1.2 reads it as a number
    ("copter", "1.0e-9", "vehicle.speed_mps 1e-09 is below the minimum of 0.5"),
    ("copter", "0", "vehicle.speed_mps 0 is below the minimum of 0.5"),
    ("copter", "30", "vehicle.speed_mps 30 is above the maximum of 25"),
    ("copter", "1e308", "vehicle.speed_mps 1e+308 is above the maximum of 25"),
    ("plane", "5", "vehicle.speed_mps 5 is below the minimum of 8"),
    ("vtol", "41", "vehicle.speed_mps 41 is above the maximum of 40"),
])
def test_speed_has_a_plausible_range_per_frame(tmp_path, frame, speed, message):
    from missions.plan.schema import SPEED_RANGE_MPS

    probs = problems_of(BASE.replace("frame: copter, speed_mps: 5", f"frame: {frame}, speed_mps: {speed}"), tmp_path)
    assert [p.message for p in probs] == [message]
    lo, hi = SPEED_RANGE_MPS[frame]
    assert probs[0].hint == f"a {'VTOL' if frame == 'vtol' else frame} surveys at {lo:g} to {hi:g} m/s"


def test_speeds_in_range_load_for_each_frame(tmp_path):
    for frame, speed in (("copter", 0.5), ("copter", 25), ("plane", 30), ("vtol", 8)):
        text = BASE.replace("frame: copter, speed_mps: 5", f"frame: {frame}, speed_mps: {speed}")
        assert parse_plan(text, "p.yaml", tmp_path).vehicle.speed_mps == speed


def test_the_schema_carries_the_speed_ranges_editors_check():
    import jsonschema

    from missions.plan.schema import SPEED_RANGE_MPS

    validator = jsonschema.Draft202012Validator(plan_schema()["properties"]["vehicle"])
    for frame, (lo, hi) in SPEED_RANGE_MPS.items():
        for speed, ok in ((lo, True), (hi, True), (lo * 0.99, False), (hi * 1.01, False)):
            v = {"firmware": "px4", "frame": frame, "speed_mps": speed}
            assert validator.is_valid(v) is ok, (frame, speed)


def test_a_bound_that_excludes_its_limit_reads_as_english(tmp_path):
    p = one(BASE.replace("lens_mm: 13", "lens_mm: 0"), tmp_path, "lens_mm")
    assert p.message == "payloads.thermal.lens_mm must be greater than 0, got 0"
    assert "focal length" in p.hint and "above 0 and at most 1000" in p.hint     # the range, not "write a number"
    p = one(BASE.replace("  - rtl: {}", "  - corridor: {line: [[50.11, 14.50], [50.12, 14.52]], width_m: 0.2, "
                                        "payloads: [thermal], altitude_m: 50, overlap: {front: 80, side: 60}}\n"
                                        "  - rtl: {}"), tmp_path, "width_m")
    assert p.message == "mission[2].corridor.width_m 0.2 is below the minimum of 1" and "1 to 5000 m" in p.hint


@pytest.mark.parametrize("written,quoted", [('"40"', True), ("'40'", True), ("1e308x", False), ("forty", False)])
def test_remove_the_quotes_only_where_there_are_quotes(tmp_path, written, quoted):
    p = one(BASE.replace("altitude_m: 40", f"altitude_m: {written}"), tmp_path, "must be a number")
    assert p.hint.startswith("remove the quotes") is quoted, p.hint


def test_a_number_too_long_to_read_is_one_short_problem(tmp_path):
    probs = problems_of(BASE.replace("altitude_m: 40", "altitude_m: " + "9" * 5000), tmp_path)
    assert [p.message for p in probs] == ["a number of 5000 characters is too long to read"]
    assert "99999" not in probs[0].hint and len(probs[0].message) + len(probs[0].hint) < 200
    assert line_col(probs[0].where) == (16, 19)


def test_an_infinite_exponent_is_not_a_finite_number(tmp_path):
    one(BASE.replace("altitude_m: 40", "altitude_m: 1e999"), tmp_path, "'1e999' is not a finite number")


@pytest.mark.parametrize("edit", [("name: t", "name: " + "n" * 5000), ("layout: fullscreen", "layout: " + "l" * 5000),
                                  ("  - rtl: {}", "  - " + "s" * 1000 + ": {}"),
                                  ("firmware: ardupilot", "firmware: " + "f" * 5000),
                                  ("overlap: {front: 80,", "overlap: {" + "k" * 1000 + ": 1, front: 80,"),
                                  ("payloads: [thermal]", "payloads: [" + "p" * 5000 + "]"),
                                  ("altitude_m: 40", "altitude_m: " + "9" * 4000)])
def test_echoed_values_are_cut(tmp_path, edit):
    probs = problems_of(BASE.replace(*edit), tmp_path)
    for p in probs:
        assert len(p.message) < 250 and len(p.hint or "") < 400, p
    assert any(" characters)" in p.message or "digits" in p.message for p in probs), probs


def test_a_directory_named_as_an_area_is_a_directory(tmp_path):
    (tmp_path / "areas").mkdir()
    (tmp_path / "areas" / "field.geojson").mkdir()
    text = BASE.replace("area: [[50.1100, 14.5000], [50.1100, 14.5030], [50.1120, 14.5030], [50.1120, 14.5000]]",
                        "area: areas/field.geojson")
    p = one(text, tmp_path, "area file 'areas/field.geojson' is a directory, not a file")
    assert "relative to the plan file" in p.hint


def test_a_plan_that_is_a_device_or_a_directory_is_refused(tmp_path):
    with pytest.raises(PlanError) as err:
        load_plan("/dev/zero")
    assert err.value.message == "is a character device, not a file" and "give -" in err.value.hint
    with pytest.raises(PlanError, match="is a directory, not a file"):
        load_plan(tmp_path)
