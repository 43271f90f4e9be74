"""The interactive mission map: `wiris mission preview PLAN -o FILE.html [--tiles URL_TEMPLATE]`.

One self-contained HTML file: Leaflet (vendored in templates/vendor, inlined), the mission as JSON, and a
little script that draws it. Pan and zoom, a metric scale, the areas, holes and exclusion zones, the flown
path in flight order (start and end marked, arrows for the direction, one colour per part when the mission
is split at the vehicle's item limit), photo points and footprints (each a layer to toggle), and every
mission item clickable (its number as uploaded, command, altitude and the commands that follow it). The
page makes no request to any host: a basemap is drawn only from the tile server the user names with
`--tiles`, its attribution shown.

Like the PNG/SVG preview it is drawn from the simulated flight (missions.measure.flight.simulate), not from
the planner's intent, and it carries the measured report's figures.
"""

from __future__ import annotations

import base64
from dataclasses import dataclass
import json
import math
from pathlib import Path
import re
from typing import Any, Sequence
from urllib.parse import urlsplit

from markupsafe import Markup
import numpy as np

from missions.compiled import Compiled
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, MissionItem
from missions.errors import PlanError
from missions.formats.itemcheck import command_label
from missions.measure.report import MissionReport, footprint_ring
from templates import TEMPLATES_DIR, render

LEAFLET = TEMPLATES_DIR / "vendor" / "leaflet-1.9.4"
# Beyond these counts the browser spends seconds per redraw: a regular subset is drawn and the page says so.
MAX_FOOTPRINTS = 4000
MAX_PHOTOS = 20000
MAX_ARROWS = 400
# Parts in the order of the mission: distinct hues a colour-blind reader can still tell apart (Okabe-Ito).
PART_COLOURS = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000")
PAYLOAD_COLOURS = ("#202020", "#0a8f88", "#b5179e")
ALTITUDE_REFERENCE = {FRAME_GLOBAL_RELATIVE_ALT: "above home", FRAME_GLOBAL: "AMSL",
                      FRAME_GLOBAL_TERRAIN_ALT: "above terrain"}


@dataclass(frozen=True)
class TileSource:
    """A basemap the user asked for: an XYZ URL template ({z}/{x}/{y}, optional {s}) and its attribution."""

    url: str
    attribution: str

    @staticmethod
    def parse(url: str, attribution: str | None = None) -> "TileSource":
        """Check the template; the attribution defaults to OpenStreetMap's for its servers, else to the host."""
        parts = urlsplit(url)
        missing = [k for k in ("{z}", "{x}", "{y}") if k not in url]
        if parts.scheme not in ("http", "https") or not parts.netloc or missing:
            raise PlanError(f"'{url}' is not a tile URL template"
                            + (f" (no {', '.join(missing)})" if missing else ""), where="--tiles",
                            hint="give an http(s) XYZ template, e.g. https://tile.openstreetmap.org/{z}/{x}/{y}.png")
        if attribution is None:
            attribution = ("© OpenStreetMap contributors" if "openstreetmap" in parts.netloc.lower()
                           else f"tiles: {parts.netloc}")
        return TileSource(url, attribution)


def _ll(lat: float, lon: float) -> list[float]:
    return [round(lat, 7), round(lon, 7)]


def _part_of_each_item(compiled: Compiled) -> list[tuple[int, int]]:
    """(part, index in that part's upload) of each item of compiled.items. A part is a slice of the mission
    with a few items of its own around it (resume speed, waypoint and trigger; hold at the end), so the
    mission's items are found in the parts in order."""
    where: list[tuple[int, int]] = []
    items = compiled.items
    for k, part in enumerate(compiled.parts):
        for j, it in enumerate(part):
            if len(where) < len(items) and it == items[len(where)]:
                where.append((k, j))
    while len(where) < len(items):     # parts that do not hold the items (a hand-built Compiled): one part
        where.append((0, len(where)))
    return where


def _altitude_text(it: MissionItem, flown_alt_m: float | None) -> str:
    """The altitude as the item gives it; for one that moves the vehicle without a position of its own
    (return to launch), the altitude it is flown at."""
    ref = ALTITUDE_REFERENCE.get(it.frame)
    if ref:
        return f"{it.z:g} m {ref}"
    return f"flown at {flown_alt_m:g} m above home" if flown_alt_m is not None else "no position"


