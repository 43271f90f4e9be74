"""A fixed-wing survey compiled for `frame: plane` flown by arduplane SITL: take-off, lines, turns, RTL, with
the WIRIS emulator shooting as ArduPilot's distance trigger commands (one flight shared by the module)."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from missions.compile import compile_plan
from wiris_tools.cli import cli
from wiris_tools.sitl.flight import fly_compiled
from wiris_tools.sitl.photos import check_photos

pytestmark = [pytest.mark.sitl, pytest.mark.slow]

PLAN = """\
version: 1
name: plane-survey
vehicle: {firmware: ardupilot, frame: plane, speed_mps: 20}
home: {lat: 50.08, lon: 14.42, alt_amsl_m: 262}
payloads:
  thermal: {camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}
mission:
  - takeoff: {alt_m: 100}
  - survey:
      area: [[50.0830, 14.4230], [50.0830, 14.4290], [50.0860, 14.4290], [50.0860, 14.4230]]
      payloads: [thermal]
      altitude_m: 100
      overlap: {front: 60, side: 50}
      trigger: distance
      blur_px: 2          # 20 m/s smears the 13 mm WIRIS's 13 cm pixel by 1.5 px (missions.thermal)
  - rtl: {}
"""


@pytest.fixture(scope="module")
def plane_flight(sitl_dir, tmp_path_factory):
    d = tmp_path_factory.mktemp("plane")
    (d / "plane.yaml").write_text(PLAN, encoding="utf-8")
    res = CliRunner().invoke(cli, ["mission", "compile", str(d / "plane.yaml"), "-o", str(d / "out")])
    assert res.exit_code == 0, res.output
    with fly_compiled(sitl_dir, d / "out", "plane-survey", vehicle="plane", workdir=d / "sitl") as flight:
        caps = [(p.position.lat / 1e7, p.position.lon / 1e7, p.position.relative_alt / 1e3) for p in flight.photos]
        texts = flight.sitl.statustext
    return check_photos(compile_plan(d / "plane.yaml"), "thermal", caps), texts


def test_the_plane_flies_the_survey_to_rtl_and_the_count_matches(plane_flight):
    check, texts = plane_flight
    assert any("RTL" in t for t in texts), texts[-5:]
    assert check.captured > 100 and check.count_ok, check


def test_the_plane_photos_lie_where_the_report_puts_them(plane_flight):
    check, _ = plane_flight
    assert check.worst_offset_m < 5.0 and check.coverage_captured >= check.coverage_predicted - 0.005, check
