"""A picture of a compiled mission that a person can check at a glance: `wiris mission preview PLAN -o FILE`.

    write_preview(compiled, "plan.png")      # .svg, .png or .html by suffix

Drawn from the simulated flight (missions.measure.flight.simulate), not from the planner's intent: area (holes and
exclusions in red), photo footprints (outlined in orange over the area), the flown path (blue, arrows show
direction), photo points, numbered waypoints (when there are few enough to read), home, a scale bar, a north
arrow, a frame with latitude/longitude ticks, a legend with the report's key figures, and for an area drawn
thinner than THIN_AREA_PX (a corridor) a magnified detail in which its passes can be told apart. North is up: the simulation's azimuthal-equidistant plane is centred
on the mission, so meridians are vertical to well under a degree over any single survey.

One display list (polygons, lines, dots, text in pixel coordinates; missions.formats.picture) feeds two
renderers there: SVG written directly (no dependency) and PNG with Pillow (2× supersampled, then reduced, for
smooth lines). The HTML is the interactive map of missions.formats.webmap (pan, zoom, clickable items;
self-contained, offline).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from missions.compiled import Compiled
from missions.errors import PlanError
from missions.formats.planfile import replacing
from missions.measure.flight import simulate
from missions.measure.report import MissionReport, footprint_ring, report
from missions.formats.picture import COLOURS, Detail, Picture, Shape, render_png, render_svg


MAP_W, MAP_H = 1000, 800          # map area in pixels
PANEL_W = 430                     # legend panel to the right
PAD = 40
# Beyond these counts the picture is a solid smear: draw a regular subset and say so in the legend.
MAX_FOOTPRINTS = 400              # outlined one by one: more is a mesh in which no footprint can be told
MAX_PHOTO_DOTS = 20000
MAX_WAYPOINT_LABELS = 60
# The map's frame, with latitude/longitude ticks on it: the left band keeps the north arrow and the latitude labels,
# the bottom band the longitude labels and the scale bar.
FRAME_BOX = (PAD + 24, 12, MAP_W - 12, MAP_H - PAD - 14)
# An area narrower than this on the map (a corridor) gets a magnified detail in the legend panel's lower part.
THIN_AREA_PX = 40
DETAIL_BOX = (MAP_W + 18, MAP_H - 290, MAP_W + PANEL_W - 18, MAP_H - 40)


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

    def xy(self, px: float, py: float) -> XY:
        """The plane's metres under a pixel."""
        return self.cx + (px - self.mx) / self.scale, self.cy - (py - self.my) / self.scale


def build_picture(compiled: Compiled, sim: Any = None, rep: MissionReport | None = None) -> Picture:
    """The preview's display list: the map from the simulated flight, the legend from the measured report."""
    sim = sim or simulate(compiled)
    rep = rep or report(compiled, sim)
    content = _map_content(compiled, sim)
    frame = _Frame.fitting(content.points())
    shapes = [*_terrain_shapes(compiled, sim, frame), *_map_shapes(compiled, content, frame),
              *_sortie_shapes(rep, sim.projection, frame), *_waypoint_shapes(compiled, sim, frame),
              *_home_shapes(compiled, sim.projection, frame), *_graticule_shapes(sim.projection, frame),
              *_scale_bar_shapes(frame.scale), *_north_arrow_shapes()]
    detail = _detail(content, frame)
    rows, legend = _legend(compiled, rep, content.fp_stride, bottom=detail.box_px[1] - 10 if detail else MAP_H - 12)
    shapes.extend(legend)
    if detail:
        shapes.extend(_detail_shapes(compiled, content, frame, detail))
    warn = tuple(w.message for w in rep.warnings)
    return Picture(MAP_W + PANEL_W, MAP_H, tuple(shapes), compiled.name, tuple(rows), warn, detail)


def _map_shapes(compiled: Compiled, content: _MapContent, f: _Frame) -> list[Shape]:
    """Area fill, then the footprints over it (so they show against it), holes, the area's outline, path, photos."""
    return [*_area_shapes(content.areas, f), *_footprint_shapes(content.footprints, f),
            *_gap_shapes(content.areas, f), *_area_outline_shapes(content.areas, f),
            *_path_shapes(content.path, f), *_photo_shapes(compiled, content.photos, f)]


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
    if getattr(compiled, "terrain", None) is not None:      # footprints cut by the DEM, as the report measures
        from missions.terrain.reflight import footprint_rings
        owners = [(k, p.payloads[0]) for k, p in enumerate(photos) if k % fp_stride == 0 and p.payloads]
        fps = tuple(tuple(map(tuple, r.tolist())) for r in footprint_rings(compiled, sim, owners))
    else:
        fps = tuple(tuple(footprint_ring(p, compiled.payload(p.payloads[0]))) for p in photos[::fp_stride]
                    if p.payloads)
    return _MapContent(tuple(areas), tuple((v.x, v.y) for v in sim.vertices), photos, fps, fp_stride)


