"""Measured quality of a set of photos over an area — computed from footprints, never from the plan's intent.

Footprint of a photo: a rectangle centred on the photo position, `along_m` in the direction of travel
(heading, degrees clockwise from north) and `across_m` perpendicular to it, at the real altitude (flat
ground at the altitude's datum).

Definitions (fractions in [0, 1]; multiply by 100 for percent):
  coverage        area(area ∩ ⋃ footprints) / area(area).
  front overlap   for each pair of consecutive photos of the same span (a camera-on leg):
                  area(F_i ∩ F_i+1) / area(F); the minimum over all such pairs is reported.
  side overlap    photos of a span that lie on one straight line with one heading form a run (its
                  segment from first to last photo). For two runs with parallel headings (within 2°)
                  whose along-track ranges overlap, side overlap = 1 − lateral distance / across_m.
                  A line that bends (a corridor along a track) is many short runs whose neighbours on
                  the next line are seldom parallel: a run of a span with several runs takes instead the
                  lateral offset of the nearest photo of another span beside it (along-track within half
                  a footprint of its ends), across its line as flown — the neighbouring footprints reach it
                  as far as that photo's. A run of two photos or more is straight, and its line is the run
                  itself; its neighbours are the photos heading within 20° of it, either way round (the
                  other leg of a bend is no side neighbour). A single photo's line runs from the photo
                  before it to the one after it. Where such a photo, or the neighbour, is in a corner (its
                  line turns more than 20° from the photo before to the one after) that side is not
                  measured: coverage measures corners. A survey's lines are one run each and are measured
                  by the parallel rule alone, as before.
                  Each run takes its nearest such neighbour on each side; the minimum over all runs and
                  sides is reported. Runs with no neighbour on a side (the outermost lines) contribute
                  nothing on that side, and a neighbour farther than across_m is no overlap but a gap,
                  which shows in coverage instead.
                  So the figure is the minimum over a corridor's straight and gently bent stretches, not
                  over its bends. At a bend turning by θ the lines outside the centre line arc round the
                  vertex and those inside turn sharp at |o| / cos(θ/2) from it, so the two lines either
                  side of the centre line are o_out + |o_in| / cos(θ/2) apart there instead of
                  o_out + |o_in|: at a 90° bend of a 60 m corridor at 60 % requested (13.4 m spacing)
                  16.2 m, and every footprint-based count that includes bends reads 39–47 % there (the
                  nearest photo of the other line across a photo's heading: 46 %; the share of a photo's
                  across-track centre line that the other line's footprints cover: 39–41 %), on an open
                  bent corridor just as on a closed loop. Measures that include bends also report
                  false lows there (on an acute bend, a photo of the innermost line whose nearest other
                  line beside it lies on the other leg: 1 %). Whether the figure should count bends, and
                  by which rule, is left open.
  outside_m       length of the flown path outside the area (turnarounds included).
  path_lower_bound_m   area / spacing: a path that sweeps the area with lines `spacing` apart can be
                  no shorter (every metre covers at most `spacing` metres of width).
  photo_lower_bound    area / (spacing · trigger distance): each photo "owns" at most that much new ground.

Speed: consecutive photos of a run are merged into one rectangle (exact: same heading, on the line, gaps
≤ along_m), so coverage is one union of O(lines) strips rather than O(photos) rectangles; overlaps are
vectorised. A 100 km² survey (~10^6 photos) measures in seconds.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.geometry.footprint import Footprint
from missions.geometry.triggers import PhotoPoint

_PARALLEL_SIN = math.sin(math.radians(2.0))
# A photo of a bent line whose neighbours on its line differ more than this in heading sits in a corner: the
# line's direction there is no one direction and a lateral distance means little where the footprints turn
# with the line. A run in a corner, or whose nearest neighbour on a side is, is not measured on that side (the
# line beyond is no neighbour); coverage measures the corner. A GPS track's kinks turn a line by 5–20°.
_CHAIN_TURN_DEG = 20.0


@dataclass(frozen=True)
class Coverage:
    area_m2: float
    covered_m2: float
    coverage: float                    # fraction of the area under at least one footprint
    min_front_overlap: float | None    # fraction; None when no span has two photos
    min_side_overlap: float | None     # fraction; None when no two runs lie side by side
    photo_count: int
    path_length_m: float
    outside_m: float
    path_lower_bound_m: float | None
    photo_lower_bound: float | None

    @property
    def path_ratio(self) -> float | None:
        return self.path_length_m / self.path_lower_bound_m if self.path_lower_bound_m else None

    @property
    def photo_ratio(self) -> float | None:
        return self.photo_count / self.photo_lower_bound if self.photo_lower_bound else None


def _arrays(photos: Sequence[PhotoPoint]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    xy = np.array([(p.x, p.y) for p in photos], dtype=float).reshape(-1, 2)
    h = np.radians(np.array([p.heading_deg for p in photos], dtype=float))
    span = np.array([p.span for p in photos], dtype=int)
    return xy, h, span


def footprint_polygons(xy: np.ndarray, heading_rad: np.ndarray, fp: Footprint) -> np.ndarray:
    """Rotated footprint rectangles (shapely array), one per photo."""
    return _rects(xy, xy, heading_rad, fp)


def _rects(start: np.ndarray, end: np.ndarray, heading_rad: np.ndarray, fp: Footprint) -> np.ndarray:
    import shapely   # heavy: loads only when a plan has an area
    d = np.column_stack([np.sin(heading_rad), np.cos(heading_rad)])
    n = np.column_stack([np.cos(heading_rad), -np.sin(heading_rad)])
    ha, hc = fp.along_m / 2.0, fp.across_m / 2.0
    s0 = start - d * ha
    e0 = end + d * ha
    ring = np.stack([s0 - n * hc, e0 - n * hc, e0 + n * hc, s0 + n * hc, s0 - n * hc], axis=1)
    return shapely.polygons(ring)


def _runs(xy: np.ndarray, h: np.ndarray, span: np.ndarray, fp: Footprint) -> list[tuple[int, int]]:
    """[start, end] index pairs of maximal runs: same span, same heading, collinear, gaps ≤ along."""
    n = len(xy)
    if n == 0:
        return []
    brk = np.ones(n, bool)
    if n > 1:
        dlt = xy[1:] - xy[:-1]
        dvec = np.column_stack([np.sin(h[:-1]), np.cos(h[:-1])])
        nvec = np.column_stack([np.cos(h[:-1]), -np.sin(h[:-1])])
        along = (dlt * dvec).sum(1)
        cross = (dlt * nvec).sum(1)
        same = (span[1:] == span[:-1]) & (np.abs(np.sin(h[1:] - h[:-1])) < 1e-9) \
            & (np.cos(h[1:] - h[:-1]) > 0) & (np.abs(cross) < 1e-6) & (along >= -1e-9) & (along <= fp.along_m + 1e-9)
        brk[1:] = ~same
    starts = np.nonzero(brk)[0]
    ends = np.append(starts[1:] - 1, n - 1)
    return list(zip(starts.tolist(), ends.tolist()))


def coverage_fraction(area: Any, photos: Sequence[PhotoPoint], fp: Footprint) -> tuple[float, float]:
    """(covered area m², coverage fraction)."""
    import shapely   # heavy: loads only when a plan has an area
    if not photos or area.area <= 0:
        return 0.0, 0.0
    xy, h, span = _arrays(photos)
    runs = _runs(xy, h, span, fp)
    s = np.array([r[0] for r in runs])
    e = np.array([r[1] for r in runs])
    strips = _rects(xy[s], xy[e], h[s], fp)
    union = shapely.union_all(strips)
    covered = float(shapely.intersection(area, union).area)
    return covered, covered / float(area.area)


def min_front_overlap(photos: Sequence[PhotoPoint], fp: Footprint) -> float | None:
    import shapely   # heavy: loads only when a plan has an area
    xy, h, span = _arrays(photos)
    if len(xy) < 2:
        return None
    pair = span[1:] == span[:-1]
    if not pair.any():
        return None
    i = np.nonzero(pair)[0]
    dlt = xy[i + 1] - xy[i]
    same_h = np.abs(np.sin(h[i + 1] - h[i])) < 1e-9
    ov = np.empty(len(i))
    # same heading: two congruent rectangles in one frame — the overlap is a product of 1-D overlaps
    d = np.column_stack([np.sin(h[i]), np.cos(h[i])])
    n = np.column_stack([np.cos(h[i]), -np.sin(h[i])])
    fa = np.clip(1.0 - np.abs((dlt * d).sum(1)) / fp.along_m, 0.0, 1.0)
    fc = np.clip(1.0 - np.abs((dlt * n).sum(1)) / fp.across_m, 0.0, 1.0)
    ov[:] = fa * fc
    turned = ~same_h
    if turned.any():
        a = footprint_polygons(xy[i[turned]], h[i[turned]], fp)
        b = footprint_polygons(xy[i[turned] + 1], h[i[turned] + 1], fp)
        ov[turned] = shapely.area(shapely.intersection(a, b)) / fp.area_m2
    return float(ov.min())


def min_side_overlap(photos: Sequence[PhotoPoint], fp: Footprint) -> float | None:
    import shapely   # heavy: loads only when a plan has an area
    xy, h, span = _arrays(photos)
    runs = _runs(xy, h, span, fp)
    if len(runs) < 2:
        return None
    s = np.array([r[0] for r in runs])
    e = np.array([r[1] for r in runs])
    S, E, H = xy[s], xy[e], h[s]
    segs = shapely.linestrings(np.stack([S, E + 1e-9], axis=1))
    tree = shapely.STRtree(segs)
    a, b = tree.query(segs, predicate="dwithin", distance=fp.across_m)
    keep = a != b
    a, b = a[keep], b[keep]
    if len(a) == 0:
        return None
    # pieces of lines that bend (spans of more than one run) are measured against the neighbours' lines as
    # flown; straight lines (a survey's: one run each) by the parallel rule
    run_span = span[s]
    ids, per_span = np.unique(run_span, return_counts=True)
    is_bent = np.isin(run_span, ids[per_span > 1])
    par = (np.abs(np.sin(H[b] - H[a])) < _PARALLEL_SIN) & ~is_bent[a]
    lat_p, a_p = _parallel_lateral(S, E, H, a[par], b[par], fp)
    lat_b, a_b = _bent_lateral(xy, h, span, s, e, np.nonzero(is_bent)[0], fp)
    a, lat = np.concatenate([a_p, a_b]), np.concatenate([lat_p, lat_b])
    if len(a) == 0:
        return None
    best = np.full((len(runs), 2), np.inf)
    side = (lat > 0).astype(int)
    np.minimum.at(best, (a, side), np.abs(lat))
    vals = best[np.isfinite(best)]
    return float(1.0 - vals.max() / fp.across_m) if len(vals) else None


def _parallel_lateral(S: np.ndarray, E: np.ndarray, H: np.ndarray, a: np.ndarray, b: np.ndarray,
                      fp: Footprint) -> tuple[np.ndarray, np.ndarray]:
    """Signed lateral distance of parallel run b from run a, for the pairs side by side (their footprints overlap
    along-track by at least half a footprint) and nearer than a footprint's width; and their a."""
    d = np.column_stack([np.sin(H[a]), np.cos(H[a])])
    n = np.column_stack([np.cos(H[a]), -np.sin(H[a])])
    lat = ((S[b] - S[a]) * n).sum(1)
    p0 = ((S[b] - S[a]) * d).sum(1)
    p1 = ((E[b] - S[a]) * d).sum(1)
    la = ((E[a] - S[a]) * d).sum(1)
    lo, hi = np.minimum(p0, p1), np.maximum(p0, p1)
    beside = (np.minimum(hi, la) - np.maximum(lo, 0.0)) > -fp.along_m / 2.0
    ok = beside & (np.abs(lat) > 1e-3) & (np.abs(lat) < fp.across_m)
    return lat[ok], a[ok]


