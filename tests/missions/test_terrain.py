"""Terrain: plans over synthetic DEM GeoTIFFs (written with rasterio) compile to lines that hold their height above
ground, overlap, coverage and clearance, measured from the emitted items; bad DEMs are clear errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import terrain_dems as T
from missions.compile import compile_plan
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, mavlink
from missions.errors import PlanError
from missions.measure.report import report
from missions.terrain.dem import load_dem
from missions.terrain.follow import FollowSettings, follow_path, rate_limited
from missions.terrain.geoid import undulation_m
from wiris_tools.cli import cli

DATA = Path(__file__).resolve().parents[1] / "data"


def _plan(tmp_path: Path, shape, name="dem.tif", crs="utm", half=150.0, **kw) -> Path:
    T.write_dem(tmp_path / name, shape, crs=crs)
    p = tmp_path / "plan.yaml"
    p.write_text(T.plan_text(name, T.square(half), **kw))
    return p


def _survey_navs(compiled):
    a = compiled.areas[0]
    return [it for it in compiled.items[a.items[0]:a.items[1]] if it.command == mavlink.MAV_CMD_NAV_WAYPOINT]


def _holds_the_request(compiled, front=0.80, side=0.70):
    rep = report(compiled)
    row = rep.terrain.steps[0]
    assert rep.coverage["thermal"] >= 0.995
    assert rep.overlap["thermal"].front_min >= front - 0.02
    assert rep.overlap["thermal"].side_min >= side - 0.02
    assert row.outside_tolerance == 0
    assert row.target_m - 0.05 <= row.hag_min_m and row.hag_max_m <= row.target_m + row.tolerance_m + 0.05
    assert rep.terrain.clearance.min_m >= 20.0
    return rep


@pytest.mark.parametrize("shape", [T.slope(30), T.hill(80, 150), T.valley(60, 120)], ids=["slope", "hill", "valley"])
def test_lines_hold_height_overlap_and_coverage_over_the_ground(tmp_path, shape):
    compiled = compile_plan(_plan(tmp_path, shape))
    navs = _survey_navs(compiled)
    assert navs and all(it.frame == FRAME_GLOBAL for it in navs)        # above mean sea level, from the DEM
    dem = compiled.terrain.dem
    ground = dem.ground_amsl([it.lat for it in navs], [it.lon for it in navs])
    agl = np.array([it.z for it in navs]) - ground
    assert agl.min() >= 60.0 - 0.05 and agl.max() <= 66.0 + 0.05         # target 60 m, default tolerance 10 %
    rep = _holds_the_request(compiled)
    assert "DEM" in rep.ground and json.loads(json.dumps(rep.to_json()))["terrain"]["min_clearance"]["min_m"] >= 20


def test_the_same_survey_assuming_flat_ground_misses_on_the_slope(tmp_path):
    # the flat plan's photos over a 30 % slope: heights above ground drift from the target far beyond 10 %
    T.write_dem(tmp_path / "dem.tif", T.slope(30))
    flat = tmp_path / "flat.yaml"
    flat.write_text(T.plan_text(None, T.square(150), home_alt=300.0))
    compiled = compile_plan(flat)
    assert report(compiled).ground == "ground assumed flat at home elevation"
    navs = _survey_navs(compiled)
    assert all(it.frame == FRAME_GLOBAL_RELATIVE_ALT and it.z == 60.0 for it in navs)
    dem = load_dem(["dem.tif"], tmp_path)
    agl = 300.0 + 60.0 - dem.ground_amsl([it.lat for it in navs], [it.lon for it in navs])
    assert agl.max() - agl.min() > 60.0


def test_hill_lines_get_waypoints_where_the_ground_bends(tmp_path):
    compiled = compile_plan(_plan(tmp_path, T.hill(80, 150)))
    kinds = [it.comment for it in _survey_navs(compiled)]
    assert kinds.count("terrain") > 10           # added along the lines over the hill
    assert all(it.z == round(it.z, 2) for it in _survey_navs(compiled))


def test_utm_and_geographic_dems_give_the_same_altitudes(tmp_path):
    (tmp_path / "u").mkdir()
    (tmp_path / "g").mkdir()
    a = compile_plan(_plan(tmp_path / "u", T.hill(), crs="utm"))
    b = compile_plan(_plan(tmp_path / "g", T.hill(), crs="4326"))
    za = np.array([it.z for it in _survey_navs(a) if it.comment != "terrain"])
    zb = np.array([it.z for it in _survey_navs(b) if it.comment != "terrain"])
    assert len(za) == len(zb) and np.abs(za - zb).max() < 1.0


def test_cliff_is_climbed_before_it_and_left_late_never_below_the_target(tmp_path):
    compiled = compile_plan(_plan(tmp_path, T.cliff(60, 0.0), half=120, angle=90.0))
    rep = report(compiled)
    row = rep.terrain.steps[0]
    # never lower than asked, to within what the DEM itself says between its samples: the follower holds the
    # target at the DEM's sample spacing, and a photo that falls between two samples at the cliff's foot reads
    # the bilinear surface there (0.31 m under with the photos where ArduPilot's 50 Hz distance trigger puts them,
    # commanded half a check short of whole checks; 0.17 m under at the planned distance)
    assert row.hag_min_m >= 60.0 - 0.35
    assert any(w.code == "terrain_rate_limited" for w in compiled.warnings)   # 60 m up at 2.5 m/s over 5 m/s
    assert rep.terrain.clearance.min_m >= 20.0


def test_climb_and_descent_rates_bound_every_line(tmp_path):
    compiled = compile_plan(_plan(tmp_path, T.hill(80, 100), vehicle_extra=", climb_mps: 1.0, descent_mps: 0.5"))
    navs = _survey_navs(compiled)
    from missions.geometry.geo import great_circle_m
    for a, b in zip(navs[:-1], navs[1:]):
        d = great_circle_m(a.lat, a.lon, b.lat, b.lon)
        if d > 1.0:
            assert (b.z - a.z) / d <= 1.0 / 5.0 + 0.01 and (a.z - b.z) / d <= 0.5 / 5.0 + 0.01


def test_terrain_frame_on_ardupilot_and_refused_on_px4(tmp_path):
    p = _plan(tmp_path, T.slope(30), terrain_extra=", frame: terrain")
    compiled = compile_plan(p)
    navs = _survey_navs(compiled)
    assert all(it.frame == FRAME_GLOBAL_TERRAIN_ALT and it.z == 60.0 for it in navs)
    assert ("TERRAIN_ENABLE", 1.0) in [(n, v) for n, v, _ in compiled.params]
    rep = report(compiled)
    assert rep.terrain.steps[0].hag_min_m == pytest.approx(60.0, abs=0.01)
    with pytest.raises(PlanError) as e:
        compile_plan(p, firmware="px4")
    assert "terrain frame" in e.value.message and "amsl" in e.value.hint


def test_outputs_keep_the_frames(tmp_path):
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(_plan(tmp_path, T.hill())), "-o", str(out)])
    assert r.exit_code == 0, r.output
    from missions.formats.planfile import load_plan as load_qgc
    from missions.formats.wpl import load_wpl
    compiled = compile_plan(tmp_path / "plan.yaml")
    items, _fence, _rally, _home = load_qgc(out / "terrain-test.plan")
    wpl, _ = load_wpl(out / "terrain-test.waypoints")
    assert [i.frame for i in items] == [i.frame for i in compiled.items] == [i.frame for i in wpl]
    assert all(a.same_on_wire(b) for a, b in zip(items, compiled.items))
    doc = json.loads((out / "terrain-test.plan").read_text())
    frames = {it["frame"]: it.get("AltitudeMode") for it in doc["mission"]["items"] if "frame" in it}
    assert frames[FRAME_GLOBAL] == 2                       # QGC's absolute altitude mode
    rep = json.loads((out / "terrain-test.report.json").read_text())
    assert rep["terrain"]["dem"][0]["vertical"].startswith("mean sea level")


def test_home_elevation_comes_from_the_dem_unless_given(tmp_path):
    compiled = compile_plan(_plan(tmp_path, T.slope(30)))
    assert compiled.home[2] == pytest.approx(300.0, abs=0.05)         # home is due south of the centre
    no_dem = tmp_path / "nodem.yaml"
    no_dem.write_text(T.plan_text(None, T.square(100)))
    with pytest.raises(PlanError) as e:
        compile_plan(no_dem)
    assert "alt_amsl_m" in str(e.value)


def test_clearance_error_names_the_place_and_the_height(tmp_path):
    # a hill between home and the area, flown over at the take-off altitude
    T.write_dem(tmp_path / "dem.tif", lambda e, n: T.BASE_M + 70.0 * np.exp(-(e ** 2 + (n + 300) ** 2) / (2 * 60.0 ** 2)))
    p = tmp_path / "plan.yaml"
    p.write_text(T.plan_text("dem.tif", T.square(100, n_m=0), takeoff_m=25, home_offset=(0.0, -600.0)))
    with pytest.raises(PlanError) as e:
        compile_plan(p)
    msg = str(e.value)
    assert "above the ground at" in msg and "terrain.clearance_m 20" in msg and e.value.hint


@pytest.mark.parametrize("case, expect", [
    ("hole", "nodata"), ("outside", "no ground height"), ("nocrs", "no coordinate reference system"),
    ("text", "cannot be read as a raster"), ("missing", "not found"), ("mars", "cannot be transformed from WGS84")])
def test_bad_dems_are_clear_errors_and_write_nothing(tmp_path, case, expect):
    area = T.square(150)
    if case == "hole":
        T.write_dem(tmp_path / "dem.tif", T.hill(), holes=[(0.0, 0.0, 30.0)])
    elif case == "outside":
        T.write_dem(tmp_path / "dem.tif", T.hill(), half_m=300.0)
        area = T.square(150, e_m=500.0)
    elif case == "nocrs":
        T.write_dem(tmp_path / "dem.tif", T.hill(), with_crs=False)
    elif case == "text":
        (tmp_path / "dem.tif").write_text("not a raster\n")
    elif case == "mars":                  # a CRS of another body: PROJ has no way from WGS84 to it
        import rasterio
        from pyproj import CRS
        from rasterio.transform import from_origin
        with rasterio.open(tmp_path / "dem.tif", "w", driver="GTiff", width=10, height=10, count=1,
                           dtype="float32", crs=rasterio.crs.CRS.from_wkt(CRS("IAU_2015:49900").to_wkt()),
                           transform=from_origin(14.7, 50.1, 0.01, 0.01)) as ds:
            ds.write(np.ones((10, 10), np.float32), 1)
    p = tmp_path / "plan.yaml"
    p.write_text(T.plan_text("dem.tif", area))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(p), "-o", str(out)])
    assert r.exit_code == 1 and expect in r.output and "Traceback" not in r.output
    assert "hint" in r.output.lower()
    assert not out.exists() or not any(out.iterdir())


def test_several_files_are_mosaicked_first_wins(tmp_path):
    T.write_dem(tmp_path / "fine.tif", T.hill(), holes=[(0.0, 0.0, 40.0)])
    T.write_dem(tmp_path / "coarse.tif", T.hill(), res_m=20.0, crs="4326")
    dem = load_dem(["fine.tif", "coarse.tif"], tmp_path)
    lat, lon = T.offset(0.0, 0.0)
    assert dem.ground_amsl(lat, lon)[0] == pytest.approx(T.BASE_M + 80.0, abs=1.5)   # from the coarse file
    lat2, lon2 = T.offset(100.0, 0.0)
    fine_only = load_dem(["fine.tif"], tmp_path).ground_amsl(lat2, lon2)[0]
    assert dem.ground_amsl(lat2, lon2)[0] == fine_only
    p = tmp_path / "plan.yaml"
    p.write_text(T.plan_text(["fine.tif", "coarse.tif"], T.square(150)))
    _holds_the_request(compile_plan(p))


def test_vertical_datum_egm96_ellipsoid_and_assumed(tmp_path):
    lat, lon = T.offset(0.0, 0.0)
    n = float(undulation_m(np.array([lat]), np.array([lon]))[0])
    assert 40.0 < n < 50.0                                            # EGM96 over central Bohemia ~ 45 m
    assert float(undulation_m(np.array([0.0]), np.array([0.0]))[0]) == pytest.approx(17.16, abs=0.01)
    T.write_dem(tmp_path / "msl.tif", T.hill(), crs="4326", vertical_epsg=5773)
    T.write_dem(tmp_path / "ell.tif", T.hill(), crs="4326", vertical_epsg=4979, offset_m=n)
    T.write_dem(tmp_path / "plain.tif", T.hill(), crs="4326", offset_m=n)
    msl, ell = load_dem(["msl.tif"], tmp_path), load_dem(["ell.tif"], tmp_path)
    assert msl.files[0].vertical == "EGM96 geoid"
    assert ell.files[0].vertical.startswith("WGS84 ellipsoid")
    assert ell.ground_amsl(lat, lon)[0] == pytest.approx(msl.ground_amsl(lat, lon)[0], abs=0.05)
    assumed = load_dem(["plain.tif"], tmp_path)
    assert assumed.files[0].vertical_source.startswith("assumed")
    said = load_dem(["plain.tif"], tmp_path, vertical="ellipsoid")
    assert said.ground_amsl(lat, lon)[0] == pytest.approx(msl.ground_amsl(lat, lon)[0], abs=0.05)


def test_srtm_hgt_tile_is_read_as_egm96(tmp_path):
    # SRTM3 layout: 1201 x 1201 big-endian int16, rows from north, named by its south-west corner
    z = np.full((1201, 1201), 250, dtype=">i2")
    z[600, 600] = 400
    (tmp_path / "N50E014.hgt").write_bytes(z.tobytes())
    dem = load_dem(["N50E014.hgt"], tmp_path)
    assert dem.files[0].vertical == "EGM96 geoid" and "SRTM" in dem.files[0].vertical_source
    assert dem.ground_amsl(50.5, 14.5)[0] == pytest.approx(400.0, abs=0.01)
    assert dem.ground_amsl(50.2, 14.2)[0] == pytest.approx(250.0)
    assert 80.0 < dem.resolution_m < 95.0


def test_real_public_dem_is_read(tmp_path):
    # tests/data/README.md says where it comes from: 3 arc-second heights around Fort Worth, Texas
    dem = load_dem([str(DATA / "fort-worth-3arcsec.tif")], ".")
    assert dem.files[0].crs.startswith("EPSG:4326")
    # pixel (row 60, col 60) centre: the file's own value there, 211 m
    assert dem.ground_amsl(32.6712499999987, -97.33458333332945)[0] == pytest.approx(211.0, abs=1e-3)
    lats, lons = np.meshgrid(np.linspace(32.63, 32.71, 9), np.linspace(-97.37, -97.30, 9))
    z = dem.ground_amsl(lats.ravel(), lons.ravel())
    assert np.isfinite(z).all() and 160 < z.min() and z.max() < 270


def test_follow_profile_respects_rates_and_band():
    s = np.linspace(0.0, 400.0, 161)
    ground = 100.0 + 40.0 * np.exp(-((s - 200.0) / 40.0) ** 2)
    z = rate_limited(ground + 50.0, s, 0.3, 0.2)
    dz = np.diff(z) / np.diff(s)
    assert dz.max() <= 0.3 + 1e-9 and dz.min() >= -0.2 - 1e-9 and (z >= ground + 50.0 - 1e-9).all()
    xy = np.column_stack([s, np.zeros_like(s)])[[0, -1]]
    prof = follow_path(xy, lambda p: 100.0 + 40.0 * np.exp(-((p[:, 0] - 200.0) / 40.0) ** 2),
                       FollowSettings(50.0, 5.0, 1.0, 1.0), 2.5)
    assert list(prof.vertex[[0, -1]]) == [0, 1] and len(prof.xy) > 4
    fine = np.linspace(0, 400, 801)
    flown = np.interp(fine, prof.xy[:, 0], prof.amsl_m)
    agl = flown - (100.0 + 40.0 * np.exp(-((fine - 200.0) / 40.0) ** 2))
    assert agl.min() >= 50.0 - 0.05 and agl.max() <= 55.0 + 0.05


def test_preview_draws_contours_under_the_path_only_with_a_dem(tmp_path):
    from missions.formats.preview import write_preview
    compiled = compile_plan(_plan(tmp_path, T.hill(80, 150)))
    svg = write_preview(compiled, tmp_path / "p.svg").read_text()
    assert svg.count('class="terrain"') > 100 and "contours every 10 m (DEM)" in svg
    assert svg.index('id="terrain"') < svg.index('id="path"')          # drawn first: under the path
    flat = tmp_path / "flat.yaml"
    flat.write_text(T.plan_text(None, T.square(150), home_alt=300.0))
    assert 'class="terrain"' not in write_preview(compile_plan(flat), tmp_path / "f.svg").read_text()


def test_lines_up_a_slope_keep_the_front_overlap(tmp_path):
    # north-south lines up a 30 % slope: a footprint is a trapezoid, consecutive ones share less of it unless
    # the trigger distance shrinks (1.4 points less without it)
    T.write_dem(tmp_path / "dem.tif", T.slope(30, azimuth_deg=0.0), half_m=900.0)
    p = tmp_path / "plan.yaml"
    p.write_text(T.plan_text("dem.tif", T.square(150)))
    compiled = compile_plan(p)
    flat_trigger = 0.2 * 40.17                        # WIRIS Pro 13 mm at 60 m: 40.2 m along, 80 % front
    assert compiled.areas[0].trigger_distance_m < 0.93 * flat_trigger
    rep = _holds_the_request(compiled)
    assert rep.overlap["thermal"].front_min >= 0.795 and rep.overlap["thermal"].side_min >= 0.695


def test_a_hill_fits_one_upload_and_holds_the_side_overlap(tmp_path):
    # straight stretches as long as the tolerance band allows: the hill needs tens of waypoints, not hundreds
    compiled = compile_plan(_plan(tmp_path, T.hill(80, 150)))
    assert len(compiled.parts) == 1 and len(compiled.items) < 300
    rep = _holds_the_request(compiled)
    assert rep.overlap["thermal"].side_min >= 0.69          # lines within [60, 66] m: spacing sized for it


def test_geojson_footprints_lie_on_the_ground(tmp_path):
    from pyproj import Transformer
    from shapely.geometry import Polygon
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(_plan(tmp_path, T.hill(80, 150))), "-o", str(out)])
    assert r.exit_code == 0, r.output
    fc = json.loads((out / "terrain-test.geojson").read_text())
    to_utm = Transformer.from_crs("EPSG:4326", "EPSG:32633", always_xy=True)
    areas = []
    for f in fc["features"]:
        if f["properties"]["kind"] == "footprint":
            ring = f["geometry"]["coordinates"][0]
            assert len(ring) == 9                             # corners and edge midpoints, closed
            areas.append(Polygon([to_utm.transform(lon, lat) for lon, lat in ring]).area)
    flat_60m = 50.2 * 40.2                                    # WIRIS Pro 13 mm at 60 m above the ground
    assert areas and 0.9 * flat_60m < min(areas) and max(areas) < 1.35 * flat_60m
    agl = [f["properties"]["agl_m"] for f in fc["features"] if f["properties"]["kind"] == "photo"]
    assert agl and min(agl) >= 59.9 and max(agl) <= 66.1


def test_corridor_by_gsd_and_hover_survey_follow_the_hill(tmp_path):
    T.write_dem(tmp_path / "dem.tif", T.hill(80, 150))
    base = T.plan_text("dem.tif", T.square(120))
    a, b = T.offset(-200, -100), T.offset(200, 120)
    corridor = base.replace(f"""  - survey:
      area: {T.square(120)}
      payloads: [thermal]
      altitude_m: 60.0""", f"""  - corridor:
      line: [[{a[0]}, {a[1]}], [{b[0]}, {b[1]}]]
      width_m: 80
      payloads: [thermal]
      gsd_cm: 8""").replace("      angle_deg: 0.0\n", "")
    assert "corridor" in corridor
    (tmp_path / "corridor.yaml").write_text(corridor)
    compiled = compile_plan(tmp_path / "corridor.yaml")
    assert compiled.areas[0].altitude_m == pytest.approx(61.18, abs=0.01)      # 8 cm/px with 13 mm
    _holds_the_request(compiled)
    (tmp_path / "hover.yaml").write_text(base.replace("angle_deg: 0.0", "angle_deg: 0.0\n      trigger: hover"))
    hover = compile_plan(tmp_path / "hover.yaml")
    stops = [it for it in _survey_navs(hover) if it.param1 > 0]
    ground = hover.terrain.dem.ground_amsl([it.lat for it in stops], [it.lon for it in stops])
    assert stops and np.all(np.abs(np.array([it.z for it in stops]) - ground - 60.0) < 0.1)
    _holds_the_request(hover)


def test_plane_landing_glide_is_judged_above_home_not_above_sea_level(tmp_path):
    # the lines fly ~400 m above mean sea level, 100 m above home: a 1.4 km final approach is a 4° glide
    T.write_dem(tmp_path / "dem.tif", T.hill(80, 150), half_m=2500.0, res_m=10.0)
    lat, lon = T.offset(0.0, -1700.0)
    text = (T.plan_text("dem.tif", T.square(150), altitude_m=100.0, takeoff_m=100.0, front=60, side=60,
                        speed_mps=15.0).replace("frame: copter", "frame: plane")
            .replace("  - rtl: {}", f"  - land: {{lat: {lat}, lon: {lon}}}")
            # 15 m/s smears the 13 mm WIRIS's 13 cm pixel by more than the default 1 px budget (missions.thermal)
            .replace("      angle_deg: 0.0\n", "      angle_deg: 0.0\n      blur_px: 3\n"))
    (tmp_path / "plane.yaml").write_text(text)
    compiled = compile_plan(tmp_path / "plane.yaml")
    assert compiled.items[-1].command == mavlink.MAV_CMD_NAV_LAND


def test_rededge_over_terrain_is_warned(tmp_path):
    text = T.plan_text("dem.tif", T.square(150)).replace(
        "thermal: {camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}",
        "thermal: {camera: rededge-mx}")
    T.write_dem(tmp_path / "dem.tif", T.hill())
    (tmp_path / "re.yaml").write_text(text)
    assert any(w.code == "rededge_over_terrain" for w in compile_plan(tmp_path / "re.yaml").warnings)


@pytest.mark.parametrize("firmware, frame", [("ardupilot", "amsl"), ("ardupilot", "terrain"), ("px4", "amsl")])
def test_terrain_missions_upload_and_verify_over_udp(tmp_path, firmware, frame):
    # the compiled .plan through `upload_file --verify` against the vehicle simulator on 127.0.0.1, which
    # gives items back in the frames each firmware uses (ArduPilot 0/10, PX4 GLOBAL_INT)
    from wiris_tools.link import Link
    from wiris_tools.transfer import upload_file
    from wiris_tools.vehicle_sim import VehicleSim
    extra = ", frame: terrain" if frame == "terrain" else ""
    p = _plan(tmp_path, T.hill(80, 150), firmware=firmware, terrain_extra=extra)
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(p), "-o", str(out)])
    assert r.exit_code == 0, r.output
    with VehicleSim(flavour=firmware, heartbeat_s=0.2) as sim, Link(f"udpout:127.0.0.1:{sim.port}") as link:
        summary = upload_file(link, str(out / "terrain-test.plan"), verify=True, timeout=5)
    assert summary["verified"]


def test_check_prints_the_ground_it_measured_on(tmp_path):
    r = CliRunner().invoke(cli, ["mission", "check", str(_plan(tmp_path, T.hill(80, 150)))])
    assert r.exit_code == 0, r.output
    assert "from the DEM: dem.tif (mean sea level (EGM96 assumed), 5.0 m)" in r.output
    assert "clearance" in r.output and "step 1 above ground  60.0–" in r.output
    flat = tmp_path / "flat.yaml"
    flat.write_text(T.plan_text(None, T.square(150), home_alt=300.0))
    r = CliRunner().invoke(cli, ["mission", "check", str(flat)])
    assert "ground assumed flat at home elevation" in r.output
    T.write_dem(tmp_path / "holes.tif", T.hill(), holes=[(0.0, 0.0, 30.0)])
    bad = tmp_path / "bad.yaml"
    bad.write_text(T.plan_text("holes.tif", T.square(150)))
    r = CliRunner().invoke(cli, ["mission", "check", "--json", str(bad)])
    assert r.exit_code == 1
    assert "nodata" in json.loads(r.stdout)["errors"][0]["message"]


def test_a_truncated_geotiff_is_a_clear_error(tmp_path):
    T.write_dem(tmp_path / "whole.tif", T.hill())
    (tmp_path / "dem.tif").write_bytes((tmp_path / "whole.tif").read_bytes()[:3000])
    with pytest.raises(PlanError) as e:
        load_dem(["dem.tif"], tmp_path, where="plan.yaml:4:8")
    assert "cannot be read as a raster" in e.value.message and e.value.where == "plan.yaml:4:8" and e.value.hint


from hypothesis import given, settings, strategies as st   # noqa: E402


@settings(max_examples=60, deadline=None)
@given(bumps=st.lists(st.tuples(st.floats(0, 600), st.floats(-80, 80), st.floats(25, 150)), min_size=1, max_size=6),
       climb=st.floats(0.1, 1.0), descent=st.floats(0.1, 1.0), tol=st.floats(0.5, 15.0),
       cuts=st.lists(st.floats(1, 599), max_size=4))
def test_followed_profile_stays_in_its_band_and_rates(bumps, climb, descent, tol, cuts):
    def ground_of(x):
        return 300.0 + sum(h * np.exp(-((x - c) / w) ** 2) for c, h, w in bumps)

    xs = np.array(sorted({0.0, 600.0, *cuts}))
    path = np.column_stack([xs, np.zeros_like(xs)])
    prof = follow_path(path, lambda p: ground_of(p[:, 0]), FollowSettings(40.0, tol, climb, descent), 2.0)
    assert [int(v) for v in prof.vertex if v >= 0] == list(range(len(xs)))      # every vertex kept, in order
    dz, dx = np.diff(prof.amsl_m), np.diff(prof.xy[:, 0])
    ok = dx > 1e-9
    assert np.all(dz[ok] / dx[ok] <= climb + 1e-6) and np.all(-dz[ok] / dx[ok] <= descent + 1e-6)
    fine = np.linspace(0.0, 600.0, 1201)
    agl = np.interp(fine, prof.xy[:, 0], prof.amsl_m) - ground_of(fine)
    # never below the target at the 2 m samples; between them a bump 25 m wide bends the ground by < 0.5 m
    assert agl.min() >= 40.0 - 0.5
    s = np.concatenate([[0.0], np.cumsum(np.diff(fine))])
    limited = rate_limited(ground_of(fine) + 40.0, s, climb, descent) - ground_of(fine)
    assert np.all(agl <= np.maximum(40.0 + tol, limited) + 1.0)     # the two profiles sample 2 m and 0.5 m


def test_geojson_path_altitudes_are_above_sea_level_in_both_frames(tmp_path):
    for frame in ("amsl", "terrain"):
        d = tmp_path / frame
        d.mkdir()
        extra = ", frame: terrain" if frame == "terrain" else ""
        r = CliRunner().invoke(cli, ["mission", "compile", str(_plan(d, T.hill(80, 150), terrain_extra=extra)),
                                     "-o", str(d / "out")])
        assert r.exit_code == 0, r.output
        fc = json.loads((d / "out" / "terrain-test.geojson").read_text())
        dem = load_dem(["dem.tif"], d)
        wps = [f for f in fc["features"] if f["properties"]["kind"] == "waypoint"
               and f["properties"]["comment"] in ("entry", "exit")]
        lon, lat, z = np.array([f["geometry"]["coordinates"] for f in wps]).T
        agl = z - dem.ground_amsl(lat, lon)
        if frame == "terrain":                    # held 60 m above the ground by the autopilot
            assert wps and np.abs(agl - 60.0).max() < 0.1
        else:                                     # the items' own altitudes, within the band
            items = compile_plan(d / "plan.yaml").items
            base = 1                              # ArduPilot numbers the mission from 1
            assert np.allclose(z, [items[f["properties"]["seq"] - base].z for f in wps], atol=0.005)
            assert agl.min() > 59.9 and agl.max() < 66.1


def test_a_survey_over_the_real_dem_holds_the_request(tmp_path):
    # 3 arc-second heights (~90 m pixels) around Fort Worth: lines every ~10 m sample, 169-258 m ground
    import shutil
    shutil.copy(DATA / "fort-worth-3arcsec.tif", tmp_path / "fw.tif")
    lat0, lon0 = 32.6712, -97.3346
    d = 0.0025
    area = [[lat0 - d, lon0 - d], [lat0 - d, lon0 + d], [lat0 + d, lon0 + d], [lat0 + d, lon0 - d]]
    text = T.plan_text("fw.tif", area, home_latlon=(lat0 - 2 * d, lon0))
    (tmp_path / "fw.yaml").write_text(text)
    compiled = compile_plan(tmp_path / "fw.yaml")
    assert compiled.terrain.dem.files[0].vertical.startswith("mean sea level")
    _holds_the_request(compiled)


def test_without_rasterio_a_dem_plan_says_what_to_install(tmp_path, monkeypatch):
    import sys
    p = _plan(tmp_path, T.hill())
    monkeypatch.setitem(sys.modules, "rasterio", None)          # as on an install without the terrain extra
    with pytest.raises(PlanError) as e:
        compile_plan(p)
    assert "needs rasterio" in e.value.message and "wiris-tools[terrain]" in e.value.hint