def _terrain_shapes(compiled: Compiled, sim: Any, f: _Frame) -> list[Shape]:
    """The DEM's contour lines under everything else (missions.terrain.shade), every fifth one darker, and a note
    of the interval; nothing without a DEM."""
    if getattr(compiled, "terrain", None) is None:
        return []
    from missions.terrain.shade import contours

    box = (f.cx - (f.mx - PAD) / f.scale, f.cy - (MAP_H - f.my - PAD) / f.scale,
           f.cx + (MAP_W - PAD - f.mx) / f.scale, f.cy + (f.my - PAD) / f.scale)
    c = contours(compiled.terrain.dem, sim.projection, box)
    if not c.segments:
        return []
    shapes = [Shape("polyline", (f.px(*a), f.px(*b)), stroke="#8c6d46" if round(level / c.interval_m) % 5 == 0
                    else "#c9b79c", stroke_width=1.0, layer="terrain") for level, (a, b) in c.segments]
    shapes.append(Shape("text", ((PAD + 34, MAP_H - 14),), text=f"contours every {c.interval_m:g} m (DEM)",
                        size=11, fill=COLOURS["muted"], layer="terrain"))
    return shapes


def _footprint_shapes(fps: Sequence[Sequence[XY]], f: _Frame) -> list[Shape]:
    """Each footprint outlined over the area's fill, with a faint fill of its own: overlaps read as darker."""
    return [Shape("polygon", f.ring(r), fill=COLOURS["footprint_fill"], fill_opacity=0.06,
                  stroke=COLOURS["footprint_line"], stroke_width=0.8, stroke_opacity=0.75, layer="footprints")
            for r in fps]


def _area_shapes(areas: Sequence[Sequence[Sequence[XY]]], f: _Frame) -> list[Shape]:
    """Each area polygon's fill (its holes left out)."""
    return [Shape("polygon", f.ring(rings[0]), tuple(f.ring(h) for h in rings[1:]), fill=COLOURS["area_fill"],
                  fill_opacity=0.22, layer="area") for rings in areas]


def _gap_shapes(areas: Sequence[Sequence[Sequence[XY]]], f: _Frame) -> list[Shape]:
    """The holes and exclusions, in red over the footprints that reach into them."""
    return [Shape("polygon", f.ring(h), fill=COLOURS["gap_fill"], fill_opacity=0.25, stroke=COLOURS["gap_line"],
                  stroke_width=2, layer="gaps") for rings in areas for h in rings[1:]]


def _area_outline_shapes(areas: Sequence[Sequence[Sequence[XY]]], f: _Frame) -> list[Shape]:
    return [Shape("polygon", f.ring(rings[0]), stroke=COLOURS["area_line"], stroke_width=2, layer="area_outline")
            for rings in areas]


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
    bx, by = PAD, MAP_H - 12
    return [Shape("polyline", ((bx, by - 6), (bx, by), (bx + bar_px, by), (bx + bar_px, by - 6)),
                  stroke=COLOURS["text"], stroke_width=2.5, layer="scale"),
            Shape("text", ((bx + bar_px / 2, by - 9),), text=_fmt_len(bar_m), size=13, anchor="middle",
                  fill=COLOURS["text"], layer="scale")]


def _nice_step(span: float, target: int = 5) -> float:
    """A 1-2-5 × 10^k step giving about `target` ticks over `span`."""
    raw = max(span, 1e-9) / target
    k = 10 ** math.floor(math.log10(raw))
    return next(m * k for m in (1, 2, 5, 10) if m * k >= raw)


def _deg_text(value: float, step: float, positive: str, negative: str) -> str:
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    # ASCII only: Pillow's built-in font has no degree sign
    return f"{abs(value):.{decimals}f} {positive if value >= 0 else negative}"


