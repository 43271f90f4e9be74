"""The interactive map (`wiris mission preview -o FILE.html`) in a real browser: Debian's Chromium driven by
playwright. It renders, logs no console error, requests nothing but its own file (a basemap only from the
--tiles server, here a real HTTP server on 127.0.0.1), pans and zooms, toggles layers, and a click on a
mission item shows its number, command and altitude.

Skipped, with the reason, when playwright or a Chromium binary is missing (CHROMIUM=/path/to/chromium
names another binary; .ci/run installs Debian's).
"""

from __future__ import annotations

from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
import io
import json
import os
from pathlib import Path
import re
import shutil
import threading

import pytest
from click.testing import CliRunner

from mission_plans import small_plan
from missions.compile import compile_plan
from missions.errors import PlanError
from missions.formats.preview import write_preview
from missions.formats.webmap import TileSource, map_data
from missions.measure.flight import simulate
from missions.measure.report import report
from wiris_tools.cli import cli

CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def _chromium() -> str | None:
    for candidate in (os.environ.get("CHROMIUM"), "/usr/bin/chromium", shutil.which("chromium")):
        if candidate and Path(candidate).is_file():
            return candidate
    return None


# ---- without a browser: the page's data and the options ------------------------------------------------------

@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    d = tmp_path_factory.mktemp("webmap-plans")
    return {"one": small_plan(d, "one"), "split": small_plan(d, "split", limit=16),
            "px4": small_plan(d, "px4", firmware="px4", camera_change=False)}


@pytest.fixture(scope="module")
def compiled(plans):
    return {k: compile_plan(p) for k, p in plans.items()}


def test_page_holds_everything_and_names_no_host(compiled, tmp_path):
    out = write_preview(compiled["one"], tmp_path / "m.html")
    text = out.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and 'id="report"' in text and 'id="mission-data"' in text
    assert "<link" not in text and not re.search(r"<script[^>]*\bsrc=", text)
    assert not re.search(r"url\((?!data:|#)", text)        # every CSS image is a data: URI (#: IE VML, no file)
    assert "sourceMappingURL" not in text
    rep = report(compiled["one"])
    assert f"{100 * rep.coverage['thermal']:.1f} %" in text


def test_every_item_is_listed_with_its_upload_number(compiled):
    c = compiled["one"]
    sim = simulate(c)
    data = map_data(c, sim, report(c, sim))
    assert [row["seq"] for row in data["items"]] == list(range(1, len(c.items) + 1))   # ArduPilot: home is 0
    positioned = [row for row in data["items"] if "at" in row]
    assert {row["command"] for row in positioned} >= {"NAV_TAKEOFF", "NAV_WAYPOINT"}
    hover = next(row for row in positioned if row["altitude"] == "30 m above home")
    assert hover["at"] == pytest.approx([50.1105, 14.5035], abs=1e-6)
    assert data["tiles"] is None and data["start"] and data["end"]
    px4 = compiled["px4"]
    px4_sim = simulate(px4)
    rows = map_data(px4, px4_sim, report(px4, px4_sim))["items"]
    assert [row["seq"] for row in rows] == list(range(len(px4.items)))                 # PX4 numbers from 0


def test_a_split_mission_is_drawn_in_one_colour_per_part(compiled):
    c = compiled["split"]
    assert len(c.parts) > 1
    sim = simulate(c)
    data = map_data(c, sim, report(c, sim))
    assert [p["part"] for p in data["path"]] == list(range(len(c.parts)))
    assert len({p["colour"] for p in data["path"]}) == len(c.parts)
    # each piece starts where the one before ended: the path has no gap at a cut
    for a, b in zip(data["path"], data["path"][1:]):
        assert a["path"][-1] == b["path"][0]
    # an item's number is its place in its part's upload
    for row in data["items"]:
        assert c.parts[row["part"]][row["seq"] - 1] == c.items[row["index"]]


