"""The preview's display list (Shape, Picture: polygons, lines, dots and text in pixel coordinates, by layer) and
its two renderers: SVG written directly (no dependency) and PNG with Pillow (supersampled, then reduced, for
smooth lines). missions.formats.preview draws a mission into it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence
from xml.sax.saxutils import escape


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
    stroke_opacity: float = 1.0
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
    detail: "Detail | None" = None                               # the magnified stretch of a thin area


@dataclass(frozen=True)
class Detail:
    """A magnified window on a thin area (a corridor), so that its passes can be told apart: `window_m` is
    (x0, y0, x1, y1) in the simulation's plane, drawn at `scale` px/m into `box_px` (x0, y0, x1, y1)."""

    window_m: tuple[float, float, float, float]
    scale: float
    box_px: tuple[float, float, float, float]


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
            if s.stroke_opacity < 1:
                style.append(f'stroke-opacity="{s.stroke_opacity:g}"')
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
            draw.line(pts + [pts[0]], fill=_rgb(s.stroke) + (round(255 * s.stroke_opacity),),
                      width=max(1, round(s.stroke_width * k)), joint="curve")


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
