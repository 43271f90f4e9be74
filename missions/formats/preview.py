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
from typing import TYPE_CHECKING, Any, Sequence
from xml.sax.saxutils import escape

import numpy as np

from missions.compiled import Compiled
from missions.errors import PlanError

if TYPE_CHECKING:
    from missions.measure.report import MissionReport

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


def build_picture(compiled: Compiled, sim: Any = None, rep: MissionReport | None = None) -> Picture:
    from missions.measure.flight import simulate
    from missions.measure.report import footprint_ring, report

    sim = sim or simulate(compiled)
    rep = rep or report(compiled, sim)
    proj = sim.projection

    # geometry in the simulation's metres
    areas = []
    for a in compiled.areas:
        for rings in a.area.latlon_rings():
            xy_rings = []
            for ring in rings:
                lat = [p[0] for p in ring]
                lon = [p[1] for p in ring]
                x, y = proj.to_xy(lat, lon)
                xy_rings.append(list(zip(x.tolist(), y.tolist())))
            areas.append(xy_rings)
    path = [(v.x, v.y) for v in sim.vertices]
    photos = list(sim.photos)
    fp_stride = max(1, math.ceil(len(photos) / MAX_FOOTPRINTS))
    fps = []
    for p in photos[::fp_stride]:
        first = p.payloads[0] if p.payloads else None
        if first is not None:
            fps.append(footprint_ring(p, compiled.payload(first)))

    pts = [pt for rings in areas for ring in rings for pt in ring] + path + [pt for r in fps for pt in r]
    xs = np.array([p[0] for p in pts] or [0.0])
    ys = np.array([p[1] for p in pts] or [0.0])
    x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
    span = max(x1 - x0, y1 - y0, 10.0)
    # the map keeps a free band at the bottom for the scale bar and at the left for the north arrow
    left, right, top, bottom = PAD + 30, MAP_W - PAD, PAD, MAP_H - PAD - 30
    scale = min((right - left) / max(x1 - x0, span * 0.05), (bottom - top) / max(y1 - y0, span * 0.05))
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    mx, my = (left + right) / 2, (top + bottom) / 2

    def px(x: float, y: float) -> tuple[float, float]:
        return (round(mx + (x - cx) * scale, 2), round(my - (y - cy) * scale, 2))

    shapes: list[Shape] = []
    outline = COLOURS["footprint_line"] if len(fps) <= 300 else None   # hundreds of outlines are a smear
    for r in fps:
        shapes.append(Shape("polygon", tuple(px(*q) for q in r), fill=COLOURS["footprint_fill"], fill_opacity=0.10,
                            stroke=outline, stroke_width=0.5, layer="footprints"))
    for rings in areas:
        shapes.append(Shape("polygon", tuple(px(*q) for q in rings[0]), tuple(tuple(px(*q) for q in h) for h in rings[1:]),
                            fill=COLOURS["area_fill"], fill_opacity=0.22, stroke=COLOURS["area_line"], stroke_width=2,
                            layer="area"))
        for h in rings[1:]:
            shapes.append(Shape("polygon", tuple(px(*q) for q in h), fill=COLOURS["gap_fill"], fill_opacity=0.25,
                                stroke=COLOURS["gap_line"], stroke_width=2, layer="gaps"))
    if len(path) > 1:
        shapes.append(Shape("polyline", tuple(px(*q) for q in path), stroke=COLOURS["path"], stroke_width=2,
                            layer="path"))
        shapes.extend(_arrows([px(*q) for q in path]))
    # dots sized to the photo spacing on screen, so that a dense line of photos does not hide the path
    dot_stride = max(1, math.ceil(len(photos) / MAX_PHOTO_DOTS))
    gaps = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(photos, photos[1:]) if a.span == b.span]
    gap_px = float(np.median(gaps)) * scale if gaps else 10.0
    if gap_px * dot_stride < 2.5:
        dot_stride = max(dot_stride, math.ceil(2.5 / max(gap_px, 1e-6)))
    r_dot = min(2.2, max(0.6, 0.3 * gap_px * dot_stride))
    for p in photos[::dot_stride]:
        shapes.append(Shape("circle", (px(p.x, p.y),), fill=_photo_colour(compiled, p.payloads), radius=r_dot,
                            layer="photos"))
    # numbered NAV waypoints, when few enough to read
    nav = []
    seen: set[int] = set()
    seq_base = 1 if compiled.firmware == "ardupilot" else 0
    for v in sim.vertices:
        if v.item >= 0 and v.item not in seen:
            seen.add(v.item)
            nav.append(v)
    if len(nav) <= MAX_WAYPOINT_LABELS:
        placed: list[tuple[float, float]] = []
        for v in nav:
            q = px(v.x, v.y)
            shapes.append(Shape("circle", (q,), fill="#ffffff", stroke=COLOURS["waypoint"], stroke_width=1.5,
                                radius=4, layer="waypoints"))
            if all(math.hypot(q[0] - a, q[1] - b) > 14 for a, b in placed):
                shapes.append(Shape("text", ((q[0] + 6, q[1] - 6),), text=str(v.item + seq_base), size=12,
                                    fill=COLOURS["waypoint"], bold=True, layer="waypoints"))
                placed.append(q)
    hx, hy = proj.point_to_xy(compiled.home[0], compiled.home[1])
    h = px(hx, hy)
    shapes.append(Shape("polygon", ((h[0], h[1] - 9), (h[0] + 8, h[1] + 6), (h[0] - 8, h[1] + 6)),
                        fill=COLOURS["home"], stroke="#ffffff", stroke_width=1.5, layer="home"))
    shapes.append(Shape("text", ((h[0] + 10, h[1] + 14),), text="H", size=14, fill=COLOURS["home"], bold=True,
                        layer="home"))

    # scale bar (bottom left) and north arrow (top left)
    bar_m = _nice_length((MAP_W * 0.25) / scale)
    bar_px = bar_m * scale
    bx, by = PAD, MAP_H - 22
    shapes.append(Shape("polyline", ((bx, by - 6), (bx, by), (bx + bar_px, by), (bx + bar_px, by - 6)),
                        stroke=COLOURS["text"], stroke_width=2.5, layer="scale"))
    shapes.append(Shape("text", ((bx + bar_px / 2, by - 9),), text=_fmt_len(bar_m), size=13, anchor="middle",
                        fill=COLOURS["text"], layer="scale"))
    nx, ny = PAD, PAD + 10
    shapes.append(Shape("polygon", ((nx, ny - 22), (nx + 9, ny + 6), (nx, ny), (nx - 9, ny + 6)),
                        fill=COLOURS["text"], layer="north"))
    shapes.append(Shape("text", ((nx, ny + 22),), text="N", size=14, anchor="middle", bold=True,
                        fill=COLOURS["text"], layer="north"))

    rows, legend = _legend(compiled, rep, len(fps), len(photos), fp_stride)
    shapes.extend(legend)
    warn = tuple(w.message for w in rep.warnings)
    return Picture(MAP_W + PANEL_W, MAP_H, tuple(shapes), compiled.name, tuple(rows), warn)


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