class _RunLines(NamedTuple):
    """The line as flown of each measured run of a bent line (`_run_lines`), one row per run."""

    a: np.ndarray             # the run's index
    single: np.ndarray        # the run is a single photo
    start: np.ndarray         # xy of its first photo
    d: np.ndarray             # unit vector along its line
    n: np.ndarray             # unit normal to it
    length_m: np.ndarray      # from its first photo to its last, along d


def _along_line(span: np.ndarray, i: np.ndarray, step: int) -> np.ndarray:
    """The photo `step` places from photo i on its line (span), or i itself where the line ends first."""
    j = np.clip(i + step, 0, len(span) - 1)
    return np.where(span[j] == span[i], j, i)


def _in_corner(h: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Whether the heading turns more than _CHAIN_TURN_DEG from photo i to photo j."""
    return np.degrees(np.abs(np.angle(np.exp(1j * (h[j] - h[i]))))) > _CHAIN_TURN_DEG


def _bent_lateral(xy: np.ndarray, h: np.ndarray, span: np.ndarray, s: np.ndarray, e: np.ndarray, a: np.ndarray,
                  fp: Footprint) -> tuple[np.ndarray, np.ndarray]:
    """For runs `a` of lines that bend (s/e: first and last photo index of each run): signed lateral offset of
    the nearest photo of another span on each side, among those beside the run (within half a footprint of its
    ends along-track) and nearer than a footprint's width; and their a. The neighbouring line's footprints reach
    this run as far as its nearest photo there. Offsets are taken across the run's line as flown: a straight
    run's own (two photos or more; its neighbours are photos heading within _CHAIN_TURN_DEG of it, either way
    round), a single photo's from the photo before it to the photo after it (a photo's own heading turns with
    every kink of a GPS track). A single photo in a corner, or a run whose nearest photo on a side is in one,
    is not measured on that side (_CHAIN_TURN_DEG)."""
    if len(a) == 0:
        return np.zeros(0), np.zeros(0, int)
    lines = _run_lines(xy, h, span, s, e, a)
    r, q = _photos_beside(xy, h, span, s, lines, fp)
    return _nearest_each_side(xy, h, span, lines, r, q, fp)


def _run_lines(xy: np.ndarray, h: np.ndarray, span: np.ndarray, s: np.ndarray, e: np.ndarray,
               a: np.ndarray) -> _RunLines:
    """The line as flown of runs `a`, without the single photos in a corner (their line has no one direction).

    A run of two photos or more is straight (one heading, collinear): its line as flown is the run itself, and it
    is in no corner however the line turns beyond its ends. Were it judged by the photos beyond its ends, a side
    of a loop or a leg of a corridor between two bends would sit "in a corner" and never be measured: a loop's
    outer lines, each bent round every corner, would go unmeasured, flown half a spacing too far out unseen. A
    single photo's line runs from the photo before it to the one after it."""
    single = s[a] == e[a]
    i0 = np.where(single, _along_line(span, s[a], -1), s[a])
    i1 = np.where(single, _along_line(span, e[a], 1), e[a])
    t = xy[i1] - xy[i0]
    tl = np.hypot(t[:, 0], t[:, 1])
    ok = (tl > 1e-9) & ~(single & _in_corner(h, i0, i1))
    a, t, tl, single = a[ok], t[ok], tl[ok], single[ok]
    d = t / tl[:, None]
    start = xy[s[a]]
    return _RunLines(a, single, start, d, np.column_stack([d[:, 1], -d[:, 0]]), ((xy[e[a]] - start) * d).sum(1))


