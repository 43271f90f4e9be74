"""A picture of a compiled mission that a person can check at a glance: `wiris mission preview PLAN -o FILE`.

    write_preview(compiled, "plan.png")      # .svg, .png or .html by suffix

Drawn from the simulated flight (missions.measure.flight.simulate), not from the planner's intent: area (holes and
exclusions in red), photo footprints (faint orange), the flown path (blue, arrows show direction), photo
points, numbered waypoints (when there are few enough to read), home, a scale bar, a north arrow, and a
legend with the report's key figures. North is up: the simulation's azimuthal-equidistant plane is centred
on the mission, so meridians are vertical to well under a degree over any single survey.

One display list (polygons, lines, dots, text in pixel coordinates) feeds two renderers: SVG written
directly (no dependency) and PNG with Pillow (2× supersampled, then reduced, for smooth lines). The HTML
is self-contained: the inline SVG plus the report table, no network resources.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path
from typing import Any, Callable, Sequence
from xml.sax.saxutils import escape

from markupsafe import Markup
import numpy as np

from missions.compiled import Compiled
from missions.errors import PlanError
from missions.formats.planfile import replacing
from missions.measure.flight import simulate
from missions.measure.report import MissionReport, footprint_ring, report
from templates import render

MAP_W, MAP_H = 1000, 800          # map area in pixels
PANEL_W = 430                     # legend panel to the right
PAD = 40
# Beyond these counts the picture is a solid smear: draw a regular subset and say so in the legend.
MAX_FOOTPRINTS = 4000
MAX_PHOTO_DOTS = 20000
MAX_WAYPOINT_LABELS = 60

COLOURS = {
    "background": "#ffffff",
    "panel": "#f4f6f8",
    "area_fill": "#3cb44b", "area_line": "#1e7a2c",
    "gap_fill": "#e6194b", "gap_line": "#b0122f",
    "footprint_fill": "#ffa500", "footprint_line": "#d98200",
    "path": "#1e6bd8",
    "photo": "#202020",
    "waypoint": "#6a1bb0",
    "home": "#000000",
    "photo2": "#0a8f88", "photo3": "#b5179e",
    "text": "#111111",
    "muted": "#555555",
}


@dataclass(frozen=True)
class Shape:
    kind: str                                   # polygon | polyline | circle | text | arrow
    points: tuple[tuple[float, float], ...] = ()
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()
    fill: str | None = None
    fill_opacity: float = 1.0
    stroke: str | None = None
    stroke_width: float = 1.0
    radius: float = 0.0
    text: str = ""
    size: float = 13.0
    anchor: str = "start"                       # start | middle | end
    bold: bool = False
    layer: str = ""                             # SVG group id / PNG overlay


@dataclass(frozen=True)
class Picture:
    width: int
    height: int
    shapes: tuple[Shape, ...]
    title: str
    rows: tuple[tuple[str, str], ...] = field(default=())       # the legend's figures
    warnings: tuple[str, ...] = ()


def _nice_length(max_m: float) -> float:
    """The largest 1-2-5 × 10^k metres not above max_m."""
    if max_m <= 0:
        return 1.0
    k = 10 ** math.floor(math.log10(max_m))
    for m in (5, 2, 1):
        if m * k <= max_m:
            return m * k
    return k


def _fmt_len(m: float) -> str:
    return f"{m / 1000:g} km" if m >= 1000 else f"{m:g} m"


def _fmt_time(s: float) -> str:
    s = int(round(s))
    return f"{s // 3600} h {s % 3600 // 60:02d} min" if s >= 3600 else f"{s // 60} min {s % 60:02d} s"


XY = tuple[float, float]


@dataclass(frozen=True)
class _MapContent:
    """What the map shows, in the simulation's metres."""

    areas: tuple[tuple[tuple[XY, ...], ...], ...]   # per polygon: its outer ring, then its holes
    path: tuple[XY, ...]
    photos: tuple[Any, ...]                         # missions.measure.flight.Photo
    footprints: tuple[tuple[XY, ...], ...]          # of every fp_stride-th photo, for its first payload
    fp_stride: int

    def points(self) -> list[XY]:
        return ([pt for rings in self.areas for ring in rings for pt in ring] + list(self.path)
                + [pt for r in self.footprints for pt in r])


