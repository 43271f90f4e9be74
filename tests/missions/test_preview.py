"""The preview is rendered and then read back: well-formed SVG with the expected elements, a PNG whose pixels
show the area and the path where they belong, self-contained HTML."""

from __future__ import annotations

import math
from pathlib import Path
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from handmade_mission import handmade
from missions.errors import PlanError
from missions.formats.preview import COLOURS, MAX_FOOTPRINTS, MAX_WAYPOINT_LABELS, build_picture, write_preview
from missions.measure.flight import simulate
from missions.measure.report import report

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def mission():
    return handmade(size_m=160.0, hole_m=40.0)


def _svg(path: Path) -> ET.Element:
    return ET.fromstring(path.read_text(encoding="utf-8"))     # raises on malformed XML


def test_svg_is_well_formed_with_one_shape_per_thing(mission, tmp_path):
    out = write_preview(mission, tmp_path / "p.svg")
    root = _svg(out)
    assert root.tag == SVG + "svg"
    groups = {g.get("id"): g for g in root.iter(SVG + "g")}
    sim = simulate(mission)
    # every photo a dot; the footprints of a regular subset outlined, at most MAX_FOOTPRINTS of them
    assert len(groups["photos"].findall(SVG + "circle")) == len(sim.photos)
    stride = math.ceil(len(sim.photos) / MAX_FOOTPRINTS)
    assert stride > 1 and len(groups["footprints"].findall(SVG + "polygon")) == len(sim.photos[::stride])
    # the area with its hole as an even-odd path, the hole again in red
    area_paths = groups["area"].findall(SVG + "path")
    assert len(area_paths) == 1 and area_paths[0].get("fill-rule") == "evenodd"
    assert area_paths[0].get("d").count("M") == 2
    assert len(groups["gaps"].findall(SVG + "polygon")) == 1
    assert len(groups["path"].findall(SVG + "polyline")) == 1
    assert len(groups["path"].find(SVG + "polyline").get("points").split()) == len(sim.vertices)
    assert groups["arrows"].findall(SVG + "polygon")
    # scale bar label, north arrow, home, legend with the report's photo count
    texts = [t.text for t in root.iter(SVG + "text")]
    assert "N" in texts and "H" in texts
    assert any(t and t.endswith(" m") for t in groups["scale"].iter(SVG + "text") for t in [t.text])
    assert str(len(sim.photos)) in texts


def test_waypoints_numbered_when_few(tmp_path):
    hover = handmade(size_m=60.0, hover=True)
    sim = simulate(hover)
    nav = len({v.item for v in sim.vertices if v.item >= 0})
    assert nav <= MAX_WAYPOINT_LABELS
    root = _svg(write_preview(hover, tmp_path / "w.svg"))
    g = next(g for g in root.iter(SVG + "g") if g.get("id") == "waypoints")
    assert len(g.findall(SVG + "circle")) == nav
    labels = [t.text for t in g.findall(SVG + "text")]
    assert labels and all(l.isdigit() for l in labels)


def _rgb(h):
    h = h.lstrip("#")
    return tuple(int(h[i:i + 2], 16) for i in (0, 2, 4))


def test_png_shows_path_and_area_where_they_are(mission, tmp_path):
    from PIL import Image

    out = write_preview(mission, tmp_path / "p.png")
    img = Image.open(out).convert("RGB")
    pic = build_picture(mission)
    assert img.size == (pic.width, pic.height)
    px = np.asarray(img, dtype=int).reshape(-1, 3)
    assert len(np.unique(px, axis=0)) > 50                     # not blank
    near = int((np.abs(px - np.array(_rgb(COLOURS["path"]))).sum(1) < 40).sum())
    assert near > 500                                          # the path colour is drawn
    # the pixel at the centre of the area's hole is tinted red, one inside the area green-ish
    area = next(s for s in pic.shapes if s.layer == "area")
    hole = area.holes[0]
    hx = sum(p[0] for p in hole[:-1]) / (len(hole) - 1)
    hy = sum(p[1] for p in hole[:-1]) / (len(hole) - 1)
    r, g, b = img.getpixel((int(hx), int(hy)))
    assert r > g and r > b
    # corner region of the area (inside, away from the hole): green dominates red
    xs = [p[0] for p in area.points]
    ys = [p[1] for p in area.points]
    x, y = min(xs) + 0.1 * (max(xs) - min(xs)), min(ys) + 0.1 * (max(ys) - min(ys))
    patch = [img.getpixel((int(x) + dx, int(y) + dy)) for dx in range(-3, 4) for dy in range(-3, 4)]
    assert sum(p[1] for p in patch) > sum(p[0] for p in patch)


def test_html_is_the_interactive_map_with_the_report(mission, tmp_path):
    # the map itself is tested in a browser: tests/missions/test_webmap.py
    out = write_preview(mission, tmp_path / "p.html")
    text = out.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert 'id="map"' in text and 'id="report"' in text and "<link" not in text
    rep = report(mission)
    assert f"{100 * rep.coverage['thermal']:.2f} %" in text


