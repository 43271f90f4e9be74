"""Swath generation: parallel flight lines over an area at a given angle, split into inside segments (legs).

Frame: the line azimuth θ (degrees clockwise from north; 0 = north–south lines) defines
    d = (sin θ, cos θ)   along-track unit vector (x east, y north)
    n = (cos θ, −sin θ)  across-track unit vector
and every point has (u, v) = (p·n, p·d). Lines are u = const.

Line placement (per polygon part): the fewest lines whose footprints, `spacing_m` apart, span the part's
width plus `edge_margin_m` on each side, centred on the part. So the outer footprint edges reach past
the boundary on both sides (QGroundControl starts its grid at an arbitrary offset from the edge, QGC #5193).

Legs: each line is cut into the segments that lie inside the area (concave parts and holes give several
legs per line; QGroundControl keeps one segment from the first to the last crossing and flies over the gap).
Leg ends are then set by what the photos must cover, not by where the line meets the boundary:
  * an outer end (the line leaves the area for good) is snapped outward to the photo grid from half a
    trigger step inside the boundary, so the end photo sits on the boundary on average (QGC's too);
  * it is stretched further only for the strip no neighbouring line's footprint reaches (zero at side
    overlap ≥ 50 %; to the boundary for the outermost lines): the end photo's footprint, half a
    footprint beyond it less the edge margin, must reach the farthest area in that strip;
  * an end facing a gap (hole, exclusion, notch) is not extended into it, except at low side overlap for
    that same exclusive strip beside the gap, and never past the middle of the gap;
  * band pieces the line never crosses (tips between lines) stretch the outermost leg or get a short leg;
  * finally a repair pass measures what the legs' footprint strips leave uncovered and covers each piece
    from its nearest line (stretching a leg, else adding a short one).
So a leg never leaves the area and re-enters it: any part of a leg outside the area touches its end.

With `trigger_m`, leg ends lie on a grid of photo positions v = k·trigger_m shared by all lines (photos
line up across lines and the first photo is at the leg start); gap ends snap inward when half a
footprint still reaches the boundary (front overlap ≥ 50 %), else outward. An end held short of a gap's
middle stays on the grid too, so every leg is a whole number of trigger steps: a photo at both ends.

Cost: vectorised shapely intersections per line and band — O(lines · vertices) — plus one union of
O(legs) rectangles for the repair pass.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.geometry.geo import leaf_parts

# Aircraft cross-track error of a GNSS multirotor is ~0.5–1 m; the outermost footprints reach this far
# past the boundary so that the edge stays covered when the line is flown slightly inside.
DEFAULT_EDGE_MARGIN_M = 0.5
_EPS = 1e-6


@dataclass(frozen=True)
class Leg:
    """One straight flight segment with the camera on, in the order the swath generator produced it (+v)."""

    part: int          # index of the polygon part of the area
    line: int          # line index within the part (increasing u)
    u: float           # across-track coordinate of the line
    v0: float          # along-track start (v0 <= v1)
    v1: float
    x0: float
    y0: float
    x1: float
    y1: float
    outer0: bool       # the v0 end faces the outside of the area (True) or a gap inside it (False)
    outer1: bool
    angle_deg: float = 0.0   # line azimuth of the pass; +v points along (sin, cos) of it

    @property
    def length_m(self) -> float:
        return self.v1 - self.v0


@dataclass(frozen=True)
class SwathSet:
    """All legs of one pass at one angle."""

    angle_deg: float
    spacing_m: float
    legs: tuple[Leg, ...]
    lines: int

    @property
    def leg_length_m(self) -> float:
        return float(sum(l.length_m for l in self.legs))


def frame(angle_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """(d, n): along-track and across-track unit vectors for a line azimuth in degrees."""
    t = math.radians(angle_deg)
    return np.array([math.sin(t), math.cos(t)]), np.array([math.cos(t), -math.sin(t)])


def to_uv(geom: Any, angle_deg: float) -> Any:
    from shapely import affinity
    t = math.radians(angle_deg)
    c, s = math.cos(t), math.sin(t)
    return affinity.affine_transform(geom, [c, -s, s, c, 0.0, 0.0])


def uv_to_xy(u: np.ndarray | float, v: np.ndarray | float, angle_deg: float) -> tuple[Any, Any]:
    d, n = frame(angle_deg)
    return u * n[0] + v * d[0], u * n[1] + v * d[1]


def normalise_angle(angle_deg: float) -> float:
    """Line azimuth in [−90, 90): a line flown either way is the same line."""
    a = (float(angle_deg) + 90.0) % 180.0 - 90.0
    return 0.0 if abs(a) < 1e-12 else a


def line_offsets(width_m: float, across_m: float, spacing_m: float, edge_margin_m: float) -> np.ndarray:
    """Across-track offsets of the lines from the low edge, centred so both edges get the same margin."""
    need = width_m + 2.0 * edge_margin_m
    if need <= across_m + _EPS:
        return np.array([width_m / 2.0])
    n = int(math.ceil((need - across_m) / spacing_m - 1e-9)) + 1
    span = (n - 1) * spacing_m
    return width_m / 2.0 - span / 2.0 + spacing_m * np.arange(n)


class Interval(NamedTuple):
    """A stretch of a line, lo <= hi (along-track v, metres)."""

    lo: float
    hi: float


def _intervals(g: Any) -> list[Interval]:
    """v-intervals of the line pieces of a (rotated) intersection result."""
    out = []
    for h in leaf_parts(g, "LineString"):
        ys = [c[1] for c in h.coords]
        a, b = min(ys), max(ys)
        if b - a > _EPS:
            out.append((a, b))
    out.sort()
    merged: list[list[float]] = []
    for a, b in out:
        if merged and a <= merged[-1][1] + _EPS:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return [Interval(a, b) for a, b in merged]


def _polys(g: Any) -> list[Any]:
    return [h for h in leaf_parts(g, "Polygon") if h.area > _EPS]


def _grid_down(v: float, trigger_m: float) -> float:
    """The grid point at or below v (v itself when infinite). Leg ends stay on the photo grid so that a
    leg's length is a whole number of trigger steps (or zero): distance triggering shoots at the leg's
    start and every trigger_m after it, so only then is there a photo at the far end too, whichever way
    the leg is flown. An end clamped off the grid lost its last photo: up to a trigger step of a narrow
    strip beside a notch went unphotographed."""
    return math.floor(v / trigger_m + 1e-9) * trigger_m if math.isfinite(v) else v


def _grid_up(v: float, trigger_m: float) -> float:
    return math.ceil(v / trigger_m - 1e-9) * trigger_m if math.isfinite(v) else v


def _snap(a: float, b: float, outer_a: bool, outer_b: bool, trigger_m: float, inward_ok: bool) -> Interval:
    lo, hi = _grid_down(a, trigger_m), _grid_up(b, trigger_m)
    if not outer_a and inward_ok:
        lo = _grid_up(a, trigger_m)
    if not outer_b and inward_ok:
        hi = _grid_down(b, trigger_m)
    if hi < lo:          # a gap-bounded leg shorter than one trigger step: keep one photo in its middle
        mid = round((a + b) / 2.0 / trigger_m) * trigger_m
        lo = hi = mid
    return Interval(lo, hi)


class PartLeg(NamedTuple):
    """One leg of a polygon part in its (u, v) frame, as `part_legs` lays it."""

    line: int             # line index within the part (increasing u)
    u: float
    v0: float
    v1: float
    outer0: bool          # the v0 end faces the outside of the area (True) or a gap inside it (False)
    outer1: bool
    lowest_v0: float = -math.inf     # the ends never move past these: the middle of the gap beside them
    highest_v1: float = math.inf


class _LineLeg(NamedTuple):
    """A leg on one line while its ends are set: `snap0`/`snap1`, the end snaps outward to the photo grid."""

    v0: float
    v1: float
    snap0: bool
    snap1: bool
    lowest_v0: float
    highest_v1: float
    outer0: bool
    outer1: bool


def _own_leg(v0: float, v1: float) -> _LineLeg:
    """A short leg of its own for a piece no inside segment reaches: both ends outer."""
    return _LineLeg(v0, v1, True, True, -math.inf, math.inf, True, True)


@dataclass(frozen=True)
class _EndRules:
    """What sets a part's leg ends (see module doc), from the footprint, spacing and trigger distance."""

    trigger_m: float | None
    excl: float           # half-width of the strip beside a line no neighbouring line's footprint reaches
    reach: float          # how far a photo's footprint reaches along-track, less the edge margin
    along_reach: float    # how far beyond a leg's end a piece may lie and still stretch the leg to it
    s_in: float           # how far inside the boundary an outer end's photo may sit
    inward_ok: bool       # a gap end may snap inward: half a footprint still reaches the boundary

    @classmethod
    def of(cls, across_m: float, spacing_m: float, trigger_m: float | None, along_m: float | None,
           edge_margin_m: float) -> "_EndRules":
        # Only the strip that no neighbouring line's footprint reaches (half-width `excl`, which is 0 at side
        # overlap ≥ 50 %) needs this line's leg ends stretched; for the outermost lines that strip runs to
        # the boundary. A monotone slanted edge's far corner in the rest of the band lies beside the
        # neighbour's longer leg, inside its footprint.
        excl = max(0.0, spacing_m - across_m / 2.0 + edge_margin_m)
        inward_ok = along_m is not None and trigger_m is not None and along_m / 2.0 >= trigger_m - _EPS
        # a photo covers half a footprint beyond itself along-track: band corners beyond a leg end need the
        # leg (its last photo) to reach within that distance of them, not all the way
        reach = max(0.0, along_m / 2.0 - edge_margin_m) if along_m else 0.0
        # Outer leg ends are snapped outward to the photo grid; starting the requirement half a trigger step
        # inside the boundary makes the end photo land, on average, on the boundary instead of d/2 beyond it
        # (QGC's photo is at the boundary too). Its footprint still reaches past the boundary by the margin.
        s_in = min(trigger_m / 2.0, reach) if trigger_m and along_m else 0.0
        return cls(trigger_m, excl, reach, along_m if along_m else 0.0, s_in, inward_ok)

    def down(self, v: float) -> float:
        """v on the photo grid, rounded down (v itself without a trigger distance)."""
        return _grid_down(v, self.trigger_m) if self.trigger_m else v

    def up(self, v: float) -> float:
        return _grid_up(v, self.trigger_m) if self.trigger_m else v


