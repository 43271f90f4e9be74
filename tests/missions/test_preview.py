"""The preview is rendered and then read back: well-formed SVG with the expected elements, a PNG whose pixels
show the area and the path where they belong, self-contained HTML."""

from __future__ import annotations

from pathlib import Path
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from handmade_mission import handmade
from missions.errors import PlanError
from missions.formats.preview import COLOURS, MAX_WAYPOINT_LABELS, build_picture, write_preview
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
    # every photo a dot, every footprint a polygon (few enough here to draw all)
    assert len(groups["photos"].findall(SVG + "circle")) == len(sim.photos)
    assert len(groups["footprints"].findall(SVG + "polygon")) == len(sim.photos)
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