@pytest.mark.parametrize("url, fragment", [
    ("ftp://tiles.example/{z}/{x}/{y}.png", "not a tile URL template"),
    ("https://tiles.example/{z}/{x}.png", "no {y}"),
    ("tile.openstreetmap.org/{z}/{x}/{y}.png", "not a tile URL template")])
def test_a_bad_tile_template_says_how_to_write_one(url, fragment):
    with pytest.raises(PlanError) as e:
        TileSource.parse(url)
    assert fragment in str(e.value) and "{z}/{x}/{y}" in e.value.hint


def test_attribution_defaults():
    assert TileSource.parse("https://tile.openstreetmap.org/{z}/{x}/{y}.png").attribution == \
        "© OpenStreetMap contributors"
    assert TileSource.parse("http://127.0.0.1:9/{z}/{x}/{y}.png").attribution == "tiles: 127.0.0.1:9"
    assert TileSource.parse("http://h/{z}/{x}/{y}.png", "© someone").attribution == "© someone"


def test_tiles_on_a_png_is_refused_and_writes_nothing(plans, tmp_path):
    r = CliRunner().invoke(cli, ["mission", "preview", str(plans["one"]), "-o", str(tmp_path / "m.png"),
                                 "--tiles", "http://127.0.0.1:9/{z}/{x}/{y}.png"])
    assert r.exit_code == 1 and "only under the interactive map" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "m.png").exists()


# ---- in Chromium ------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def browser():
    playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed "
                                         "(make test installs it from requirements-test.lock)")
    binary = _chromium()
    if binary is None:
        pytest.skip("no Chromium found: apt-get install chromium (or set CHROMIUM=/path/to/chromium)")
    with playwright_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=binary, args=CHROMIUM_ARGS)
        yield b
        b.close()


class Page:
    """A page of the map with everything it asked the network for and every console error it logged."""

    def __init__(self, browser, path: Path):
        self.url = path.resolve().as_uri()
        self.requests: list[str] = []
        self.errors: list[str] = []
        self.context = browser.new_context(viewport={"width": 1400, "height": 900})
        self.page = self.context.new_page()
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.goto(self.url)
        self.page.wait_for_function("window.wirisMap !== undefined", timeout=30_000)

    def js(self, expression: str, arg=None):
        return self.page.evaluate(expression, arg)

    def close(self):
        self.context.close()


@pytest.fixture
def open_map(browser):
    pages = []

    def _open(path: Path) -> Page:
        pages.append(Page(browser, path))
        return pages[-1]

    yield _open
    for p in pages:
        p.close()


def test_map_renders_offline_with_no_console_error(compiled, open_map, tmp_path):
    m = open_map(write_preview(compiled["one"], tmp_path / "m.html"))
    m.page.wait_for_timeout(300)
    assert m.errors == []
    assert m.requests == [m.url]                              # its own file, nothing else
    # the layers are on the map, fitted to the mission, with a metric scale
    overlays = m.js("Object.keys(wirisMap.overlays)")
    assert {"area", "flight path (arrows: direction)", "photo points", "mission items (click one)",
            "home, start, end"} <= set(overlays) and any(o.startswith("photo footprints") for o in overlays)
    assert m.js("Object.values(wirisMap.overlays).every(l => wirisMap.map.hasLayer(l))")
    assert re.fullmatch(r"\d+ k?m", m.page.inner_text(".leaflet-control-scale-line").strip())
    inside = m.js("wirisMap.map.getBounds().contains([50.1115, 14.5050])")
    assert inside
    # the path and the area are really painted: their colours in a screenshot of the map
    from PIL import Image

    shot = Image.open(io.BytesIO(m.page.locator("#map").screenshot())).convert("RGB")
    colours = {rgb for _, rgb in shot.getcolors(maxcolors=shot.width * shot.height)}
    assert any(abs(r - 0x00) < 30 and abs(g - 0x72) < 30 and abs(b - 0xb2) < 30 for r, g, b in colours)   # path
    assert any(g > r + 20 and g > b + 20 for r, g, b in colours)                                          # area