def _strips(poly_uv: Any, us: np.ndarray, half_width_m: float) -> np.ndarray:
    """Per line, the part's pieces within `half_width_m` of it; the outermost lines' strips run past the part."""
    import shapely
    umin, vmin, umax, vmax = poly_uv.bounds
    lo, hi = us - half_width_m, us + half_width_m
    lo[0] = umin - 1.0
    hi[-1] = umax + 1.0
    return shapely.intersection(shapely.box(lo, vmin - 1.0, hi, vmax + 1.0), poly_uv)


def part_legs(poly_uv: Any, across_m: float, spacing_m: float, trigger_m: float | None, along_m: float | None,
              edge_margin_m: float, estimate: bool = False) -> list[PartLeg]:
    """The legs of one polygon part already rotated to the (u, v) frame, by line and v0.
    `estimate`: the inside segments only (no end rules, no repair) — enough to rank angles, ~10× cheaper."""
    import shapely

    umin, vmin, umax, vmax = poly_uv.bounds
    if along_m is not None and umax - umin + 2 * edge_margin_m <= across_m \
            and vmax - vmin + 2 * edge_margin_m <= along_m:
        # the whole part fits in one footprint: one photo at its centre
        vc = (vmin + vmax) / 2.0
        return [PartLeg(0, (umin + umax) / 2.0, vc, vc, True, True)]
    us = umin + line_offsets(umax - umin, across_m, spacing_m, edge_margin_m)
    nl = len(us)
    lines = shapely.linestrings(np.stack([np.column_stack([us, np.full(nl, vmin - 1.0)]),
                                          np.column_stack([us, np.full(nl, vmax + 1.0)])], axis=1))
    shapely.prepare(poly_uv)
    cores = shapely.intersection(lines, poly_uv)
    if estimate:
        return [PartLeg(k, float(us[k]), a, b, True, True) for k in range(nl) for a, b in _intervals(cores[k])]
    rules = _EndRules.of(across_m, spacing_m, trigger_m, along_m, edge_margin_m)
    bands = _strips(poly_uv, us, spacing_m / 2.0)
    exclusive = _strips(poly_uv, us, max(rules.excl, 1e-3))
    legs: list[PartLeg] = []
    for k in range(nl):
        legs.extend(_line_legs(poly_uv, k, float(us[k]), _intervals(cores[k]), _polys(bands[k]),
                               _polys(exclusive[k]), rules))
    return _repair(poly_uv, legs, us, across_m, rules, edge_margin_m)