@dataclass(frozen=True)
class _Frame:
    """Metres in the simulation's plane to map pixels: north up, the content centred and fitted."""

    scale: float            # pixels per metre
    cx: float               # the content's centre (metres) ...
    cy: float
    mx: float               # ... drawn here (pixels)
    my: float

    @staticmethod
    def fitting(pts: Sequence[XY]) -> _Frame:
        xs = np.array([p[0] for p in pts] or [0.0])
        ys = np.array([p[1] for p in pts] or [0.0])
        x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
        span = max(x1 - x0, y1 - y0, 10.0)
        # the map keeps a free band at the bottom for the scale bar and at the left for the north arrow
        left, right, top, bottom = PAD + 30, MAP_W - PAD, PAD, MAP_H - PAD - 30
        scale = min((right - left) / max(x1 - x0, span * 0.05), (bottom - top) / max(y1 - y0, span * 0.05))
        return _Frame(scale, (x0 + x1) / 2, (y0 + y1) / 2, (left + right) / 2, (top + bottom) / 2)

    def px(self, x: float, y: float) -> XY:
        return (round(self.mx + (x - self.cx) * self.scale, 2), round(self.my - (y - self.cy) * self.scale, 2))

    def ring(self, ring: Sequence[XY]) -> tuple[XY, ...]:
        return tuple(self.px(*q) for q in ring)


def build_picture(compiled: Compiled, sim: Any = None, rep: MissionReport | None = None) -> Picture:
    """The preview's display list: the map from the simulated flight, the legend from the measured report."""
    sim = sim or simulate(compiled)
    rep = rep or report(compiled, sim)
    content = _map_content(compiled, sim)
    frame = _Frame.fitting(content.points())
    shapes = [*_footprint_shapes(content.footprints, frame), *_area_shapes(content.areas, frame),
              *_path_shapes(content.path, frame), *_sortie_shapes(rep, sim.projection, frame),
              *_photo_shapes(compiled, content.photos, frame),
              *_waypoint_shapes(compiled, sim, frame), *_home_shapes(compiled, sim.projection, frame),
              *_scale_bar_shapes(frame.scale), *_north_arrow_shapes()]
    rows, legend = _legend(compiled, rep, content.fp_stride)
    shapes.extend(legend)
    warn = tuple(w.message for w in rep.warnings)
    return Picture(MAP_W + PANEL_W, MAP_H, tuple(shapes), compiled.name, tuple(rows), warn)


def _map_content(compiled: Compiled, sim: Any) -> _MapContent:
    proj = sim.projection
    areas = []
    for a in compiled.areas:
        for rings in a.area.latlon_rings():
            xy_rings = []
            for ring in rings:
                x, y = proj.to_xy([p[0] for p in ring], [p[1] for p in ring])
                xy_rings.append(tuple(zip(x.tolist(), y.tolist())))
            areas.append(tuple(xy_rings))
    photos = tuple(sim.photos)
    fp_stride = max(1, math.ceil(len(photos) / MAX_FOOTPRINTS))
    fps = tuple(tuple(footprint_ring(p, compiled.payload(p.payloads[0]))) for p in photos[::fp_stride] if p.payloads)
    return _MapContent(tuple(areas), tuple((v.x, v.y) for v in sim.vertices), photos, fps, fp_stride)


def _footprint_shapes(fps: Sequence[Sequence[XY]], f: _Frame) -> list[Shape]:
    outline = COLOURS["footprint_line"] if len(fps) <= 300 else None   # hundreds of outlines are a smear
    return [Shape("polygon", f.ring(r), fill=COLOURS["footprint_fill"], fill_opacity=0.10, stroke=outline,
                  stroke_width=0.5, layer="footprints") for r in fps]


def _area_shapes(areas: Sequence[Sequence[Sequence[XY]]], f: _Frame) -> list[Shape]:
    """Each area polygon, its holes drawn again in red on top."""
    shapes = []
    for rings in areas:
        shapes.append(Shape("polygon", f.ring(rings[0]), tuple(f.ring(h) for h in rings[1:]),
                            fill=COLOURS["area_fill"], fill_opacity=0.22, stroke=COLOURS["area_line"], stroke_width=2,
                            layer="area"))
        shapes.extend(Shape("polygon", f.ring(h), fill=COLOURS["gap_fill"], fill_opacity=0.25,
                            stroke=COLOURS["gap_line"], stroke_width=2, layer="gaps") for h in rings[1:])
    return shapes


