"""Optics: numbers checked against the reference's own tables (autopilots-and-cameras §5.3/§5.4), not the code."""

from __future__ import annotations

import pytest

from cdf.catalogue import catalogue
from missions.geometry import optics
from missions.errors import PlanError
from missions.plan import Payload


def info(camera: str, lens: float | None = None, imager: str | None = None, landscape: bool = True):
    cam = catalogue().get(camera)
    return optics.payload_info(Payload(name="p", camera=camera, imager=imager, lens_mm=lens, landscape=landscape),
                               cam, where="plan.yaml:5:3")


@pytest.mark.parametrize("lens,gsd_m,fp_w,fp_h", [(9, 0.227, 145, 116), (13, 0.157, 100, 80), (19, 0.107, 69, 55),
                                                 (25, 0.082, 52, 42), (35, 0.058, 37, 30)])
def test_wiris_pro_gsd_and_footprint_at_120m_match_reference_table(lens, gsd_m, fp_w, fp_h):
    # reference §5.4: 640×512, 17 µm, GSD and footprint at 120 m per focal length
    i, _ = info("wiris-pro", lens)
    assert i.gsd_cm(120) / 100 == pytest.approx(gsd_m, abs=0.0015)
    w, h = i.footprint_m(120)
    assert w == pytest.approx(fp_w, abs=1.0) and h == pytest.approx(fp_h, abs=1.0)


def test_rededge_gsd_at_120m_matches_reference():
    i, warn = info("rededge-mx")          # one lens in the table: no lens_mm needed
    assert i.gsd_cm(120) == pytest.approx(8.33, abs=0.01)   # §5.3: 3.75 µm × 120 m / 5.4 mm
    assert i.footprint_m(120) == pytest.approx((106.7, 80.0), abs=0.1)
    assert warn == ()


def test_gsd_altitude_round_trip():
    i, _ = info("wiris-security")
    for gsd in (1.0, 2.5, 5.83):
        assert i.gsd_cm(optics.altitude_for_gsd(i, gsd)) == pytest.approx(gsd)
    assert optics.altitude_for_gsd(i, 5.83) == pytest.approx(120, abs=0.1)   # §5.4: Security 5.83 cm at 120 m


def test_portrait_swaps_footprint():
    land, _ = info("wiris-pro", 13)
    port, _ = info("wiris-pro", 13, landscape=False)
    assert port.footprint_m(50) == pytest.approx(tuple(reversed(land.footprint_m(50))))


def test_spacing_and_trigger_from_overlap():
    i, _ = info("wiris-pro", 13)
    w, h = i.footprint_m(40)
    assert optics.spacing_m(i, 40, 70) == pytest.approx(w * 0.3)
    assert optics.trigger_m(i, 40, 80) == pytest.approx(h * 0.2)


def test_unknown_optics_refused_with_table_note():
    with pytest.raises(PlanError) as ei:
        info("wiris-agro")
    assert "unknown" in ei.value.message and "wiris-agro" in ei.value.hint
    assert "No public source" in ei.value.hint
    assert ei.value.where == "plan.yaml:5:3"


def test_lens_not_in_table_lists_lenses():
    with pytest.raises(PlanError) as ei:
        info("wiris-pro", 14)
    assert "no 14 mm lens" in ei.value.message
    for lens in ("9 mm", "13 mm", "19 mm", "25 mm", "35 mm"):
        assert lens in ei.value.hint


def test_several_lenses_need_lens_mm():
    with pytest.raises(PlanError, match="which lens") as ei:
        info("wiris-pro")
    assert "lens_mm" in ei.value.hint


def test_assumed_optics_warn():
    _, warn = info("wiris-pro", 13)
    assert warn and warn[0].code == "assumed_optics" and "pixel pitch" in warn[0].message


def test_unknown_visible_imager_named():
    with pytest.raises(PlanError, match="visible"):
        info("wiris-pro", None, imager="visible")


def test_too_fast_names_the_speed_that_works():
    i, _ = info("wiris-security")          # 1.8 s minimum interval
    with pytest.raises(PlanError) as ei:
        optics.check_interval(i, 9.0, 6.0, where="plan.yaml:9:9")
    assert "1.8 s" in ei.value.message
    assert "5 m/s" in ei.value.hint       # 9 m / 1.8 s
    assert optics.check_interval(i, 9.0, 5.0) == pytest.approx(1.8)


@pytest.mark.parametrize("gsd", [0.0, -1.0, float("nan")])
def test_gsd_must_be_positive(gsd):
    i, _ = info("wiris-pro", 13)
    with pytest.raises(PlanError, match="must be positive") as ei:
        optics.altitude_for_gsd(i, gsd)
    assert "gsd_cm" in ei.value.hint


def test_camera_without_imagers_names_its_table():
    import dataclasses

    cam = dataclasses.replace(catalogue().get("wiris-pro"), imagers=())
    with pytest.raises(PlanError, match="lists no imagers") as ei:
        optics.payload_info(Payload(name="p", camera="wiris-pro"), cam, where="plan.yaml:5:3")
    assert ei.value.where == "plan.yaml:5:3"
    assert f"cdf/tables/{cam.table}" in ei.value.hint