def _line_legs(poly_uv: Any, k: int, u: float, ivs: list[Interval], band: list[Any], exclusive: list[Any],
               rules: _EndRules) -> list[PartLeg]:
    """The legs of line k (at u): one per inside segment `ivs`, ends set by what the photos must cover in the
    line's band and exclusive strip, then merged where they meet and put on the photo grid."""
    legs = [_segment_leg(poly_uv, u, ivs, i, exclusive, rules) for i in range(len(ivs))]
    legs = _cover_tips(legs, u, ivs, band, rules)
    return [_on_grid(k, u, leg, rules) for leg in _merged(legs)]


def _segment_leg(poly_uv: Any, u: float, ivs: list[Interval], i: int, exclusive: list[Any],
                 rules: _EndRules) -> _LineLeg:
    """The leg of inside segment i: an outer end pulled inside by up to s_in where the exclusive strip's far
    corners allow it; a gap end kept short of the gap's middle."""
    import shapely
    a, b = ivs[i]
    first, last = i == 0, i == len(ivs) - 1
    na, nb = a, b
    if first or last:
        # the first/last photo may sit up to s_in inside the boundary; the band's far corners
        # must stay within `reach` of it
        if first:
            na = a + rules.s_in
        if last:
            nb = b - rules.s_in
        mid = shapely.Point(u, (a + b) / 2.0)
        for c in exclusive:
            if c.distance(mid) < 1e-6:
                if first:
                    na = min(na, c.bounds[1] + rules.reach)
                if last:
                    nb = max(nb, c.bounds[3] - rules.reach)
                break
        if na > nb:
            na = nb = (na + nb) / 2.0
    leg = _LineLeg(na, nb, first, last,
                   -math.inf if first else (ivs[i - 1].hi + a) / 2.0 + 0.5,
                   math.inf if last else (b + ivs[i + 1].lo) / 2.0 - 0.5, first, last)
    return _reach_into_gaps(poly_uv, u, ivs, i, leg, rules) if rules.excl > 0 else leg