def _legend(compiled: Compiled, rep: MissionReport, n_fp: int, n_ph: int, fp_stride: int) -> tuple[list[tuple[str, str]], list[Shape]]:
    rows: list[tuple[str, str]] = [
        ("firmware", f"{rep.firmware} {compiled.frame}"),
        ("mission items", f"{rep.mission_items} (limit {rep.item_limit}, {rep.parts} part"
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
    rows.append(("warnings / errors", f"{len(rep.warnings)} / {len(rep.errors)}"))

    x0 = MAP_W + 18
    shapes = [Shape("polygon", ((MAP_W, 0), (MAP_W + PANEL_W, 0), (MAP_W + PANEL_W, MAP_H), (MAP_W, MAP_H)),
                    fill=COLOURS["panel"], stroke="#cccccc", layer="legend"),
              Shape("text", ((x0, 34),), text=compiled.name, size=19, bold=True, fill=COLOURS["text"], layer="legend")]
    y = 62
    keys = [("area", COLOURS["area_fill"], "area to cover"), ("gap", COLOURS["gap_fill"], "hole / exclusion"),
            ("fp", COLOURS["footprint_fill"], "photo footprint" + (f" (every {fp_stride}th)" if fp_stride > 1 else "")),
            ("path", COLOURS["path"], "flight path, arrows = direction"),
            *[("photo", _photo_colour(compiled, (p.name,)),
               "photo position" + (f" ({p.name})" if len(compiled.payloads) > 1 else ""))
              for p in compiled.payloads[:3]],
            ("wp", COLOURS["waypoint"], "waypoint (mission seq)"), ("home", COLOURS["home"], "home (H)")]
    for kind, colour, label in keys:
        if kind == "path":
            shapes.append(Shape("polyline", ((x0, y - 4), (x0 + 22, y - 4)), stroke=colour, stroke_width=3, layer="legend"))
        elif kind in ("photo", "wp"):
            shapes.append(Shape("circle", ((x0 + 11, y - 4),), fill=colour if kind == "photo" else "#ffffff",
                                stroke=colour, stroke_width=1.5, radius=4, layer="legend"))
        else:
            shapes.append(Shape("polygon", ((x0, y - 11), (x0 + 22, y - 11), (x0 + 22, y + 3), (x0, y + 3)),
                                fill=colour, fill_opacity=0.45, stroke=colour, layer="legend"))
        shapes.append(Shape("text", ((x0 + 32, y),), text=label, size=13, fill=COLOURS["text"], layer="legend"))
        y += 21
    y += 12
    # value column after the longest key (the built-in font is ~7 px per character at 13 px)
    col = max(128, 7 * max(len(k) for k, _ in rows) + 14)
    for k, v in rows:
        shapes.append(Shape("text", ((x0, y),), text=k, size=13, fill=COLOURS["muted"], layer="legend"))
        shapes.append(Shape("text", ((x0 + col, y),), text=v, size=13, fill=COLOURS["text"], bold=True, layer="legend"))
        y += 20
    codes: dict[str, int] = {}
    for w in rep.warnings:
        codes[w.code] = codes.get(w.code, 0) + 1
    if codes:
        y += 10
        shapes.append(Shape("text", ((x0, y),), text="warnings", size=13, bold=True, fill="#a05a00", layer="legend"))
        for c, n in codes.items():
            y += 18
            if y > MAP_H - 12:
                break
            shapes.append(Shape("text", ((x0 + 8, y),), text=f"{c}" + (f" (x{n})" if n > 1 else ""), size=12,
                                fill="#a05a00", layer="legend"))
    return rows, shapes


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


def render_png(pic: Picture, path: Path, supersample: int = 2) -> None:
    from PIL import Image, ImageDraw, ImageFont

    k = supersample
    base = Image.new("RGBA", (pic.width * k, pic.height * k), _rgb(COLOURS["background"]) + (255,))
    fonts: dict[tuple[float, bool], Any] = {}

    def font(size: float, bold: bool):
        key = (size, bold)
        if key not in fonts:
            fonts[key] = ImageFont.load_default(size=size * k)
        return fonts[key]

    def sc(points):
        return [(x * k, y * k) for x, y in points]

    layer = None
    overlay = None
    draw = None

    def flush():
        nonlocal base
        if overlay is not None:
            base = Image.alpha_composite(base, overlay)

    for s in pic.shapes:
        if s.layer != layer:
            flush()
            overlay = Image.new("RGBA", base.size, (0, 0, 0, 0))
            draw = ImageDraw.Draw(overlay)
            layer = s.layer
        assert draw is not None
        if s.kind == "polygon":
            fill = _rgb(s.fill) + (int(255 * s.fill_opacity),) if s.fill else None
            draw.polygon(sc(s.points), fill=fill)
            for hole in s.holes:
                draw.polygon(sc(hole), fill=(0, 0, 0, 0))
            if s.stroke:
                for ring in (s.points, *s.holes):
                    pts = sc(ring)
                    draw.line(pts + [pts[0]], fill=_rgb(s.stroke) + (255,), width=max(1, round(s.stroke_width * k)),
                              joint="curve")
        elif s.kind == "polyline":
            draw.line(sc(s.points), fill=_rgb(s.stroke) + (255,), width=max(1, round(s.stroke_width * k)), joint="curve")
        elif s.kind == "circle":
            (x, y), = s.points
            r = s.radius * k
            draw.ellipse((x * k - r, y * k - r, x * k + r, y * k + r),
                         fill=_rgb(s.fill) + (255,) if s.fill else None,
                         outline=_rgb(s.stroke) + (255,) if s.stroke else None,
                         width=max(1, round(s.stroke_width * k)) if s.stroke else 0)
        elif s.kind == "text":
            (x, y), = s.points
            anchor = {"start": "ls", "middle": "ms", "end": "rs"}[s.anchor]
            colour = _rgb(s.fill or COLOURS["text"]) + (255,)
            f = font(s.size, s.bold)
            draw.text((x * k, y * k), s.text, font=f, fill=colour, anchor=anchor,
                      stroke_width=1 if s.bold else 0, stroke_fill=colour)
    flush()
    img = base.convert("RGB").resize((pic.width, pic.height), Image.Resampling.LANCZOS)
    img.save(path, format="PNG", optimize=True)


# ------------------------------------------------------------------------------------------------ HTML

def render_html(pic: Picture, rep: MissionReport) -> str:
    from markupsafe import Markup
    from templates import render

    return render("preview.html.j2", title=pic.title, svg=Markup(render_svg(pic)), rows=pic.rows,
                  warnings=pic.warnings, errors=[e.message for e in rep.errors], areas=rep.areas)


def write_preview(compiled: Compiled, out: str | Path) -> Path:
    """Render the preview to `out` (.svg, .png or .html, by suffix), written atomically."""
    from missions.formats.planfile import replacing
    from missions.measure.flight import simulate
    from missions.measure.report import report

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