def _param_text(it: MissionItem) -> str:
    """The item's non-zero params, as a pilot compares them with QGC's editor."""
    vals = [("p1", it.param1), ("p2", it.param2), ("p3", it.param3), ("p4", it.param4)]
    return ", ".join(f"{k} {v:g}" for k, v in vals if v == v and v != 0)   # v == v drops NaN ("keep")


def _items(compiled: Compiled, sim: Any) -> list[dict]:
    """Every mission item as the map lists it; positioned ones (they put a vertex on the flown path) carry
    where the vehicle went, the others follow the positioned item before them."""
    seq_base = 1 if compiled.firmware == "ardupilot" else 0     # ArduPilot keeps home as item 0
    where = _part_of_each_item(compiled)
    vertex_of: dict[int, int] = {}
    for i, v in enumerate(sim.vertices):
        if v.item >= 0:
            vertex_of.setdefault(v.item, i)
    out = []
    for i, it in enumerate(compiled.items):
        part, j = where[i]
        v = vertex_of.get(i)
        flown = round(sim.vertices[v].alt_m, 1) if v is not None else None
        row: dict[str, Any] = {"index": i, "seq": j + seq_base, "part": part,
                               "command": command_label(it.command).removeprefix("MAV_CMD_"),
                               "altitude": _altitude_text(it, flown), "params": _param_text(it), "comment": it.comment}
        if v is not None:
            row["at"] = _ll(*sim.latlon[v])
            row["alt_m"] = flown
        out.append(row)
    return out


def _path_by_part(sim: Any, where: Sequence[tuple[int, int]]) -> list[dict]:
    """The flown path cut where the part changes; each piece starts where the one before ended."""
    pieces: list[dict] = []
    for v, ll in zip(sim.vertices, sim.latlon):
        part = where[v.item][0] if 0 <= v.item < len(where) else (pieces[-1]["part"] if pieces else 0)
        if not pieces or pieces[-1]["part"] != part:
            start = pieces[-1]["path"][-1:] if pieces else []
            pieces.append({"part": part, "colour": PART_COLOURS[part % len(PART_COLOURS)], "path": list(start)})
        pieces[-1]["path"].append(_ll(*ll))
    return pieces


def _arrows(sim: Any) -> list[dict]:
    """Direction marks at the middle of the path's longer legs (at most MAX_ARROWS, spread evenly)."""
    legs = []
    for a, b, la, lb in zip(sim.vertices, sim.vertices[1:], sim.latlon, sim.latlon[1:]):
        d = math.hypot(b.x - a.x, b.y - a.y)
        if d > 1.0:
            heading = math.degrees(math.atan2(b.x - a.x, b.y - a.y)) % 360   # from north, clockwise
            legs.append({"at": _ll((la[0] + lb[0]) / 2, (la[1] + lb[1]) / 2), "heading": round(heading, 1)})
    stride = max(1, math.ceil(len(legs) / MAX_ARROWS))
    return legs[::stride]


def _rings(projection: Any, ring: Sequence[tuple[float, float]]) -> list[list[float]]:
    lat, lon = projection.to_latlon([p[0] for p in ring], [p[1] for p in ring])
    return [_ll(a, b) for a, b in zip(lat.tolist(), lon.tolist())]


ZONE_COLOURS = {"no_fly": "#b0122f", "no_photo": "#7b2cbf", "exclude": "#e6194b"}


def _declared_zones(compiled: Compiled, projection: Any) -> list[dict]:
    """The plan's zones as the compiler gives them on each step (AreaInfo.zones, missions.geometry.zones.StepZones:
    kind, name, and the polygon as drawn), each once."""
    out, seen = [], set()
    for a in compiled.areas:
        step_zones = getattr(a, "zones", None)
        for z in getattr(step_zones, "zones", None) or ():
            if (z.kind, z.name, z.where) in seen:
                continue
            seen.add((z.kind, z.name, z.where))
            drawn = z.xy(projection)
            for poly in getattr(drawn, "geoms", [drawn]):
                out.append({"kind": z.kind, "name": z.name, "colour": ZONE_COLOURS.get(z.kind, "#e6194b"),
                            "ring": _rings(projection, list(poly.exterior.coords))})
    return out