def _reach_into_gaps(poly_uv: Any, u: float, ivs: list[Interval], i: int, leg: _LineLeg,
                     rules: _EndRules) -> _LineLeg:
    """At low side overlap the strip beside a gap, closer to this line than its neighbours' footprints reach,
    can only be photographed from this line: reach into the gap as far as that needs, never past the middle of
    the gap (so two legs never join across it)."""
    import shapely
    a, b = ivs[i]
    excl, reach = rules.excl, rules.reach
    if i < len(ivs) - 1:
        slab = shapely.intersection(poly_uv, shapely.box(u - excl, b, u + excl, ivs[i + 1].lo))
        tops = [q.bounds[3] for q in _polys(slab) if q.bounds[1] <= b + 1e-6]
        if tops and min(max(tops) - reach, leg.highest_v1) > leg.v1:
            leg = leg._replace(v1=min(max(tops) - reach, leg.highest_v1), snap1=True)
    if i > 0:
        slab = shapely.intersection(poly_uv, shapely.box(u - excl, ivs[i - 1].hi, u + excl, a))
        bots = [q.bounds[1] for q in _polys(slab) if q.bounds[3] >= a - 1e-6]
        if bots and max(min(bots) + reach, leg.lowest_v0) < leg.v0:
            leg = leg._replace(v0=max(min(bots) + reach, leg.lowest_v0), snap0=True)
    return leg


