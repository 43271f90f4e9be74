"""Corridor scan: parallel offset lines along a polyline (pipeline, road, river, power line).

    plan = plan_corridor([[50.11, 14.50], [50.12, 14.52]], width_m=60, footprint=fp, front_pct=80,
                         side_pct=60, turnaround_m=10, speed_mps=6)

The corridor is the polyline buffered by width/2 with flat ends (`plan.area`, an `Area` in its own local
projection — measure coverage against it). Lines: the fewest offset curves, `spacing` apart and centred
on the polyline, whose footprints span the width plus the edge margin (QGC uses ceil(width/spacing),
which leaves the outer half-footprints unused). Bends use round joins so the outer lines stay at their
offset; each line is extended at its far end so its length is a whole number of trigger distances (the
last photo sits on or beyond the corridor's end). Lines are flown alternately, each with turnaround stubs
along its end tangents and distance triggering over its whole length.

A closed line (its last point within 1 cm of its first: a ring road, a fence around a site) is a loop: the
corridor is a ring with no ends, and each line is a closed offset ring of the centre line (the boundary of the
centre polygon buffered out or in by the offset), started level with the first point and flown once round and
on along itself to a whole number of trigger distances, so its last photo sits on or beyond its first. GEOS's
offset curve of a closed line is no such ring: it leaves out the join at the closing vertex on the outer side
of the turn there (a 300 m square loop starting at a corner left a wedge of its outer corner unphotographed:
99.89 % coverage), and where the closing vertex is nearly straight it drops stretches of the inner lines (the
same loop started mid-edge 1–5 cm off the straight line lost 145 m of its two inner lines: 97.2 %).

Returns a `CorridorPlan` with the same fields the compiler reads from a `SurveyPlan` (waypoints,
camera_spans, photos, hover=False, stats, warnings) plus `area` and `lines_xy`.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.geometry.area import Area, LatLonPolygon, _inline_polygon
from missions.errors import PlanError
from missions.geometry.footprint import Footprint, transect_spacing_m, trigger_distance_m
from missions.geometry.geo import LocalProjection
from missions.geometry.route import KIND_ENTRY, KIND_EXIT, KIND_TURN_IN
from missions.compiled import PlanWarning
from missions.geometry.objectives import estimated_time_s
from missions.geometry.survey import DEFAULT_EXIT_MARGIN_M, MAX_PHOTOS, SurveyStats, Waypoint, check_photo_budget
from missions.geometry.swaths import DEFAULT_EDGE_MARGIN_M, line_offsets
from missions.geometry.triggers import PhotoPoint, TriggerSpan, simulate_distance_trigger


@dataclass(frozen=True)
class CorridorPlan:
    waypoints: tuple[Waypoint, ...]
    camera_spans: tuple[TriggerSpan, ...]
    hover: bool
    trigger_distance_m: float
    spacing_m: float
    photos: tuple[PhotoPoint, ...]
    lines_xy: tuple[tuple[tuple[float, float], ...], ...]
    area: Area
    stats: SurveyStats
    warnings: tuple[PlanWarning, ...]

    @property
    def path_xy(self) -> np.ndarray:
        return np.array([(w.x, w.y) for w in self.waypoints], dtype=float).reshape(-1, 2)


def _offset_line(centre: Any, g: Any) -> np.ndarray | None:
    """One offset line, running the centre line's way, from what `offset_curve` returned: None when empty.

    GEOS cuts an offset curve into pieces where the centre line has a vertex it treats as a degenerate turn
    (a middle point within ~1 mm of the straight line, as a densified or hand-clicked straight line has):
    each piece is half of the same line, so they are merged back into one. Keeping only the longest left
    one side's lines half the corridor long (84 % coverage on a 3-point straight line). Pieces that still
    do not meet are chained in their order along the centre line by straight hops over the gap."""
    import shapely
    from shapely.geometry import Point

    if g.is_empty:
        return None
    if g.geom_type != "LineString":
        g = shapely.line_merge(g)
    pieces = [h for h in getattr(g, "geoms", [g]) if h.geom_type == "LineString" and h.length > 1e-6]
    if not pieces:
        return None
    out = []
    for h in sorted(pieces, key=lambda h: centre.project(h.interpolate(0.5, normalized=True))):
        xy = np.asarray(h.coords, dtype=float)
        # line_merge joins the pieces whichever way round suits it
        if centre.project(Point(xy[0])) > centre.project(Point(xy[-1])):
            xy = xy[::-1]
        out.append(xy if not out or np.hypot(*(xy[0] - out[-1][-1])) > 1e-9 else xy[1:])
    return np.vstack(out)


def _ring_offsets(ring: np.ndarray, o: float, start: np.ndarray) -> list[np.ndarray]:
    """Offset lines of a closed centre line `ring` at signed offset o (left of the direction of travel positive,
    as offset_curve): the boundary rings of the centre polygon buffered by o, outward or inward, with round joins
    (round on the outer side of every turn, trimmed on the inner side, as offset_curve). Each runs the centre
    line's way round, closed, and starts at its point nearest `start` (where an open line's offset would start).
    One ring as a rule; an inward offset that pinches off gives one per piece, an outward one that closes a bay
    narrower than the offset also the bay's ring, and none when the loop is too small for the offset."""
    from shapely.geometry import LineString, Point, Polygon
    from shapely.geometry.polygon import orient
    from shapely.ops import substring

    poly = Polygon(ring)
    ccw = poly.exterior.is_ccw
    inside = (o > 0) == ccw                     # left of a counter-clockwise loop is its inside
    g = poly.buffer(-abs(o) if inside else abs(o), quad_segs=4, join_style="round")
    sign = 1.0 if ccw else -1.0
    rings = []
    for part in getattr(g, "geoms", [g]):
        if part.geom_type != "Polygon" or part.is_empty:
            continue
        part = orient(part, sign)               # exterior the loop's way round, a bay's ring too
        rings += [r for r in [part.exterior, *part.interiors] if r.length > 1e-6]
    out = []
    for r in sorted(rings, key=lambda r: r.distance(Point(start))):
        line = LineString(r.coords)
        s0 = float(line.project(Point(start)))
        if s0 <= 1e-9 or s0 >= line.length - 1e-9:
            xy = np.asarray(line.coords, dtype=float)
        else:
            a = np.asarray(substring(line, s0, line.length).coords, dtype=float)
            b = np.asarray(substring(line, 0.0, s0).coords, dtype=float)
            xy = np.vstack([a, b[1:]])
            xy[-1] = xy[0]
        out.append(xy)
    return out