def test_a_preview_is_an_ordinary_file(mission, tmp_path):
    import os

    umask = os.umask(0o022)
    try:
        out = write_preview(mission, tmp_path / "p.svg")
    finally:
        os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o644   # not the temporary file's 0600


def test_unknown_suffix_is_a_plan_error_and_writes_nothing(mission, tmp_path):
    with pytest.raises(PlanError) as e:
        write_preview(mission, tmp_path / "p.jpg")
    assert ".svg, .png or .html" in str(e.value) and e.value.hint
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("out,text,hint", [("missing/p.svg", "output directory does not exist", "create it"),
                                           ("m" * 300 + "/p.svg", "cannot write the preview", "240 bytes")])
def test_unusable_output_path_says_what_to_do(mission, tmp_path, out, text, hint):
    with pytest.raises(PlanError, match=text) as e:
        write_preview(mission, tmp_path / out)
    assert e.value.where == str(tmp_path / out) and hint in e.value.hint
    assert list(tmp_path.iterdir()) == []


def _scale_px_per_m(pic):
    """The map's scale read off its scale bar: the bar's pixel length over the length it is labelled with."""
    bar = next(s for s in pic.shapes if s.layer == "scale" and s.kind == "polyline")
    label = next(s.text for s in pic.shapes if s.layer == "scale" and s.kind == "text")
    value, unit = label.split()
    metres = float(value) * (1000 if unit == "km" else 1)
    return (bar.points[2][0] - bar.points[1][0]) / metres


def _ticks(pic, hemispheres):
    """(degrees, pixel) of the frame's labelled ticks whose label ends in one of `hemispheres`."""
    out = []
    for s in pic.shapes:
        if s.layer == "graticule" and s.kind == "text" and s.text[-1] in hemispheres:
            value = float(s.text.split()[0]) * (-1 if s.text[-1] in "SW" else 1)
            out.append((value, s.points[0][0] if hemispheres in ("EW",) else s.points[0][1] - 3))
    return sorted(out)


def test_the_frame_carries_coordinates_where_they_are(mission):
    from pyproj import Geod

    pic = build_picture(mission)
    scale = _scale_px_per_m(pic)
    lons, lats = _ticks(pic, "EW"), _ticks(pic, "NS")
    assert len(lons) >= 2 and len(lats) >= 2
    geod = Geod(ellps="WGS84")
    home_lat, home_lon = mission.home[0], mission.home[1]
    home_x = next(s for s in pic.shapes if s.layer == "home" and s.kind == "polygon").points[0][0]
    home_y = next(s for s in pic.shapes if s.layer == "home" and s.kind == "polygon").points[0][1] + 9
    for lon, x in lons:
        # east of home by the geodesic distance along home's parallel, at the bar's scale (within 2 px)
        _, _, d = geod.inv(home_lon, home_lat, lon, home_lat)
        assert x - home_x == pytest.approx(math.copysign(d, lon - home_lon) * scale, abs=2.0)
    for lat, y in lats:
        _, _, d = geod.inv(home_lon, home_lat, home_lon, lat)
        assert home_y - y == pytest.approx(math.copysign(d, lat - home_lat) * scale, abs=2.0)


def test_footprints_are_drawn_over_the_area_fill(mission, tmp_path):
    root = _svg(write_preview(mission, tmp_path / "p.svg"))
    order = [g.get("id") for g in root.iter(SVG + "g")]
    assert order.index("area") < order.index("footprints") < order.index("area_outline")
    fp = root.find(f".//{SVG}g[@id='footprints']/{SVG}polygon")
    assert fp.get("stroke") == COLOURS["footprint_line"]


def test_a_wide_area_needs_no_detail(mission):
    assert build_picture(mission).detail is None


def test_a_thin_corridor_gets_a_detail_where_its_passes_are_apart(tmp_path):
    from missions.compile import compile_plan

    corridor = compile_plan(Path(__file__).resolve().parents[2] / "examples" / "powerline-corridor.yaml")
    sim = simulate(corridor)
    pic = build_picture(corridor, sim)
    assert pic.detail is not None
    x0, y0, x1, y1 = pic.detail.window_m
    inside = [p for p in sim.photos if x0 <= p.x <= x1 and y0 <= p.y <= y1]
    # the nearest photos of two different passes inside the window
    across = min(math.hypot(a.x - b.x, a.y - b.y) for a in inside for b in inside if a.span != b.span)
    main = _scale_px_per_m(pic)
    assert across * main < 8                                  # on the map the passes' photos nearly touch ...
    assert across * pic.detail.scale >= 30 and pic.detail.scale >= 4 * main   # ... in the detail they are apart
    root = _svg(write_preview(corridor, tmp_path / "c.svg"))
    groups = {g.get("id"): g for g in root.iter(SVG + "g")}
    assert groups["detail-path"].findall(SVG + "polyline") and groups["detail-photos"].findall(SVG + "circle")
    assert groups["detail-mark"].findall(SVG + "polygon")
    bx0, by0, bx1, by1 = pic.detail.box_px
    for c in groups["detail-photos"].findall(SVG + "circle"):    # cut to the detail's box
        assert bx0 <= float(c.get("cx")) <= bx1 and by0 <= float(c.get("cy")) <= by1