def _cover_tips(legs: list[_LineLeg], u: float, ivs: list[Interval], band: list[Any],
                rules: _EndRules) -> list[_LineLeg]:
    """Band pieces the line never crosses (tips between lines): covered by stretching the outermost leg when
    they are near it, else by a short leg of their own; pieces beside a gap are left to the neighbouring lines.
    The legs, stretched, and the short ones after them."""
    import shapely
    legs = list(legs)
    extra: list[_LineLeg] = []
    for c in band:
        cv0, cv1 = c.bounds[1], c.bounds[3]
        if any(c.distance(shapely.Point(u, (a + b) / 2.0)) < 1e-6 for a, b in ivs):
            continue
        lo_need, hi_need = cv0 + rules.reach, cv1 - rules.reach
        if lo_need > hi_need:
            lo_need = hi_need = (cv0 + cv1) / 2.0
        if not legs:
            extra.append(_own_leg(lo_need, hi_need))
        elif cv1 <= legs[0].v0 + _EPS:
            if legs[0].v0 - cv1 > rules.along_reach:
                extra.append(_own_leg(lo_need, hi_need))
            else:
                legs[0] = legs[0]._replace(v0=min(legs[0].v0, lo_need))
        elif cv0 >= legs[-1].v1 - _EPS:
            if cv0 - legs[-1].v1 > rules.along_reach:
                extra.append(_own_leg(lo_need, hi_need))
            else:
                legs[-1] = legs[-1]._replace(v1=max(legs[-1].v1, hi_need))
        elif cv0 < legs[0].v0:
            legs[0] = legs[0]._replace(v0=min(legs[0].v0, lo_need))
        elif cv1 > legs[-1].v1:
            legs[-1] = legs[-1]._replace(v1=max(legs[-1].v1, hi_need))
    return legs + extra


def _merged(legs: list[_LineLeg]) -> list[_LineLeg]:
    """Legs of one line that meet or overlap joined into one, which ends where the farther-reaching one ends."""
    merged: list[_LineLeg] = []
    for leg in sorted(legs, key=lambda t: t.v0):
        if merged and leg.v0 <= merged[-1].v1 + _EPS:
            m = merged[-1]
            if leg.v1 >= m.v1:
                merged[-1] = m._replace(v1=leg.v1, snap1=leg.snap1, highest_v1=leg.highest_v1, outer1=leg.outer1)
        else:
            merged.append(leg)
    return merged


def _on_grid(k: int, u: float, leg: _LineLeg, rules: _EndRules) -> PartLeg:
    a, b = leg.v0, leg.v1
    if rules.trigger_m:
        a, b = _snap(a, b, leg.snap0, leg.snap1, rules.trigger_m, rules.inward_ok)
        # an outward snap must not carry a gap end past the middle of the gap; the end stays on
        # the grid (see _grid_down) at the last grid point before the middle
        a, b = max(a, _grid_up(leg.lowest_v0, rules.trigger_m)), min(b, _grid_down(leg.highest_v1, rules.trigger_m))
        if a > b:
            a = b = (a + b) / 2.0
    return PartLeg(k, u, a, b, bool(leg.outer0), bool(leg.outer1), leg.lowest_v0, leg.highest_v1)


def _repair(poly_uv: Any, legs: list[PartLeg], us: np.ndarray, across_m: float, rules: _EndRules,
            edge_margin_m: float) -> list[PartLeg]:
    """Measure what the legs leave uncovered (each leg's strip: its photos' footprints less the margins)
    and cover every remaining piece from its nearest line (`_cover_piece`). Catches the cases the band
    rules above do not foresee (spikes between lines, narrow necks) at the cost of one polygon union."""
    import shapely

    if not legs:
        return legs
    hw = max(across_m / 2.0 - edge_margin_m, 1e-3)
    reach = rules.reach
    min_piece = max(0.5, 1e-7 * poly_uv.area)
    legs = list(legs)
    for _round in range(2):
        rects = shapely.box([l.u - hw for l in legs], [l.v0 - reach for l in legs],
                            [l.u + hw for l in legs], [l.v1 + reach for l in legs])
        rest = poly_uv.difference(shapely.union_all(rects))
        pieces = [q for q in _polys(rest) if q.area > min_piece]
        if not pieces:
            break
        for q in pieces:
            _cover_piece(legs, q, us, rules)
    legs.sort(key=lambda l: (l.line, l.v0))
    return legs