def _extend_along(xy: np.ndarray, extra: float) -> np.ndarray:
    """A closed line flown on past its start along itself for `extra` metres (less than its length)."""
    if extra <= 1e-9:
        return xy
    seg = np.hypot(*np.diff(xy, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    k = min(max(int(np.searchsorted(cum, extra, side="left")), 1), len(xy) - 1)   # first vertex at/after it
    f = (extra - cum[k - 1]) / max(seg[k - 1], 1e-12)
    return np.vstack([xy, xy[1:k], xy[k - 1] + f * (xy[k] - xy[k - 1])])


def _extend_end(xy: np.ndarray, extra: float) -> np.ndarray:
    if extra <= 1e-9:
        return xy
    d = xy[-1] - xy[-2]
    d = d / np.hypot(*d)
    return np.vstack([xy, xy[-1] + d * extra])


class _CentreLine(NamedTuple):
    """The corridor's centre line in its own local projection."""

    projection: LocalProjection
    xy: np.ndarray                 # vertices, points under 1 cm apart merged; a loop's last is its first
    closed: bool                   # a loop (see the module docstring)
    line: Any                      # shapely LineString of xy

    @property
    def left(self) -> np.ndarray:
        """Unit normal to the left of the first segment: where a line at a positive offset starts."""
        d = self.xy[1] - self.xy[0]
        return np.array([-d[1], d[0]]) / np.hypot(*d)


class _Spacing(NamedTuple):
    spacing_m: float               # between lines
    trigger_m: float               # between photos on a line
    interval_s: float              # between photos at the planned speed


class _PathPoint(NamedTuple):
    x: float
    y: float
    kind: str                      # KIND_TURN_IN | KIND_ENTRY | "line" | KIND_EXIT
    line: int                      # index of the flight line it belongs to


def _checked_points(line: Sequence[Sequence[float]], width_m: float, where: str) -> Sequence[Any]:
    """The centre line's [lat, lon] points, with the width checked."""
    poly_in: LatLonPolygon = _inline_polygon(line, where)      # reuses the [lat, lon] checks
    pts = poly_in.outer
    if len(pts) < 2:
        raise PlanError("a corridor needs at least 2 points", where=where,
                        hint="give the centre line as [lat, lon] points, e.g. [[50.110, 14.500], [50.113, 14.504]]")
    if not (isinstance(width_m, (int, float)) and math.isfinite(width_m) and width_m > 0):
        raise PlanError(f"corridor width {width_m!r} m must be positive", where="corridor.width_m",
                        hint="width_m is the full width in metres, centred on the line, e.g. width_m: 60")
    return pts


def _spacing(footprint: Footprint, front_pct: float, side_pct: float, speed_mps: float,
             min_interval_s: float | None) -> _Spacing:
    """Line spacing and trigger distance from the overlaps; photos may not come faster than the camera shoots."""
    spacing = transect_spacing_m(footprint, side_pct)
    trig = trigger_distance_m(footprint, front_pct)
    interval = trig / speed_mps
    if min_interval_s and interval < min_interval_s - 1e-9:
        raise PlanError(f"photos would be {interval:.2f} s apart, faster than the camera's minimum of "
                        f"{min_interval_s:g} s", where="overlap.front",
                        hint=f"fly at most {trig / min_interval_s:.1f} m/s, lower the front overlap or fly higher")
    return _Spacing(spacing, trig, interval)


def _centre_line(pts: Sequence[Any], where: str) -> _CentreLine:
    """The points projected, refused when they have no length, span more than a plan holds or cross."""
    from shapely.geometry import LineString

    from missions.geometry.geo import MAX_EXTENT_M  # the limit areas have: the local projection's accuracy

    proj = LocalProjection.centred_on([p[0] for p in pts], [p[1] for p in pts])
    x, y = proj.to_xy([p[0] for p in pts], [p[1] for p in pts])
    xy = np.column_stack([x, y])
    keep = np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 0.01])
    xy = xy[keep]
    if len(xy) < 2:
        raise PlanError("the corridor line has no length (all points coincide)", where=where,
                        hint="give its start and end as different points (points under 1 cm apart count as one)")
    closed = len(xy) >= 4 and float(np.hypot(*(xy[-1] - xy[0]))) <= 0.01
    if closed:
        xy[-1] = xy[0]
    size = float(max(np.ptp(xy[:, 0]), np.ptp(xy[:, 1])))
    if not size <= MAX_EXTENT_M:
        raise PlanError(f"the corridor line spans {size / 1000:.0f} km, more than the {MAX_EXTENT_M / 1000:.0f} km "
                        "one plan can hold", where=where, hint="split it into several plans")
    centre = LineString(xy)
    if not centre.is_simple:
        raise PlanError("the corridor line crosses itself", where=where,
                        hint="split it into two corridors")
    return _CentreLine(proj, xy, closed, centre)