def _photos_beside(xy: np.ndarray, h: np.ndarray, span: np.ndarray, s: np.ndarray, lines: _RunLines,
                   fp: Footprint) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (r, q): photo q of another line lies in the window beside line r (along-track from half a footprint
    before it to half a footprint after it, a footprint's width to each side) and, when r is a straight run,
    heads along it.

    A straight run's side neighbours run alongside it: a photo of another line heading more than _CHAIN_TURN_DEG
    off the run's heading (either way round) is on another leg of a bend. An acute bend puts the other leg's
    photos within half a footprint of the run's end, off to one side; taken as a neighbour, such a photo would
    read the run's edge line lower than flown (56 % against 60 %: its one real neighbour is on its other side)."""
    import shapely   # heavy: loads only when a plan has an area

    d, n, start = lines.d, lines.n, lines.start
    half = fp.along_m / 2.0
    lo, hi = start - d * half, start + d * (lines.length_m + half)[:, None]
    ring = np.stack([lo - n * fp.across_m, hi - n * fp.across_m, hi + n * fp.across_m, lo + n * fp.across_m,
                     lo - n * fp.across_m], axis=1)
    tree = shapely.STRtree(shapely.points(xy))
    r, q = tree.query(shapely.polygons(ring), predicate="intersects")
    first_photo = s[lines.a[r]]
    along = np.abs(np.sin(h[q] - h[first_photo])) < math.sin(math.radians(_CHAIN_TURN_DEG))
    other = (span[q] != span[first_photo]) & (lines.single[r] | along)
    return r[other], q[other]


def _nearest_each_side(xy: np.ndarray, h: np.ndarray, span: np.ndarray, lines: _RunLines, r: np.ndarray,
                       q: np.ndarray, fp: Footprint) -> tuple[np.ndarray, np.ndarray]:
    """Of the pairs (r, q), the signed lateral offset of q across line r for the nearest q on each side of each
    line (nearer than a footprint's width), unless that photo is in a corner; and the lines' runs."""
    lat = ((xy[q] - lines.start[r]) * lines.n[r]).sum(1)
    near = (np.abs(lat) > 1e-3) & (np.abs(lat) < fp.across_m)
    r, q, lat = r[near], q[near], lat[near]
    order = np.lexsort((np.abs(lat), lat > 0, r))
    r, q, lat = r[order], q[order], lat[order]
    first = np.ones(len(r), bool)
    first[1:] = (r[1:] != r[:-1]) | ((lat[1:] > 0) != (lat[:-1] > 0))
    keep = first & ~_in_corner(h, _along_line(span, q, -1), _along_line(span, q, 1))
    return lat[keep], lines.a[r[keep]]


def outside_length_m(path_xy: np.ndarray, area: Any) -> float:
    from shapely.geometry import LineString   # heavy: loads only when a plan has an area
    if len(path_xy) < 2:
        return 0.0
    return float(LineString(path_xy).difference(area).length)


def measure(area: Any, photos: Sequence[PhotoPoint], fp: Footprint, path_xy: np.ndarray | None = None,
            spacing_m: float | None = None, trigger_m: float | None = None) -> Coverage:
    """All quality figures of `photos` (and the flown `path_xy`) over `area` (shapely geometry, metres)."""
    covered, frac = coverage_fraction(area, photos, fp)
    path = np.zeros((0, 2)) if path_xy is None else np.asarray(path_xy, float).reshape(-1, 2)
    length = float(np.hypot(*np.diff(path, axis=0).T).sum()) if len(path) > 1 else 0.0
    A = float(area.area)
    return Coverage(
        area_m2=A, covered_m2=covered, coverage=frac,
        min_front_overlap=min_front_overlap(photos, fp),
        min_side_overlap=min_side_overlap(photos, fp),
        photo_count=len(photos), path_length_m=length,
        outside_m=outside_length_m(path, area) if len(path) > 1 else 0.0,
        path_lower_bound_m=A / spacing_m if spacing_m else None,
        photo_lower_bound=A / (spacing_m * trigger_m) if spacing_m and trigger_m else None,
    )