def _cover_piece(legs: list[PartLeg], q: Any, us: np.ndarray, rules: _EndRules) -> None:
    """Cover piece q from its nearest line, in `legs`: stretch a leg on that line when the piece lies just
    beyond its end (on the grid, never past a gap's middle), else add a short leg."""
    pu0, pv0, pu1, pv1 = q.bounds
    k = int(np.argmin(np.abs(us - (pu0 + pu1) / 2.0)))
    lo, hi = pv0 + rules.reach, pv1 - rules.reach
    if lo > hi:
        lo = hi = (pv0 + pv1) / 2.0
    far = rules.along_reach
    on_line = sorted((i for i, l in enumerate(legs) if l.line == k),
                     key=lambda i: min(abs(legs[i].v0 - pv1), abs(legs[i].v1 - pv0)))
    for i in on_line:
        l = legs[i]
        if l.v0 <= lo and hi <= l.v1:
            return            # covered along-track already: the piece is a margin artefact
        if pv0 >= l.v0 and hi > l.v1 and hi - l.v1 <= far and hi <= l.highest_v1:
            legs[i] = l._replace(v1=max(l.v1, min(rules.up(hi), rules.down(l.highest_v1))))
            return
        if pv1 <= l.v1 and lo < l.v0 and l.v0 - lo <= far and lo >= l.lowest_v0:
            legs[i] = l._replace(v0=min(l.v0, max(rules.down(lo), rules.up(l.lowest_v0))))
            return
    legs.append(PartLeg(k, float(us[k]), rules.down(lo), rules.up(hi), True, True))


def generate_swaths(geometry: Any, angle_deg: float, footprint_across_m: float, spacing_m: float,
                    trigger_m: float | None = None, footprint_along_m: float | None = None,
                    edge_margin_m: float = DEFAULT_EDGE_MARGIN_M, estimate: bool = False) -> SwathSet:
    """Legs covering `geometry` (shapely Polygon/MultiPolygon in metres) with lines at azimuth `angle_deg`.
    `estimate=True` gives the bare inside segments, for ranking angles."""
    angle = normalise_angle(angle_deg)
    rotated = to_uv(geometry, angle)
    parts: Sequence[Any] = list(rotated.geoms) if rotated.geom_type == "MultiPolygon" else [rotated]
    legs: list[Leg] = []
    nlines = 0
    for p, poly in enumerate(parts):
        raw = part_legs(poly, footprint_across_m, spacing_m, trigger_m, footprint_along_m, edge_margin_m, estimate)
        if raw:
            nlines += max(r.line for r in raw) + 1
        for r in raw:
            x0, y0 = uv_to_xy(r.u, r.v0, angle)
            x1, y1 = uv_to_xy(r.u, r.v1, angle)
            legs.append(Leg(p, r.line, r.u, r.v0, r.v1, float(x0), float(y0), float(x1), float(y1), r.outer0, r.outer1,
                            angle))
    return SwathSet(angle, spacing_m, tuple(legs), nlines)


@dataclass(frozen=True)
class PartEdges:
    """Every ring edge of an area's parts as arrays, for `bare_lines`: edge k runs a[k] -> b[k] (metres) on part
    part[k] (edges grouped by part, part p's from first[p]), with the area on its left where left[k] is +1 (an
    outer ring drawn anticlockwise, a hole clockwise) and on its right where -1."""

    a: np.ndarray
    b: np.ndarray
    part: np.ndarray
    left: np.ndarray
    first: np.ndarray

    @property
    def parts(self) -> int:
        return len(self.first)

    @classmethod
    def of(cls, geometry: Any) -> "PartEdges":
        a, b, part, left, first = [], [], [], [], []
        n = 0
        polys = list(geometry.geoms) if geometry.geom_type == "MultiPolygon" else [geometry]
        for p, poly in enumerate(polys):        # in generate_swaths' order of parts
            first.append(n)
            for r, ring in enumerate([poly.exterior, *poly.interiors]):
                xy = np.asarray(ring.coords)[:, :2]
                ccw = float(np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1])) > 0
                a.append(xy[:-1])
                b.append(xy[1:])
                part.append(np.full(len(xy) - 1, p))
                left.append(np.full(len(xy) - 1, 1.0 if ccw == (r == 0) else -1.0))
                n += len(xy) - 1
        return cls(np.concatenate(a), np.concatenate(b), np.concatenate(part), np.concatenate(left), np.array(first))


@dataclass(frozen=True)
class BareLines:
    length_m: float      # the inside segments' length, summed
    legs: int            # inside segments (a part that fits in one footprint: one, of length 0)
    line_hops: int       # lines after the first of each part
    centre_xy: np.ndarray    # per part: the centre of its extent in the lines' frame (x, y metres)
    along_m: np.ndarray      # per part: its extent along the lines
    one_photo: np.ndarray    # per part: it fits in one footprint