def _graticule_shapes(proj: Any, f: _Frame) -> list[Shape]:
    """The map's frame with latitude ticks on its left and right, longitude ticks on its top and bottom, the
    values written beside the left and bottom ones (degrees, WGS84)."""
    x0, y0, x1, y1 = FRAME_BOX
    shapes = [Shape("polygon", ((x0, y0), (x1, y0), (x1, y1), (x0, y1)), stroke="#9aa3ab", stroke_width=1,
                    layer="graticule")]
    lat_bottom = proj.point_to_latlon(*f.xy((x0 + x1) / 2, y1))[0]
    lon_left = proj.point_to_latlon(*f.xy(x0, (y0 + y1) / 2))[1]
    corners = [proj.point_to_latlon(*f.xy(x, y)) for x in (x0, x1) for y in (y0, y1)]
    lats, lons = [c[0] for c in corners], [c[1] for c in corners]
    lon_step, lat_step = _nice_step(max(lons) - min(lons)), _nice_step(max(lats) - min(lats))
    for k in range(math.ceil(min(lons) / lon_step), math.floor(max(lons) / lon_step) + 1):
        lon = k * lon_step
        x = f.px(*proj.point_to_xy(lat_bottom, lon))[0]
        if x0 + 40 < x < x1 - 40:
            shapes += [Shape("polyline", ((x, y1), (x, y1 - 7)), stroke="#5c6670", stroke_width=1, layer="graticule"),
                       Shape("polyline", ((x, y0), (x, y0 + 7)), stroke="#5c6670", stroke_width=1, layer="graticule"),
                       Shape("text", ((x, y1 + 13),), text=_deg_text(lon, lon_step, "E", "W"), size=10,
                             anchor="middle", fill=COLOURS["muted"], layer="graticule")]
    for k in range(math.ceil(min(lats) / lat_step), math.floor(max(lats) / lat_step) + 1):
        lat = k * lat_step
        y = f.px(*proj.point_to_xy(lat, lon_left))[1]
        if max(y0 + 20, PAD + 50) < y < y1 - 20:            # clear of the north arrow
            shapes += [Shape("polyline", ((x0, y), (x0 + 7, y)), stroke="#5c6670", stroke_width=1, layer="graticule"),
                       Shape("polyline", ((x1, y), (x1 - 7, y)), stroke="#5c6670", stroke_width=1, layer="graticule"),
                       Shape("text", ((x0 - 3, y + 3),), text=_deg_text(lat, lat_step, "N", "S"), size=10,
                             anchor="end", fill=COLOURS["muted"], layer="graticule")]
    return shapes


def _detail(content: _MapContent, f: _Frame) -> Detail | None:
    """A window on the middle of the thinnest area when it is drawn narrower than THIN_AREA_PX, scaled so that
    the area's width fills a bit under half the detail box."""
    from shapely.geometry import Point, Polygon
    from shapely.ops import nearest_points

    thinnest = None
    for rings in content.areas:
        poly = Polygon(rings[0], rings[1:])
        if poly.is_empty or poly.area <= 0:
            continue
        width_m = 2 * poly.area / poly.exterior.length       # a strip's width, from its area and perimeter
        if width_m * f.scale < THIN_AREA_PX and (thinnest is None or width_m < thinnest[0]):
            thinnest = (width_m, poly)
    if thinnest is None or len(content.path) < 2:
        return None
    width_m, poly = thinnest
    bx0, by0, bx1, by1 = DETAIL_BOX
    scale = 0.45 * (by1 - by0) / width_m
    # the middle of a long strip: the point of the area nearest its bounding box's centre (a bent corridor's
    # centroid may lie outside it)
    minx, miny, maxx, maxy = poly.bounds
    centre = Point((minx + maxx) / 2, (miny + maxy) / 2)
    if not poly.contains(centre):
        centre = nearest_points(poly, centre)[0]
    hw, hh = (bx1 - bx0) / 2 / scale, (by1 - by0) / 2 / scale
    return Detail((centre.x - hw, centre.y - hh, centre.x + hw, centre.y + hh), scale, DETAIL_BOX)


def _clipped(shapes: Sequence[Shape], box: tuple[float, float, float, float]) -> list[Shape]:
    """The shapes cut to a pixel box: filled polygons as polygons, outlines and lines as lines, dots and text
    kept when inside."""
    from shapely.geometry import LineString, Point, Polygon, box as make_box

    b = make_box(*box)
    out: list[Shape] = []
    for s in shapes:
        if s.kind == "polygon" and s.fill:
            g = Polygon(s.points, s.holes)
            g = g if g.is_valid else g.buffer(0)
            for part in getattr(g.intersection(b), "geoms", [g.intersection(b)]):
                if part.geom_type == "Polygon" and not part.is_empty:
                    out.append(replace(s, points=tuple(part.exterior.coords),
                                       holes=tuple(tuple(h.coords) for h in part.interiors)))
        elif s.kind in ("polygon", "polyline"):
            pts = list(s.points) + ([s.points[0]] if s.kind == "polygon" else [])
            cut = LineString(pts).intersection(b)
            for part in getattr(cut, "geoms", [cut]):
                if part.geom_type == "LineString" and not part.is_empty:
                    out.append(replace(s, kind="polyline", points=tuple(part.coords)))
        elif b.contains(Point(s.points[0])):
            out.append(s)
    return out