def _path_shapes(path: Sequence[XY], f: _Frame) -> list[Shape]:
    if len(path) <= 1:
        return []
    return [Shape("polyline", f.ring(path), stroke=COLOURS["path"], stroke_width=2, layer="path"),
            *_arrows(list(f.ring(path)))]


# a mission flown in sorties: each sortie's path in its own colour (cycled), over the whole path's blue
SORTIE_COLOURS = ("#e63030", "#ff9f1e", "#00b000", "#a01eb0", "#00a0a0", "#c06000")
SORTIE_COLOUR_NAMES = ("red", "orange", "green", "purple", "teal", "brown")


def _sortie_shapes(rep: MissionReport, proj: Any, f: _Frame) -> list[Shape]:
    table = rep.sorties
    if table is None:
        return []
    out = []
    for k, path in enumerate(table.paths):
        x, y = proj.to_xy([p[0] for p in path], [p[1] for p in path])
        out.append(Shape("polyline", f.ring(tuple(zip(x.tolist(), y.tolist()))),
                         stroke=SORTIE_COLOURS[k % len(SORTIE_COLOURS)], stroke_width=2, layer="sorties"))
    return out


def _photo_shapes(compiled: Compiled, photos: Sequence[Any], f: _Frame) -> list[Shape]:
    """Photo dots sized to the photo spacing on screen, so that a dense line of photos does not hide the path."""
    dot_stride = max(1, math.ceil(len(photos) / MAX_PHOTO_DOTS))
    gaps = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(photos, photos[1:]) if a.span == b.span]
    gap_px = float(np.median(gaps)) * f.scale if gaps else 10.0
    if gap_px * dot_stride < 2.5:
        dot_stride = max(dot_stride, math.ceil(2.5 / max(gap_px, 1e-6)))
    r_dot = min(2.2, max(0.6, 0.3 * gap_px * dot_stride))
    return [Shape("circle", (f.px(p.x, p.y),), fill=_photo_colour(compiled, p.payloads), radius=r_dot,
                  layer="photos") for p in photos[::dot_stride]]


def _waypoint_shapes(compiled: Compiled, sim: Any, f: _Frame) -> list[Shape]:
    """Numbered NAV waypoints (mission seq), when few enough to read; a label that would overlap one already
    drawn is left out."""
    nav = []
    seen: set[int] = set()
    for v in sim.vertices:
        if v.item >= 0 and v.item not in seen:
            seen.add(v.item)
            nav.append(v)
    if len(nav) > MAX_WAYPOINT_LABELS:
        return []
    seq_base = 1 if compiled.firmware == "ardupilot" else 0
    shapes = []
    placed: list[XY] = []
    for v in nav:
        q = f.px(v.x, v.y)
        shapes.append(Shape("circle", (q,), fill="#ffffff", stroke=COLOURS["waypoint"], stroke_width=1.5,
                            radius=4, layer="waypoints"))
        if all(math.hypot(q[0] - a, q[1] - b) > 14 for a, b in placed):
            shapes.append(Shape("text", ((q[0] + 6, q[1] - 6),), text=str(v.item + seq_base), size=12,
                                fill=COLOURS["waypoint"], bold=True, layer="waypoints"))
            placed.append(q)
    return shapes


def _home_shapes(compiled: Compiled, proj: Any, f: _Frame) -> list[Shape]:
    h = f.px(*proj.point_to_xy(compiled.home[0], compiled.home[1]))
    return [Shape("polygon", ((h[0], h[1] - 9), (h[0] + 8, h[1] + 6), (h[0] - 8, h[1] + 6)),
                  fill=COLOURS["home"], stroke="#ffffff", stroke_width=1.5, layer="home"),
            Shape("text", ((h[0] + 10, h[1] + 14),), text="H", size=14, fill=COLOURS["home"], bold=True,
                  layer="home")]


