"""`wiris mission schema|compile|check|preview` through click's CliRunner: outputs, exit codes, messages with
locations, and nothing written for a bad plan."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from mission_plans import BAD_PLANS, bad_plan, small_plan
from wiris_tools.cli import cli


def run(*args):
    return CliRunner().invoke(cli, list(map(str, args)))


def test_schema_is_json_schema():
    r = run("mission", "schema")
    assert r.exit_code == 0
    schema = json.loads(r.output)
    assert schema["$schema"].startswith("https://json-schema.org/")
    assert "mission" in schema["properties"]


def test_compile_writes_and_lists_files(tmp_path):
    plan = small_plan(tmp_path)
    out = tmp_path / "out"
    r = run("mission", "compile", plan, "-o", out)
    assert r.exit_code == 0, r.output
    # the files follow "wrote:" (the summary above it has indented lines too: the steps' numbers)
    lines = r.output.splitlines()
    listed = [line.strip() for line in lines[lines.index("wrote:") + 1:] if line.startswith("  ")]
    assert sorted(Path(p).name for p in listed) == sorted(p.name for p in out.iterdir())
    assert (out / "small.plan").exists() and "photos" in r.output


def test_compile_firmware_override(tmp_path):
    # PX4 cannot carry the in-flight range_mode change: a located error, nothing written
    r = run("mission", "compile", small_plan(tmp_path), "-o", tmp_path / "o", "--firmware", "px4")
    assert r.exit_code == 1 and "small.yaml:" in r.output and "PX4" in r.output
    assert not (tmp_path / "o").exists()
    plan = small_plan(tmp_path, camera_change=False)
    r = run("mission", "compile", plan, "-o", tmp_path / "o", "--firmware", "px4")
    assert r.exit_code == 0, r.output
    doc = json.loads((tmp_path / "o" / "small.plan").read_text())
    assert doc["mission"]["firmwareType"] == 12          # MAV_AUTOPILOT_PX4
    assert not (tmp_path / "o" / "small.lua").exists()   # the Lua bridge is ArduPilot's


def test_check_json_has_the_binding_fields(tmp_path):
    r = run("mission", "check", small_plan(tmp_path), "--json")
    assert r.exit_code == 0, r.output
    rep = json.loads(r.output)
    for key in ("plan", "firmware", "mission_items", "item_limit", "parts", "photos", "path_length_m",
                "flight_time_s", "area_m2", "gsd_cm", "coverage", "overlap", "warnings", "errors"):
        assert key in rep
    assert rep["coverage"]["thermal"] >= 0.995
    assert rep["errors"] == []


def test_check_text(tmp_path):
    r = run("mission", "check", small_plan(tmp_path))
    assert r.exit_code == 0
    assert "coverage thermal" in r.output and "flight time" in r.output


def test_preview_png(tmp_path):
    r = run("mission", "preview", small_plan(tmp_path), "-o", tmp_path / "p.png")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "p.png").read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("key", sorted(BAD_PLANS))
def test_bad_plans_exit_1_with_location_and_write_nothing(tmp_path, key):
    plan, fragment = bad_plan(tmp_path, key)
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("untouched")
    before = sorted(p.name for p in tmp_path.iterdir())
    r = run("mission", "compile", plan, "-o", out)
    assert r.exit_code == 1
    assert "Traceback" not in r.output
    assert f"{plan.name}:" in r.output                 # file:line:col
    assert fragment in r.output
    assert "hint:" in r.output
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    # check and preview answer the same way
    c = run("mission", "check", plan)
    assert c.exit_code == 1 and f"{plan.name}:" in c.output
    assert run("mission", "check", plan, "--json").exit_code == 1
    p = run("mission", "preview", plan, "-o", tmp_path / "x.svg")
    assert p.exit_code == 1 and not (tmp_path / "x.svg").exists()


def test_outputs_the_system_refuses_are_errors_not_crashes(tmp_path):
    plan = small_plan(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    long = "d" * 300  # longer than NAME_MAX: Path.exists() raises instead of answering
    for args in (["compile", plan, "-o", tmp_path / long], ["compile", plan, "-o", "/proc/wiris-out"],
                 ["preview", plan, "-o", tmp_path / f"{long}.svg"], ["preview", plan, "-o", tmp_path / long / "p.svg"],
                 ["preview", plan, "-o", "/proc/wiris.svg"]):
        r = run("mission", *args)
        assert r.exit_code == 1 and "internal error" not in r.output and "error:" in r.output, (args, r.output)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_rededge_shooting_along_long_transits_is_held_to_the_photo_budget(tmp_path, monkeypatch):
    # The RedEdge shoots by itself at its operating altitude, transits included: twelve legs of 178 km at the
    # survey's altitude (each waypoint within reach of home) would be about 214 000 photos to place and measure,
    # over a budget of 100 000 (the plan's real one is larger; the check is the same).
    import shutil

    import yaml

    import missions.geometry.survey
    monkeypatch.setattr(missions.geometry.survey, "MAX_PHOTOS", 100_000)

    examples = Path(__file__).resolve().parents[2] / "examples"
    shutil.copytree(examples / "areas", tmp_path / "areas")
    doc = yaml.safe_load((examples / "field-multispectral.yaml").read_text())
    home, survey = doc["home"], next(s["survey"] for s in doc["mission"] if "survey" in s)
    far = [{"waypoint": {"lat": home["lat"] + (0.8 if i % 2 else -0.8), "lon": home["lon"],
                         "alt_m": survey["altitude_m"]}} for i in range(12)]
    doc["mission"][-1:-1] = far
    plan = tmp_path / "far.yaml"
    plan.write_text(yaml.safe_dump(doc))
    before = sorted(p.name for p in tmp_path.iterdir())
    for args in (["check", plan], ["compile", plan, "-o", tmp_path / "out"], ["preview", plan, "-o", tmp_path / "p.svg"],
                 ["upload", plan, "--connect", "udpout:127.0.0.1:9", "--timeout", "0.3"]):  # refused before sending
        r = run("mission", *args)
        assert r.exit_code == 1 and f"{plan}: this flight's multispectral payload" in r.output, r.output
        assert "photos, more than the 100,000 one plan can hold" in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_check_json_on_a_bad_plan_is_still_json(tmp_path):
    plan, _ = bad_plan(tmp_path, "unknown_payload")
    r = run("mission", "check", plan, "--json")
    assert r.exit_code == 1
    doc = json.loads(r.stdout)
    assert doc["errors"] and doc["errors"][0]["where"].startswith(str(plan))
    assert "thermall" in doc["errors"][0]["message"]


def test_missing_plan_and_usage_errors(tmp_path):
    r = run("mission", "check", tmp_path / "nope.yaml")
    assert r.exit_code == 1 and "nope.yaml" in r.output and "Traceback" not in r.output
    assert run("mission", "compile", small_plan(tmp_path)).exit_code == 2          # -o missing
    assert run("mission", "preview", small_plan(tmp_path), "-o", tmp_path / "p.gif").exit_code == 1


def test_report_json_is_check_json(tmp_path):
    plan = small_plan(tmp_path)
    run("mission", "compile", plan, "-o", tmp_path / "o")
    written = json.loads((tmp_path / "o" / "small.report.json").read_text())
    printed = json.loads(run("mission", "check", plan, "--json").output)
    assert written == printed


def test_split_mission_is_a_warning_not_an_error(tmp_path):
    r = run("mission", "check", small_plan(tmp_path, limit=10), "--json")
    assert r.exit_code == 0
    rep = json.loads(r.output)
    assert rep["parts"] > 1 and all(n <= 10 for n in rep["part_items"])
    assert [w["code"] for w in rep["warnings"]].count("mission_split") == 1


def test_compile_writes_nothing_when_the_measured_report_has_errors(tmp_path, monkeypatch):
    """A mission the report finds unflyable (e.g. a part over the item limit) is printed, not written."""
    from dataclasses import replace

    import missions.measure.report as report_module

    real_report = report_module.report

    def report_with_an_error(*args, **kwargs):
        rep = real_report(*args, **kwargs)
        extra = report_module.Finding("item_limit", "part 1 has 701 items, over the limit of 700")
        return replace(rep, errors=rep.errors + (extra,))

    monkeypatch.setattr(report_module, "report", report_with_an_error)
    out = tmp_path / "out"
    r = run("mission", "compile", small_plan(tmp_path), "-o", out)
    assert r.exit_code == 1
    assert "error [item_limit]" in r.output
    assert not out.exists()


def test_compile_into_the_plans_own_area_folder_is_refused_and_the_area_kept(tmp_path):
    import shutil

    examples = Path(__file__).resolve().parents[2] / "examples"
    shutil.copytree(examples, tmp_path / "ex")
    areas = tmp_path / "ex" / "areas"
    before = {p.name: p.read_bytes() for p in areas.iterdir()}
    r = run("mission", "compile", tmp_path / "ex" / "solar-park.yaml", "-o", areas)
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert (f"{areas / 'solar-park.geojson'}: this output would overwrite {areas / 'solar-park.geojson'}, "
            "an input of the plan") in r.output and "hint:" in r.output
    assert {p.name: p.read_bytes() for p in areas.iterdir()} == before


def test_compile_refuses_a_folder_in_the_way_of_an_output_and_keeps_it(tmp_path):
    plan = small_plan(tmp_path)
    out = tmp_path / "out"
    (out / "small.kml").mkdir(parents=True)
    (out / "small.kml" / "survey-photos.txt").write_text("the user's")
    r = run("mission", "compile", plan, "-o", out)
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert f"{out / 'small.kml'}: a directory is in the way of an output file; refusing to replace it" in r.output
    assert [p.name for p in out.iterdir()] == ["small.kml"]
    assert (out / "small.kml" / "survey-photos.txt").read_text() == "the user's"


def test_a_compiled_plan_edited_by_hand_is_the_users_to_upload(tmp_path):
    """QGroundControl saves a .plan in place: the edit is not mistaken for a half-written compile."""
    from missions.formats.planfile import load_plan as read_plan_file

    plan = small_plan(tmp_path)
    out = tmp_path / "out"
    assert run("mission", "compile", plan, "-o", out).exit_code == 0
    doc = json.loads((out / "small.plan").read_text())
    doc["mission"]["items"][0]["params"][6] = 45          # the take-off altitude, by hand
    (out / "small.plan").write_text(json.dumps(doc))
    mission, _fence, _rally, _home = read_plan_file(out / "small.plan")
    assert mission[0].z == 45