def test_pan_and_zoom(compiled, open_map, tmp_path):
    m = open_map(write_preview(compiled["one"], tmp_path / "m.html"))
    z0 = m.js("wirisMap.map.getZoom()")
    m.page.click(".leaflet-control-zoom-in")
    m.page.wait_for_function(f"wirisMap.map.getZoom() > {z0}", timeout=10_000)
    m.page.wait_for_timeout(600)                              # the zoom animation ends before the drag
    c0 = m.js("wirisMap.map.getCenter()")
    box = m.page.locator("#map").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    m.page.mouse.move(x, y)
    m.page.mouse.down()
    for k in range(1, 11):
        m.page.mouse.move(x + 20 * k, y + 10 * k)
    m.page.mouse.up()
    c1 = m.js("wirisMap.map.getCenter()")
    assert c1["lng"] < c0["lng"] and c1["lat"] > c0["lat"]    # dragged right and down: the view moved west, north
    # photo dots shrink when zoomed out, so that a dense line of them does not hide the path
    radius = "Object.values(wirisMap.overlays['photo points']._layers)[0].getRadius()"
    for zoom, expected in ((12, 0.7), (20, 3.0)):
        m.js(f"() => {{ wirisMap.map.setZoom({zoom}, {{animate: false}}); }}")
        m.page.wait_for_function(f"wirisMap.map.getZoom() === {zoom}", timeout=10_000)
        assert m.js(radius) == pytest.approx(expected)
    assert m.errors == []


def test_clicking_a_waypoint_shows_its_number_command_and_altitude(compiled, open_map, tmp_path):
    c = compiled["one"]
    m = open_map(write_preview(c, tmp_path / "m.html"))
    hover = next(r for r in m.js("wirisMap.data.items") if r["altitude"] == "30 m above home")
    m.js("i => { wirisMap.map.setView(wirisMap.markers[i].getLatLng(), 19); }", hover["index"])
    m.page.wait_for_timeout(400)
    pt = m.js("i => wirisMap.map.latLngToContainerPoint(wirisMap.markers[i].getLatLng())", hover["index"])
    box = m.page.locator("#map").bounding_box()
    m.page.mouse.click(box["x"] + pt["x"], box["y"] + pt["y"])
    popup = m.page.locator(".leaflet-popup-content")
    popup.wait_for(timeout=10_000)
    text = popup.inner_text()
    assert f"#{hover['seq']} NAV_WAYPOINT" in text and "30 m above home" in text
    # the commands after it (the photo it takes, the camera change) are in its popup too
    assert f"then #{hover['seq'] + 1} IMAGE_START_CAPTURE" in text
    assert m.errors == []


def test_a_row_of_the_item_list_opens_that_item(compiled, open_map, tmp_path):
    m = open_map(write_preview(compiled["one"], tmp_path / "m.html"))
    rows = m.js("wirisMap.data.items")
    takeoff = next(r for r in rows if r["command"] == "NAV_TAKEOFF")
    m.page.click(f'#items tr[data-index="{takeoff["index"]}"]')
    popup = m.page.locator(".leaflet-popup-content")
    popup.wait_for(timeout=10_000)
    assert f"#{takeoff['seq']} NAV_TAKEOFF" in popup.inner_text() and "40 m above home" in popup.inner_text()


def test_footprints_and_photos_toggle(compiled, open_map, tmp_path):
    m = open_map(write_preview(compiled["one"], tmp_path / "m.html"))
    for name in ("photo footprints", "photo points"):
        label = m.page.locator(".leaflet-control-layers-overlays label", has_text=name)
        key = m.js("n => Object.keys(wirisMap.overlays).find(k => k.startsWith(n))", name)
        assert m.js("k => wirisMap.map.hasLayer(wirisMap.overlays[k])", key)
        label.locator("input").click()
        assert not m.js("k => wirisMap.map.hasLayer(wirisMap.overlays[k])", key)
        label.locator("input").click()
        assert m.js("k => wirisMap.map.hasLayer(wirisMap.overlays[k])", key)