def _scale_bar_shapes(scale: float) -> list[Shape]:
    """A scale bar of a round length, about a quarter of the map wide, bottom left."""
    bar_m = _nice_length((MAP_W * 0.25) / scale)
    bar_px = bar_m * scale
    bx, by = PAD, MAP_H - 22
    return [Shape("polyline", ((bx, by - 6), (bx, by), (bx + bar_px, by), (bx + bar_px, by - 6)),
                  stroke=COLOURS["text"], stroke_width=2.5, layer="scale"),
            Shape("text", ((bx + bar_px / 2, by - 9),), text=_fmt_len(bar_m), size=13, anchor="middle",
                  fill=COLOURS["text"], layer="scale")]


def _north_arrow_shapes() -> list[Shape]:
    nx, ny = PAD, PAD + 10
    return [Shape("polygon", ((nx, ny - 22), (nx + 9, ny + 6), (nx, ny), (nx - 9, ny + 6)),
                  fill=COLOURS["text"], layer="north"),
            Shape("text", ((nx, ny + 22),), text="N", size=14, anchor="middle", bold=True,
                  fill=COLOURS["text"], layer="north")]

def _photo_colour(compiled: Compiled, payloads: Sequence[str]) -> str:
    """Photos are coloured by the first payload that takes them (plan order), so two cameras can be told apart."""
    names = [p.name for p in compiled.payloads]
    k = min((names.index(n) for n in payloads if n in names), default=0)
    return (COLOURS["photo"], COLOURS["photo2"], COLOURS["photo3"])[min(k, 2)]


def _arrows(path_px: Sequence[tuple[float, float]]) -> list[Shape]:
    """Small arrowheads on the path every ~90 px of drawn length, pointing the way it is flown."""
    out = []
    carry = 45.0
    for (ax, ay), (bx, by) in zip(path_px, path_px[1:]):
        L = math.hypot(bx - ax, by - ay)
        if L < 1e-6:
            continue
        ux, uy = (bx - ax) / L, (by - ay) / L
        s = carry
        while s < L:
            cx, cy = ax + ux * s, ay + uy * s
            tip = (cx + ux * 6, cy + uy * 6)
            left = (cx - ux * 5 - uy * 4.5, cy - uy * 5 + ux * 4.5)
            right = (cx - ux * 5 + uy * 4.5, cy - uy * 5 - ux * 4.5)
            out.append(Shape("polygon", (tip, left, right), fill=COLOURS["path"], layer="arrows"))
            s += 90.0
        carry = s - L
    return out


# Pillow's built-in font has no en dash or multiplication sign: the legend sticks to ASCII.
NONE = "n/a"


def _pct(v: float | None) -> str:
    return NONE if v is None else f"{100 * v:.1f} %"


def _legend(compiled: Compiled, rep: MissionReport, fp_stride: int) -> tuple[list[tuple[str, str]], list[Shape]]:
    """The legend panel right of the map: title, colour keys, the report's key figures, warning codes. Returns the
    figures too (the HTML shows them as a table)."""
    rows = _legend_rows(compiled, rep)
    x0 = MAP_W + 18
    shapes = [Shape("polygon", ((MAP_W, 0), (MAP_W + PANEL_W, 0), (MAP_W + PANEL_W, MAP_H), (MAP_W, MAP_H)),
                    fill=COLOURS["panel"], stroke="#cccccc", layer="legend"),
              Shape("text", ((x0, 34),), text=compiled.name, size=19, bold=True, fill=COLOURS["text"], layer="legend")]
    y = 62
    for kind, colour, label in _legend_keys(compiled, fp_stride):
        shapes.append(_key_swatch(kind, colour, x0, y))
        shapes.append(Shape("text", ((x0 + 32, y),), text=label, size=13, fill=COLOURS["text"], layer="legend"))
        y += 21
    y += 12
    # value column after the longest key (the built-in font is ~7 px per character at 13 px)
    col = max(128, 7 * max(len(k) for k, _ in rows) + 14)
    for k, v in rows:
        shapes.append(Shape("text", ((x0, y),), text=k, size=13, fill=COLOURS["muted"], layer="legend"))
        shapes.append(Shape("text", ((x0 + col, y),), text=v, size=13, fill=COLOURS["text"], bold=True, layer="legend"))
        y += 20
    shapes.extend(_warning_code_shapes(rep, x0, y))
    return rows, shapes