def _corridor_area(centre: _CentreLine, width_m: float, where: str) -> Area:
    """The centre line buffered by width/2 with flat ends (a ring for a loop)."""
    from shapely.geometry.polygon import orient

    corridor = centre.line.buffer(width_m / 2.0, cap_style="flat", join_style="round")
    corridor = orient(corridor, 1.0) if corridor.geom_type == "Polygon" else corridor
    return Area(corridor, centre.projection, where)


def _offset_pieces(centre: _CentreLine, o: float) -> list[np.ndarray]:
    """The line(s) at offset o from the centre line: one as a rule (see `_ring_offsets` for a loop's)."""
    if centre.closed:
        # each ring starts level with the first point: where an open line's offset would start
        if abs(o) < 1e-9:
            return [centre.xy]
        return _ring_offsets(centre.xy, float(o), centre.xy[0] + float(o) * centre.left)
    g = centre.line if abs(o) < 1e-9 else centre.line.offset_curve(float(o), quad_segs=4, join_style="round")
    lxy = _offset_line(centre.line, g)
    return [] if lxy is None else [lxy]


def _whole_triggers(lxy: np.ndarray, trig: float, closed: bool) -> np.ndarray:
    """A flight line simplified to 25 cm and extended to a whole number of trigger distances (on past its start
    round a loop, straight on past its end otherwise), so its last photo sits on or beyond the corridor's end."""
    from shapely.geometry import LineString

    lxy = np.asarray(LineString(lxy).simplify(0.25).coords, dtype=float)
    L = float(np.hypot(*np.diff(lxy, axis=0).T).sum())
    extra = math.ceil(L / trig - 1e-9) * trig - L
    return _extend_along(lxy, extra) if closed else _extend_end(lxy, extra)


def _flight_lines(centre: _CentreLine, offsets: np.ndarray, trig: float, where: str) -> list[np.ndarray]:
    lines = [_whole_triggers(lxy, trig, centre.closed) for o in offsets for lxy in _offset_pieces(centre, o)]
    if not lines:
        raise PlanError("the corridor produced no flight lines", where=where,
                        hint="straighten the line or narrow width_m; if neither helps, please report it with "
                             "the plan")
    return lines


def _unit(d: np.ndarray) -> np.ndarray:
    return d / np.hypot(*d)