def map_data(compiled: Compiled, sim: Any, rep: MissionReport, tiles: TileSource | None = None) -> dict:
    """Everything the page draws, as JSON-ready values (degrees, 7 decimals)."""
    where = _part_of_each_item(compiled)
    names = [p.name for p in compiled.payloads]
    areas, zones = [], []
    for a in compiled.areas:
        for rings in a.area.latlon_rings():
            areas.append({"step": a.step + 1, "kind": a.kind, "rings": [[_ll(*p) for p in r] for r in rings]})
            zones.extend({"step": a.step + 1, "ring": [_ll(*p) for p in hole]} for hole in rings[1:])
    photos = sim.photos
    photo_stride = max(1, math.ceil(len(photos) / MAX_PHOTOS))
    fp_stride = max(1, math.ceil(len(photos) / MAX_FOOTPRINTS))
    items = _items(compiled, sim)
    seq_of = {row["index"]: row["seq"] for row in items}
    photo_rows = [{"at": _ll(p.lat, p.lon), "n": n + 1, "payload": min((names.index(x) for x in p.payloads if x in names),
                                                                        default=0),
                   "alt_m": round(p.alt_m, 1), "item": seq_of.get(p.item)}
                  for n, p in enumerate(photos) if n % photo_stride == 0]
    spacing = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(photos, photos[1:]) if a.span == b.span]
    footprints = [_rings(sim.projection, footprint_ring(p, compiled.payload(p.payloads[0])))
                  for p in photos[::fp_stride] if p.payloads]
    latlon = sim.latlon
    return {
        "title": compiled.name, "firmware": compiled.firmware, "parts": len(compiled.parts),
        "home": _ll(compiled.home[0], compiled.home[1]),
        "start": _ll(*latlon[0]) if latlon else None, "end": _ll(*latlon[-1]) if latlon else None,
        "areas": areas, "zones": zones, "declared_zones": _declared_zones(compiled, sim.projection), "path": _path_by_part(sim, where), "arrows": _arrows(sim),
        "items": items, "photos": photo_rows, "photo_stride": photo_stride,
        # the photos' spacing along a line sizes their dots to the zoom (a dense line must not hide the path)
        "photo_spacing_m": round(float(np.median(spacing)), 2) if spacing else None,
        "footprints": footprints, "footprint_stride": fp_stride,
        "payloads": [{"name": n, "colour": PAYLOAD_COLOURS[min(k, 2)]} for k, n in enumerate(names)],
        "part_colours": [PART_COLOURS[k % len(PART_COLOURS)] for k in range(len(compiled.parts))],
        "tiles": None if tiles is None else {"url": tiles.url, "attribution": tiles.attribution},
    }


def _script_json(value: Any) -> Markup:
    """JSON safe inside <script>: no `</` can close the element, no `<!--` open a comment."""
    text = json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    return Markup(text.replace("<", "\\u003c"))


def _data_uri(path: Path) -> str:
    return "data:image/png;base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def leaflet_assets() -> tuple[Markup, Markup]:
    """The vendored Leaflet's script and style, made to load nothing: the source-map comment dropped, the layer
    control's icons as data: URIs, the default marker icon (never used: the map draws circles) emptied."""
    js = (LEAFLET / "leaflet.js").read_text(encoding="utf-8")
    js = re.sub(r"\n//# sourceMappingURL=\S+\s*$", "\n", js)
    css = (LEAFLET / "leaflet.css").read_text(encoding="utf-8")
    css = css.replace("url(images/layers.png)", f"url({_data_uri(LEAFLET / 'images' / 'layers.png')})")
    css = css.replace("url(images/layers-2x.png)", f"url({_data_uri(LEAFLET / 'images' / 'layers-2x.png')})")
    css = css.replace("url(images/marker-icon.png)", "none")
    if "url(images/" in css or re.search(r"</script|<!--", js, re.IGNORECASE):
        raise PlanError("the vendored Leaflet refers to a file the page cannot inline", where=str(LEAFLET),
                        hint="restore templates/vendor/leaflet-1.9.4 from the npm package leaflet@1.9.4")
    return Markup(js), Markup(css)


def render_map_html(compiled: Compiled, sim: Any, rep: MissionReport, rows: Sequence[tuple[str, str]],
                    tiles: TileSource | None = None) -> str:
    """The page: the map with its layer switch, the item list beside it, the report's figures below."""
    js, css = leaflet_assets()
    return render("webmap.html.j2", title=compiled.name, leaflet_js=js, leaflet_css=css,
                  data=_script_json(map_data(compiled, sim, rep, tiles)), rows=rows,
                  warnings=[w.message for w in rep.warnings], errors=[e.message for e in rep.errors],
                  areas=rep.areas)