def _legend_rows(compiled: Compiled, rep: MissionReport) -> list[tuple[str, str]]:
    """The report's key figures, as (key, value) text."""
    rows: list[tuple[str, str]] = [
        ("firmware", f"{rep.firmware} {compiled.frame}"),
        ("mission items", f"{rep.mission_items} (limit {rep.item_limit}, {rep.parts} sortie"
                          f"{'s' if rep.parts != 1 else ''})"),
        ("path", f"{rep.path_length_m / 1000:.2f} km"),
        ("flight time", f"{_fmt_time(rep.flight_time_s)} (QGC: {_fmt_time(rep.flight_time_qgc_s or 0)})"),
        ("area", f"{rep.area_m2 / 10000:.2f} ha" if rep.area_m2 else NONE),
    ]
    for name, n in rep.photos.items():
        rows.append((f"photos {name}", str(n)))
        g = rep.gsd_cm.get(name)
        if g:
            rows.append((f"GSD {name}", f"{g.min_cm:.2f} cm/px" if abs(g.max_cm - g.min_cm) < 0.005
                         else f"{g.min_cm:.2f} to {g.max_cm:.2f} cm/px"))
    for name, c in rep.coverage.items():
        ov = rep.overlap[name]
        rows.append((f"coverage {name}", _pct(c)))
        rows.append((f"overlap {name}", f"front {_pct(ov.front_min)}, side {_pct(ov.side_min)} (min)"))
    if rep.sorties is not None:
        for k, r in enumerate(rep.sorties.rows):
            lines = "" if r["first_line"] is None else f", lines {r['first_line']}..{r['last_line']}"
            rows.append((f"sortie {k + 1} ({SORTIE_COLOUR_NAMES[k % len(SORTIE_COLOURS)]})",
                         f"{_fmt_time(r['flight_time_s'])}, {r['photos']} photos{lines}"))
    rows.append(("warnings / errors", f"{len(rep.warnings)} / {len(rep.errors)}"))
    return rows


def _legend_keys(compiled: Compiled, fp_stride: int) -> list[tuple[str, str, str]]:
    """(kind of swatch, colour, label) of each thing the map draws."""
    return [("area", COLOURS["area_fill"], "area to cover"), ("gap", COLOURS["gap_fill"], "hole / exclusion"),
            ("fp", COLOURS["footprint_fill"], "photo footprint" + (f" (every {fp_stride}th)" if fp_stride > 1 else "")),
            ("path", COLOURS["path"], "flight path, arrows = direction"),
            *[("photo", _photo_colour(compiled, (p.name,)),
               "photo position" + (f" ({p.name})" if len(compiled.payloads) > 1 else ""))
              for p in compiled.payloads[:3]],
            ("wp", COLOURS["waypoint"], "waypoint (mission seq)"), ("home", COLOURS["home"], "home (H)")]


def _key_swatch(kind: str, colour: str, x0: float, y: float) -> Shape:
    """A key's sample: a line for the path, a dot for photos and waypoints, a patch for areas."""
    if kind == "path":
        return Shape("polyline", ((x0, y - 4), (x0 + 22, y - 4)), stroke=colour, stroke_width=3, layer="legend")
    if kind in ("photo", "wp"):
        return Shape("circle", ((x0 + 11, y - 4),), fill=colour if kind == "photo" else "#ffffff",
                     stroke=colour, stroke_width=1.5, radius=4, layer="legend")
    return Shape("polygon", ((x0, y - 11), (x0 + 22, y - 11), (x0 + 22, y + 3), (x0, y + 3)),
                 fill=colour, fill_opacity=0.45, stroke=colour, layer="legend")


def _warning_code_shapes(rep: MissionReport, x0: float, y: float) -> list[Shape]:
    """The warnings' codes with their counts, below the figures, as many as fit the panel."""
    codes: dict[str, int] = {}
    for w in rep.warnings:
        codes[w.code] = codes.get(w.code, 0) + 1
    if not codes:
        return []
    y += 10
    shapes = [Shape("text", ((x0, y),), text="warnings", size=13, bold=True, fill="#a05a00", layer="legend")]
    for c, n in codes.items():
        y += 18
        if y > MAP_H - 12:
            break
        shapes.append(Shape("text", ((x0 + 8, y),), text=f"{c}" + (f" (x{n})" if n > 1 else ""), size=12,
                            fill="#a05a00", layer="legend"))
    return shapes