def _flight_path(lines: list[np.ndarray], trig: float, turnaround_m: float,
                 exit_margin_m: float) -> tuple[list[_PathPoint], list[TriggerSpan]]:
    """The lines flown alternately: each entered along its start tangent from a turnaround stub, shot from its
    entry to an exit point just past its end (the trigger stops there), then on to a stub along its end tangent."""
    em = min(exit_margin_m, 0.45 * trig)
    path: list[_PathPoint] = []
    spans: list[TriggerSpan] = []
    for k, lxy in enumerate(lines):
        seq = lxy if k % 2 == 0 else lxy[::-1]
        d0 = _unit(seq[1] - seq[0])
        d1 = _unit(seq[-1] - seq[-2])
        if turnaround_m > 0:
            s = seq[0] - d0 * turnaround_m
            path.append(_PathPoint(float(s[0]), float(s[1]), KIND_TURN_IN, k))
        a = len(path)
        for i, p in enumerate(seq):
            path.append(_PathPoint(float(p[0]), float(p[1]), KIND_ENTRY if i == 0 else "line", k))
        e = seq[-1] + d1 * em
        path.append(_PathPoint(float(e[0]), float(e[1]), KIND_EXIT, k))
        spans.append(TriggerSpan(a, len(path) - 1, trig, True, False))
        if turnaround_m > em:
            t = seq[-1] + d1 * turnaround_m
            path.append(_PathPoint(float(t[0]), float(t[1]), KIND_TURN_IN, k))
    return path, spans


def _photos(pxy: np.ndarray, spans: list[TriggerSpan], proj: LocalProjection) -> tuple[PhotoPoint, ...]:
    """Where the distance trigger shoots along the path."""
    raw = simulate_distance_trigger(pxy, spans)
    fxy = np.array([(p.x, p.y) for p in raw]).reshape(-1, 2)
    flat, flon = proj.to_latlon(fxy[:, 0], fxy[:, 1]) if len(fxy) else (np.zeros(0), np.zeros(0))
    return tuple(PhotoPoint(p.x, p.y, p.heading_deg, p.span, float(a), float(o)) for p, a, o in zip(raw, flat, flon))


def _stats(area: Area, sp: _Spacing, lines: list[np.ndarray], pxy: np.ndarray, photo_count: int,
           speed_mps: float) -> SurveyStats:
    length = float(np.hypot(*np.diff(pxy, axis=0).T).sum())
    return SurveyStats(area_m2=area.area_m2, angle_deg=math.nan, spacing_m=sp.spacing_m,
                       trigger_distance_m=sp.trigger_m, lines=len(lines), legs=len(lines), photo_count=photo_count,
                       path_length_m=length,
                       leg_length_m=float(sum(np.hypot(*np.diff(l, axis=0).T).sum() for l in lines)),
                       est_time_s=estimated_time_s(length, 2 * len(lines), speed_mps),
                       trigger_interval_s=sp.interval_s)


def plan_corridor(line: Sequence[Sequence[float]], width_m: float, footprint: Footprint, front_pct: float,
                  side_pct: float, turnaround_m: float = 10.0, speed_mps: float = 5.0,
                  min_interval_s: float | None = None, where: str = "corridor.line",
                  exit_margin_m: float = DEFAULT_EXIT_MARGIN_M, photos_left: int = MAX_PHOTOS) -> CorridorPlan:
    """Plan a corridor along `line` (see module doc); `photos_left`: what the plan's earlier steps left of
    MAX_PHOTOS."""
    pts = _checked_points(line, width_m, where)
    sp = _spacing(footprint, front_pct, side_pct, speed_mps, min_interval_s)
    centre = _centre_line(pts, where)
    area = _corridor_area(centre, width_m, where)
    offsets = line_offsets(width_m, footprint.across_m, sp.spacing_m, DEFAULT_EDGE_MARGIN_M) - width_m / 2.0
    check_photo_budget(centre.line.length * len(offsets) / sp.trigger_m, "corridor", photos_left)
    lines = _flight_lines(centre, offsets, sp.trigger_m, where)
    path, spans = _flight_path(lines, sp.trigger_m, turnaround_m, exit_margin_m)
    pxy = np.array([(p.x, p.y) for p in path])
    lat, lon = centre.projection.to_latlon(pxy[:, 0], pxy[:, 1])
    waypoints = tuple(Waypoint(p.x, p.y, float(a), float(o), p.kind, p.line) for p, a, o in zip(path, lat, lon))
    photos = _photos(pxy, spans, centre.projection)
    return CorridorPlan(waypoints, tuple(spans), False, sp.trigger_m, sp.spacing_m, photos,
                        tuple(tuple(map(tuple, l.tolist())) for l in lines), area,
                        _stats(area, sp, lines, pxy, len(photos), speed_mps), ())