def _detail_shapes(compiled: Compiled, content: _MapContent, main: _Frame, d: Detail) -> list[Shape]:
    """The detail box: the map drawn again at the detail's scale and cut to the box, its own scale bar, and a
    rectangle on the main map showing where it is."""
    bx0, by0, bx1, by1 = d.box_px
    wx0, wy0, wx1, wy1 = d.window_m
    f = _Frame(d.scale, (wx0 + wx1) / 2, (wy0 + wy1) / 2, (bx0 + bx1) / 2, (by0 + by1) / 2)
    margin = max(wx1 - wx0, wy1 - wy0)
    photos = tuple(p for p in content.photos if wx0 - margin <= p.x <= wx1 + margin and wy0 - margin <= p.y <= wy1 + margin)
    fps = tuple(r for r in content.footprints
                if any(wx0 - margin <= x <= wx1 + margin and wy0 - margin <= y <= wy1 + margin for x, y in r))
    inner = _clipped(_map_shapes(compiled, _MapContent(content.areas, content.path, photos, fps, content.fp_stride), f),
                     d.box_px)
    box = ((bx0, by0), (bx1, by0), (bx1, by1), (bx0, by1))
    bar_m = _nice_length((bx1 - bx0) * 0.3 / d.scale)
    bar_px = bar_m * d.scale
    sx, sy = bx0 + 10, by1 - 10
    mark = main.ring(((wx0, wy0), (wx1, wy0), (wx1, wy1), (wx0, wy1)))
    mark_top = min(mark, key=lambda q: q[1])
    return [Shape("polygon", box, fill="#ffffff", layer="detail-background"),
            *[replace(s, layer="detail-" + s.layer) for s in inner],
            Shape("polyline", ((sx, sy - 5), (sx, sy), (sx + bar_px, sy), (sx + bar_px, sy - 5)), stroke=COLOURS["text"],
                  stroke_width=2, layer="detail-frame"),
            Shape("text", ((sx + bar_px / 2, sy - 7),), text=_fmt_len(bar_m), size=11, anchor="middle",
                  fill=COLOURS["text"], layer="detail-frame"),
            Shape("polygon", box, stroke="#333333", stroke_width=1.5, layer="detail-frame"),
            Shape("text", ((bx0, by0 - 6),), text=f"detail (x{d.scale / main.scale:.0f}): the passes of the thin area",
                  size=12, bold=True, fill=COLOURS["text"], layer="detail-frame"),
            Shape("polygon", mark, stroke="#333333", stroke_width=1.5, layer="detail-mark"),
            Shape("text", ((mark_top[0] + 4, mark_top[1] - 4),), text="detail", size=11, bold=True,
                  fill="#333333", layer="detail-mark")]


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


def _legend(compiled: Compiled, rep: MissionReport, fp_stride: int,
            bottom: float = MAP_H - 12) -> tuple[list[tuple[str, str]], list[Shape]]:
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
    shapes.extend(_warning_code_shapes(rep, x0, y, bottom))
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


def _warning_code_shapes(rep: MissionReport, x0: float, y: float, bottom: float = MAP_H - 12) -> list[Shape]:
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
        if y > bottom:
            break
        shapes.append(Shape("text", ((x0 + 8, y),), text=f"{c}" + (f" (x{n})" if n > 1 else ""), size=12,
                            fill="#a05a00", layer="legend"))
    return shapes


def render_html(compiled: Compiled, sim: Any, rep: MissionReport, pic: Picture, tiles: Any = None) -> str:
    """The interactive map (missions.formats.webmap) with the legend's figures."""
    from missions.formats.webmap import render_map_html

    return render_map_html(compiled, sim, rep, pic.rows, tiles)


def write_preview(compiled: Compiled, out: str | Path, tiles: Any = None) -> Path:
    """Render the preview to `out` (.svg, .png or .html, by suffix), written atomically. `tiles`
    (missions.formats.webmap.TileSource) puts a basemap under the HTML map."""
    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".svg", ".png", ".html", ".htm"):
        raise PlanError(f"cannot draw a preview as '{suffix or out.name}'", where=str(out),
                        hint="name the output .svg, .png or .html")
    if tiles is not None and suffix not in (".html", ".htm"):
        raise PlanError(f"a basemap (--tiles) is drawn only under the interactive map, not in a {suffix} file",
                        where=str(out), hint="name the output FILE.html, or leave --tiles out")
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
            text = render_svg(pic) if suffix == ".svg" else render_html(compiled, sim, rep, pic, tiles)
            tmp.write_text(text, encoding="utf-8")
    return out