# ------------------------------------------------------------------------------------------------ SVG

def _pts(points: Sequence[tuple[float, float]]) -> str:
    return " ".join(f"{x:.1f},{y:.1f}" for x, y in points)


def render_svg(pic: Picture) -> str:
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{pic.width}" height="{pic.height}" '
           f'viewBox="0 0 {pic.width} {pic.height}" font-family="DejaVu Sans, Arial, sans-serif">',
           f"<title>{escape(pic.title)}</title>",
           f'<rect id="background" x="0" y="0" width="{pic.width}" height="{pic.height}" fill="{COLOURS["background"]}"/>']
    layer = None
    for s in pic.shapes:
        if s.layer != layer:
            if layer is not None:
                out.append("</g>")
            out.append(f'<g id="{s.layer}">')
            layer = s.layer
        style = []
        style.append(f'fill="{s.fill}"' if s.fill else 'fill="none"')
        if s.fill and s.fill_opacity < 1:
            style.append(f'fill-opacity="{s.fill_opacity:g}"')
        if s.stroke:
            style.append(f'stroke="{s.stroke}" stroke-width="{s.stroke_width:g}"')
        st = " ".join(style)
        if s.kind == "polygon":
            if s.holes:
                d = " ".join("M" + " L".join(f"{x:.1f},{y:.1f}" for x, y in ring) + " Z" for ring in (s.points, *s.holes))
                out.append(f'<path class="{s.layer}" d="{d}" fill-rule="evenodd" {st} stroke-linejoin="round"/>')
            else:
                out.append(f'<polygon class="{s.layer}" points="{_pts(s.points)}" {st} stroke-linejoin="round"/>')
        elif s.kind == "polyline":
            out.append(f'<polyline class="{s.layer}" points="{_pts(s.points)}" fill="none" stroke="{s.stroke}" '
                       f'stroke-width="{s.stroke_width:g}" stroke-linejoin="round" stroke-linecap="round"/>')
        elif s.kind == "circle":
            (x, y), = s.points
            out.append(f'<circle class="{s.layer}" cx="{x:.1f}" cy="{y:.1f}" r="{s.radius:g}" {st}/>')
        elif s.kind == "text":
            (x, y), = s.points
            weight = ' font-weight="bold"' if s.bold else ""
            out.append(f'<text x="{x:.1f}" y="{y:.1f}" font-size="{s.size:g}" text-anchor="{s.anchor}" '
                       f'fill="{s.fill or COLOURS["text"]}"{weight}>{escape(s.text)}</text>')
    if layer is not None:
        out.append("</g>")
    out.append("</svg>\n")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------ PNG

def _rgb(hex_colour: str) -> tuple[int, int, int]:
    h = hex_colour.lstrip("#")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)


def _by_layer(shapes: Sequence[Shape]) -> list[list[Shape]]:
    """The shapes in runs of one layer, in drawing order."""
    runs: list[list[Shape]] = []
    for s in shapes:
        if not runs or runs[-1][0].layer != s.layer:
            runs.append([])
        runs[-1].append(s)
    return runs


def _png_polygon(draw: Any, s: Shape, k: int, font: Callable[[float, bool], Any]) -> None:
    fill = _rgb(s.fill) + (int(255 * s.fill_opacity),) if s.fill else None
    draw.polygon(_scaled(s.points, k), fill=fill)
    for hole in s.holes:
        draw.polygon(_scaled(hole, k), fill=(0, 0, 0, 0))
    if s.stroke:
        for ring in (s.points, *s.holes):
            pts = _scaled(ring, k)
            draw.line(pts + [pts[0]], fill=_rgb(s.stroke) + (255,), width=max(1, round(s.stroke_width * k)),
                      joint="curve")


def _png_polyline(draw: Any, s: Shape, k: int, font: Callable[[float, bool], Any]) -> None:
    draw.line(_scaled(s.points, k), fill=_rgb(s.stroke) + (255,), width=max(1, round(s.stroke_width * k)),
              joint="curve")