def test_parts_in_colours_in_the_browser(compiled, open_map, tmp_path):
    c = compiled["split"]
    m = open_map(write_preview(c, tmp_path / "m.html"))
    legend = m.page.inner_text("#legend")
    assert f"part 2 of {len(c.parts)}" in legend
    colours = m.js("""Object.values(wirisMap.overlays['flight path (arrows: direction)']._layers)
                      .filter(l => l instanceof L.Polyline).map(l => l.options.color)""")
    assert len(set(colours)) == len(c.parts)
    assert m.errors == []


class _TileServer(BaseHTTPRequestHandler):
    tile = b""

    def do_GET(self):  # noqa: N802 (http.server's name)
        self.send_response(200)
        self.send_header("Content-Type", "image/png")
        self.send_header("Content-Length", str(len(self.tile)))
        self.end_headers()
        self.wfile.write(self.tile)

    def log_message(self, *args):
        pass


@pytest.fixture
def tile_server():
    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (256, 256), (200, 180, 240)).save(buf, format="PNG")
    handler = type("Handler", (_TileServer,), {"tile": buf.getvalue()})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_port}"
    server.shutdown()
    server.server_close()
    thread.join(timeout=10)


def test_tiles_come_only_from_the_named_server_with_its_attribution(plans, open_map, tmp_path, tile_server):
    out = tmp_path / "m.html"
    r = CliRunner().invoke(cli, ["mission", "preview", str(plans["one"]), "-o", str(out),
                                 "--tiles", tile_server + "/{z}/{x}/{y}.png", "--attribution", "test tiles ©"])
    assert r.exit_code == 0, r.output
    m = open_map(out)
    m.page.wait_for_function("document.querySelectorAll('.leaflet-tile-loaded').length > 0", timeout=30_000)
    others = [u for u in m.requests if u != m.url]
    assert others and all(re.fullmatch(re.escape(tile_server) + r"/\d+/\d+/\d+\.png", u) for u in others), others
    assert "test tiles ©" in m.page.inner_text(".leaflet-control-attribution")
    assert m.errors == []
    assert json.loads(m.js("JSON.stringify(wirisMap.data.tiles)"))["attribution"] == "test tiles ©"


def test_the_zones_a_step_carries_are_drawn_with_their_kind(compiled):
    # The zones feature hands each step its zones (AreaInfo.zones.zones: kind, name, where, xy(projection));
    # here one stand-in zone of that shape, a square inside the survey, stands for them.
    from dataclasses import fields, replace
    from types import SimpleNamespace

    from shapely.geometry import box

    c = compiled["one"]
    sim = simulate(c)
    x, y = sim.projection.point_to_xy(50.1115, 14.5050)
    zone = SimpleNamespace(kind="no_photo", name="substation", where="plan.yaml:9:7",
                           xy=lambda proj: box(x - 10, y - 10, x + 10, y + 10))
    zoned = replace(c, areas=tuple(SimpleNamespace(**({f.name: getattr(a, f.name) for f in fields(a)}
                                                      | {"zones": SimpleNamespace(zones=(zone, zone))}))
                                   for a in c.areas))
    data = map_data(zoned, sim, report(c, sim))
    assert len(data["declared_zones"]) == 1                     # each zone once, though two steps list it
    z = data["declared_zones"][0]
    assert z["kind"] == "no_photo" and z["name"] == "substation" and len(z["ring"]) == 5
    lats = [p[0] for p in z["ring"]]
    assert min(lats) < 50.1115 < max(lats)
    assert map_data(c, sim, report(c, sim))["declared_zones"] == []
