"""The numbers a pilot reads per survey/corridor step (check, the report, compile's summary): angle, spacing,
lines, trigger distance and time between photos, footprint, GSD range, photos, storage needed (from the capture
files the settings choose, where the catalogue knows their size), flight time, and every assumption."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from cdf.catalogue import TABLES_DIR, load_catalogue
from cdf.errors import CdfError
from missions.compile import compile_plan
from missions.measure.flight import simulate
from missions.measure.report import format_report, report, summary_lines
from wiris_tools.cli import cli

PLAN = """\
version: 1
name: numbers
vehicle: {firmware: ardupilot, frame: copter, speed_mps: 4}
home: {lat: 50.1102, lon: 14.5031, alt_amsl_m: 262}
payloads:
  thermal:
    camera: wiris-pro
    imager: thermal
    lens_mm: 13
    component_id: 101
    settings: {capture: [radiometric_jpeg, visible_jpeg]}
  multispectral:
    camera: rededge-mx
    settings: {raw_format: dng}
mission:
  - takeoff: {alt_m: 40}
  - survey:
      area: [[50.1110, 14.5040], [50.1110, 14.5060], [50.1120, 14.5060], [50.1120, 14.5040]]
      payloads: [thermal, multispectral]
      altitude_m: 40
      overlap: {front: 75, side: 60}
  - camera: {payload: thermal, settings: {range_mode: auto}}
  - survey:
      area: [[50.1110, 14.5040], [50.1110, 14.5060], [50.1120, 14.5060], [50.1120, 14.5040]]
      payloads: [thermal]
      altitude_m: 50
      angle_deg: 30
      overlap: {front: 70, side: 60}
  - corridor:
      line: [[50.1100, 14.5000], [50.1100, 14.5030]]
      width_m: 40
      payloads: [thermal]
      altitude_m: 40
      overlap: {front: 70, side: 60}
  - rtl: {}
"""


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    path = tmp_path_factory.mktemp("numbers") / "numbers.yaml"
    path.write_text(PLAN, encoding="utf-8")
    compiled = compile_plan(path)
    sim = simulate(compiled)
    return compiled, sim, report(compiled, sim, plan_path=str(path))


def test_every_area_step_has_its_numbers(measured):
    compiled, sim, rep = measured
    assert [s.facts.step for s in rep.steps] == [1, 3, 4]
    first, fixed, corridor = (s.to_json() for s in rep.steps)
    for s, route in zip((first, fixed, corridor), compiled.intent):
        assert s["line_spacing_m"] == pytest.approx(route.spacing_m, abs=0.01)
        assert s["trigger_distance_m"] == pytest.approx(route.trigger_distance_m, abs=0.01)
        assert s["photo_interval_s"] == pytest.approx(route.trigger_distance_m / 4, abs=0.001)
        assert s["lines"] >= 1 and s["flight_time_s"] > 0
        across, along = compiled.payload("thermal").footprint_m(s["altitude_m"])
        assert s["footprint_m"] == {"across": pytest.approx(across, abs=0.01), "along": pytest.approx(along, abs=0.01)}
    assert first["angle_auto"] is True and first["lines"] == compiled.intent[0].lines
    assert fixed["angle_auto"] is False and fixed["angle_deg"] == pytest.approx(30, abs=0.01)
    assert corridor["angle_deg"] is None
    # the steps fly part of the mission: each takes less than the whole flight, together no more
    assert sum(s["flight_time_s"] for s in (first, fixed, corridor)) < rep.flight_time_s


def test_photos_and_gsd_are_the_steps_own(measured):
    compiled, sim, rep = measured
    first = rep.steps[0]
    by_name = {p.name: p for p in first.payloads}
    assert by_name["thermal"].photos == rep.areas[0].photos["thermal"]
    gsd = compiled.payload("thermal").gsd_cm(40)
    assert by_name["thermal"].gsd_cm == pytest.approx((gsd, gsd), abs=0.01)


def test_storage_comes_from_the_capture_files_the_settings_choose(measured):
    compiled, sim, rep = measured
    first = {p.name: p for p in rep.steps[0].payloads}
    red = first["multispectral"]
    assert red.formats == "dng" and red.mb_per_photo == 9.0       # 5 × 1.8 MB (MicaSense's File Storage page)
    assert red.storage_mb == pytest.approx(red.photos * 9.0) and "micasense" in red.size_source.lower()
    wiris = first["thermal"]
    assert wiris.formats == "radiometric_jpeg + visible_jpeg" and wiris.storage_mb is None
    assert "no published image sizes" in wiris.size_source
    # the capture files cannot change in flight (IMAGE_START_CAPTURE carries them): the later steps keep them
    assert rep.steps[1].payloads[0].formats == "radiometric_jpeg + visible_jpeg"


def test_assumptions_are_listed(measured):
    compiled, sim, rep = measured
    first = rep.steps[0].facts.assumptions
    assert any(a.startswith("flat ground") for a in first)
    assert any("thermal: pixel pitch" in a and "assumed" in a for a in first)
    assert any("4 m/s ground speed" in a for a in first)


def test_check_text_json_and_compile_summary_show_them(measured, tmp_path):
    compiled, sim, rep = measured
    text = format_report(rep)
    for needle in ("(chosen: auto)", "angle 30.0°", "along its centre line", "a photo every", "footprint",
                   "storage unknown", "flight time", "assumes", "overlap asked front 75 %, side 60 %"):
        assert needle in text, needle
    summary = "\n".join(summary_lines(rep))
    assert "step 1 survey:" in summary and "(auto)" in summary and "storage" in summary and "assumes" in summary
    path = tmp_path / "numbers.yaml"
    path.write_text(PLAN, encoding="utf-8")
    r = CliRunner().invoke(cli, ["mission", "check", str(path), "--json"])
    doc = json.loads(r.output)
    assert [s["step"] for s in doc["steps"]] == [1, 3, 4]
    assert doc["steps"][0]["payloads"]["multispectral"]["capture_formats"] == "dng"
    assert doc["areas"][0]["requested"]["front_pct"] == 75


# ------------------------------------------------------------------------------ the catalogue's capture sizes

def _tables(tmp_path: Path, change) -> Path:
    for name in ("rededge.yaml", "wiris-pro.yaml", "workswell.yaml"):
        shutil.copy(TABLES_DIR / name, tmp_path)
    path = tmp_path / "rededge.yaml"
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    change(data["capture_sizes"])
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return tmp_path


@pytest.mark.parametrize("change,message,hint", [
    (lambda c: c.update(setting="raw_fromat"), "is no setting with options", "did you mean 'raw_format'?"),
    (lambda c: c["mb"].update(tif=3.0), "unknown option tif", "dng, tiff"),
    (lambda c: c["mb"].update(tiff=-1.0), "not positive", "megabytes"),
    (lambda c: c.pop("source"), "has no source", "published"),
])
def test_a_broken_capture_size_table_is_refused_with_a_hint(tmp_path, change, message, hint):
    with pytest.raises(CdfError) as err:
        load_catalogue(_tables(tmp_path, change))
    assert message in err.value.message and hint in err.value.hint and err.value.where == "rededge.yaml"