def bare_lines(edges: PartEdges, angle_deg: float, across_m: float, spacing_m: float, along_m: float,
               edge_margin_m: float = DEFAULT_EDGE_MARGIN_M) -> BareLines:
    """The inside segments of the lines generate_swaths(estimate=True) lays over every part at `angle_deg`,
    measured from the edges alone in one vectorised pass (cost: edges + crossings; no polygon operations). A
    line's inside length is the sum of its crossings' v, negative where it enters the area and positive where
    it leaves: the edges it crosses are counted for u in [low end, high end), so a vertex on the line counts
    once."""
    d, n = frame(normalise_angle(angle_deg))
    ua, va = edges.a @ n, edges.a @ d
    ub, vb = edges.b @ n, edges.b @ d
    umin, umax = np.minimum.reduceat(ua, edges.first), np.maximum.reduceat(ua, edges.first)
    vmin, vmax = np.minimum.reduceat(va, edges.first), np.maximum.reduceat(va, edges.first)
    w = umax - umin
    one_photo = (w + 2 * edge_margin_m <= across_m) & (vmax - vmin + 2 * edge_margin_m <= along_m)
    need = w + 2.0 * edge_margin_m          # as line_offsets counts and centres the lines
    nl = np.where(need <= across_m + _EPS, 1, np.ceil((need - across_m) / spacing_m - 1e-9) + 1).astype(np.int64)
    nl[one_photo] = 0
    # line k of part p lies at u = centre[p] + (k - mid[p]) * spacing
    centre = (umin + umax) / 2.0
    mid = (nl - 1) / 2.0
    p = edges.part
    lo, hi = np.minimum(ua, ub), np.maximum(ua, ub)
    k_lo = np.maximum(np.ceil((lo - centre[p]) / spacing_m + mid[p]), 0).astype(np.int64)
    k_hi = np.minimum(np.ceil((hi - centre[p]) / spacing_m + mid[p]) - 1, nl[p] - 1).astype(np.int64)
    count = np.maximum(k_hi - k_lo + 1, 0)
    e = np.repeat(np.arange(len(ua)), count)
    k = k_lo[e] + np.arange(len(e)) - np.repeat(np.cumsum(count) - count, count)
    u = centre[p[e]] + (k - mid[p[e]]) * spacing_m
    du = ub[e] - ua[e]
    v = va[e] + (u - ua[e]) * (vb[e] - va[e]) / du
    # an edge crossed going +u with the area on its left has the area above it: the line enters there
    length = float(np.sum(-np.sign(du) * edges.left[e] * v))
    cx, cy = uv_to_xy(centre, (vmin + vmax) / 2.0, normalise_angle(angle_deg))
    return BareLines(length, int(len(e) // 2 + one_photo.sum()), int(np.maximum(nl - 1, 0).sum()),
                     np.column_stack([cx, cy]), vmax - vmin, one_photo)


def candidate_angles(geometry: Any, coarse_step_deg: float = 10.0, max_edges: int = 24) -> list[float]:
    """Angles worth trying: directions of the convex hull's edges (optimal for convex areas: the sweep
    is then perpendicular to the minimum width), of the longest polygon edges, and a coarse sweep."""
    cands: set[float] = set()
    hull = geometry.convex_hull
    parts = list(geometry.geoms) if geometry.geom_type == "MultiPolygon" else [geometry]

    def longest(rings: list[Any], k: int) -> None:
        edges: list[tuple[float, float]] = []
        for ring in rings:
            xy = np.asarray(ring.coords)
            dx, dy = np.diff(xy[:, 0]), np.diff(xy[:, 1])
            for ex, ey in zip(dx, dy):
                ln = math.hypot(ex, ey)
                if ln > 1e-6:
                    edges.append((ln, math.degrees(math.atan2(ex, ey))))
        edges.sort(reverse=True)
        for _ln, az in edges[:k]:
            cands.add(round(normalise_angle(az), 6))

    longest([hull.exterior] if hull.geom_type == "Polygon" else [], max_edges)
    longest([p.exterior for p in parts], max_edges // 2)
    a = -90.0
    while a < 90.0:
        cands.add(round(a, 6))
        a += coarse_step_deg
    return sorted(cands)