def _png_circle(draw: Any, s: Shape, k: int, font: Callable[[float, bool], Any]) -> None:
    (x, y), = s.points
    r = s.radius * k
    draw.ellipse((x * k - r, y * k - r, x * k + r, y * k + r),
                 fill=_rgb(s.fill) + (255,) if s.fill else None,
                 outline=_rgb(s.stroke) + (255,) if s.stroke else None,
                 width=max(1, round(s.stroke_width * k)) if s.stroke else 0)


def _png_text(draw: Any, s: Shape, k: int, font: Callable[[float, bool], Any]) -> None:
    (x, y), = s.points
    anchor = {"start": "ls", "middle": "ms", "end": "rs"}[s.anchor]
    colour = _rgb(s.fill or COLOURS["text"]) + (255,)
    # Pillow's built-in font has no bold face: a bold text is drawn with a one-pixel stroke of its colour
    draw.text((x * k, y * k), s.text, font=font(s.size, s.bold), fill=colour, anchor=anchor,
              stroke_width=1 if s.bold else 0, stroke_fill=colour)


def _scaled(points: Sequence[tuple[float, float]], k: int) -> list[tuple[float, float]]:
    return [(x * k, y * k) for x, y in points]


_PNG_DRAW: dict[str, Callable[[Any, Shape, int, Callable[[float, bool], Any]], None]] = {
    "polygon": _png_polygon, "polyline": _png_polyline, "circle": _png_circle, "text": _png_text}


def render_png(pic: Picture, path: Path, supersample: int = 2) -> None:
    """Draw `pic` at `supersample` times its size, each layer on its own overlay (so its opacities blend with
    what is below it, not with itself), then reduce it: smooth lines without anti-aliasing in Pillow's draw."""
    from PIL import Image, ImageDraw, ImageFont   # Pillow loads only for a .png preview

    k = supersample
    base = Image.new("RGBA", (pic.width * k, pic.height * k), _rgb(COLOURS["background"]) + (255,))
    fonts: dict[tuple[float, bool], Any] = {}

    def font(size: float, bold: bool) -> Any:
        if (size, bold) not in fonts:
            fonts[size, bold] = ImageFont.load_default(size=size * k)
        return fonts[size, bold]

    for run in _by_layer(pic.shapes):
        overlay = Image.new("RGBA", base.size, (0, 0, 0, 0))
        draw = ImageDraw.Draw(overlay)
        for s in run:
            if s.kind in _PNG_DRAW:
                _PNG_DRAW[s.kind](draw, s, k, font)
        base = Image.alpha_composite(base, overlay)
    img = base.convert("RGB").resize((pic.width, pic.height), Image.Resampling.LANCZOS)
    img.save(path, format="PNG", optimize=True)

# ------------------------------------------------------------------------------------------------ HTML

def render_html(pic: Picture, rep: MissionReport) -> str:
    return render("preview.html.j2", title=pic.title, svg=Markup(render_svg(pic)), rows=pic.rows,
                  warnings=pic.warnings, errors=[e.message for e in rep.errors], areas=rep.areas)


def write_preview(compiled: Compiled, out: str | Path) -> Path:
    """Render the preview to `out` (.svg, .png or .html, by suffix), written atomically."""
    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".svg", ".png", ".html", ".htm"):
        raise PlanError(f"cannot draw a preview as '{suffix or out.name}'", where=str(out),
                        hint="name the output .svg, .png or .html")
    sim = simulate(compiled)
    rep = report(compiled, sim)
    pic = build_picture(compiled, sim, rep)
    try:
        if not out.resolve().parent.is_dir():
            raise PlanError("the output directory does not exist", where=str(out), hint="create it first")
    except OSError as err:  # is_dir() answers False only for "no such file"; a name too long raises
        raise PlanError(f"cannot write the preview: {err.strerror}", where=str(out),
                        hint="give -o a path you may access, its file name at most 240 bytes") from None
    with replacing(out, "the preview") as tmp:
        if suffix == ".png":
            render_png(pic, tmp)
        else:
            text = render_svg(pic) if suffix == ".svg" else render_html(pic, rep)
            tmp.write_text(text, encoding="utf-8")
    return out
