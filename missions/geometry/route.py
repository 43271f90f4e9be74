"""Route: order legs into one flyable path with turnarounds and connections.

1. Cells: legs of consecutive lines whose along-track ranges overlap one-to-one form a boustrophedon cell
   (a monotone region). A concave area or a hole splits lines into several legs; where the pairing is not
   one-to-one a new cell starts.
2. Cell order: greedy nearest-next from every cell end as a start (the nearest next entry found on a grid of
   buckets: about O(cells) per start; starts capped), keeping the shortest total connection. Inside a cell the
   legs alternate direction (lawn-mower).
3. Each leg is flown turnaround-in → entry → exit → turnaround-out; the turnaround extends `turnaround_m`
   along the line beyond each end (QGC's TurnAroundDistance) so the vehicle is straight and at speed when
   the camera starts. The exit point lies `exit_margin_m` past the last photo so that an autopilot which
   accepts a waypoint early (ArduCopter's WPNAV_RADIUS, 2 m by default) still takes it.
4. Connections between cells whose straight line would leave the area go along the shortest path inside
   the polygon part (visibility graph over its vertices); those connections drop the turnaround stubs,
   which would leave the area. Parts too complex for the graph (> MAX_GRAPH_VERTICES) fall back to the
   straight line; the metres outside the area are measured by `coverage.outside_length_m` either way.
5. `avoid` (the area's holes and exclusion zones as drawn): a turnaround stub is cut short where it would
   enter one (and left out when less than MIN_STUB_M of it remains), and a connection that would still cross
   one drops its stubs and, if the straight hop from exit to entry crosses too, goes around it: inside the
   part when both legs are in one, else through free space around the zones (the same visibility graph over
   the zones' vertices). Stubs only straighten the vehicle before the camera starts; the photos are where
   the legs put them, so coverage is unchanged. What the zones' complexity or shape leaves crossing is
   measured by the report (`path_over_exclusion`).
"""

from __future__ import annotations

from dataclasses import dataclass
import heapq
import math
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.geometry.swaths import Leg, frame

MAX_GRAPH_VERTICES = 400
MIN_GAP_M2 = 25.0
_INSIDE_TOL_M = 0.05
# A turnaround cut short by an exclusion to less than this (beyond the exit point, for the stub after a leg)
# gives the vehicle no straight run, only one more waypoint: it is left out.
MIN_STUB_M = 1.0
# Stubs stop this far short of an exclusion and detours around one keep this far from it: the edge margin's
# GNSS cross-track error (swaths.DEFAULT_EDGE_MARGIN_M), so that a vehicle slightly off its track stays out.
_AVOID_CLEARANCE_M = 0.5
# A connection whose length inside the exclusions (beyond what its own ends force) exceeds this crosses them.
# Inside means deeper than this: a detour inside the area follows its boundary, which may be a zone's edge
# (the report measures the path over the zones with the same tolerance).
ZONE_EDGE_TOL_M = 0.05

# Up to this many cell entries (4 per cell) the greedy order scans them all at each step (numpy, faster than
# bucketing them at this size); above, it searches a grid of buckets around the position (_NearestEntry).
_SCAN_ENTRIES = 800

KIND_TURN_IN = "turnaround"
KIND_ENTRY = "entry"
KIND_EXIT = "exit"
KIND_VIA = "via"
KIND_PHOTO = "photo"


@dataclass(frozen=True)
class RoutePoint:
    x: float
    y: float
    kind: str              # turnaround | entry | exit | via | photo
    leg: int = -1          # index into Route.legs, -1 for connections


class FlownLeg(NamedTuple):
    """One step of a leg order: which leg, and whether it is flown from v1 to v0."""

    index: int
    reversed: bool


class CameraSpan(NamedTuple):
    """Where a leg's camera runs: from its entry point to its exit point (indices into Route.points)."""

    entry: int
    exit: int


@dataclass(frozen=True)
class Route:
    points: tuple[RoutePoint, ...]
    legs: tuple[Leg, ...]                 # in flying order
    reversed_legs: tuple[bool, ...]       # flown from v1 to v0
    spans: tuple[CameraSpan, ...]         # one per leg

    @property
    def xy(self) -> np.ndarray:
        return np.array([(p.x, p.y) for p in self.points], dtype=float).reshape(-1, 2)

    @property
    def length_m(self) -> float:
        xy = self.xy
        return float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0


def build_cells(legs: Sequence[Leg]) -> list[list[int]]:
    """Group leg indices into boustrophedon cells (lists ordered by line)."""
    by_line: dict[tuple[int, int], list[int]] = {}
    for i, l in enumerate(legs):
        by_line.setdefault((l.part, l.line), []).append(i)
    cells: list[list[int]] = []
    cell_of: dict[int, int] = {}
    for (part, line) in sorted(by_line):
        cur = sorted(by_line[(part, line)], key=lambda i: legs[i].v0)
        prev = sorted(by_line.get((part, line - 1), []), key=lambda i: legs[i].v0)

        def overl(i: int, j: int) -> bool:
            return min(legs[i].v1, legs[j].v1) - max(legs[i].v0, legs[j].v0) > 1e-6

        for i in cur:
            ps = [j for j in prev if overl(i, j)]
            if len(ps) == 1 and [k for k in cur if overl(k, ps[0])] == [i] and ps[0] in cell_of \
                    and cells[cell_of[ps[0]]][-1] == ps[0]:
                c = cell_of[ps[0]]
                cells[c].append(i)
                cell_of[i] = c
            else:
                cell_of[i] = len(cells)
                cells.append([i])
    return cells


def skip_line_order(n: int, gap: int) -> list[int]:
    """Positions 0..n-1 in an order where consecutive ones are at least `gap` apart: a plane cannot turn onto the
    line beside the one it leaves when they are closer than two turn radii. Blocks of 2s lines (s = gap + 1) are
    flown as pairs out and back, b, b+s, b+1, b+s+1, ..., every other block mirrored so that it starts s lines
    from where the last one ended; the lines left over at the end are flown lowest-far-enough first, and where
    none is far enough, nearest (a loop turn)."""
    if gap <= 1 or n <= 2:
        return list(range(n))
    s = gap + 1
    out: list[int] = []
    b = 0
    mirrored = False
    while b + 2 * s <= n:
        pairs = [(b + i, b + s + i) for i in range(s)]
        if mirrored:
            pairs = [(b + s - 1 - i, b + 2 * s - 1 - i) for i in range(s)]
        out += [k for pair in pairs for k in pair]
        b += 2 * s
        mirrored = not mirrored
    left = list(range(b, n))
    while left:
        far = next((k for k, m in enumerate(left) if not out or abs(m - out[-1]) >= gap), None)
        if far is None:
            far = min(range(len(left)), key=lambda k: abs(left[k] - out[-1]))
        out.append(left.pop(far))
    return out


def _cell_sequence(legs: Sequence[Leg], cell: list[int], from_start: bool, first_forward: bool,
                   gap: int = 1) -> list[FlownLeg]:
    order = cell if from_start else cell[::-1]
    order = [order[k] for k in skip_line_order(len(order), gap)]
    out = []
    fwd = first_forward
    for i in order:
        out.append(FlownLeg(i, not fwd))
        fwd = not fwd
    return out


def _ends(leg: Leg, rev: bool) -> tuple[tuple[float, float], tuple[float, float]]:
    a, b = (leg.x0, leg.y0), (leg.x1, leg.y1)
    return (b, a) if rev else (a, b)


class _Nearest(NamedTuple):
    """A nearest entry: compared as (distance, index), so equal distances go to the lowest index."""

    distance_m: float
    index: int


class _NearestEntry:
    """The greedy's nearest-next query over the cell entries (4 per cell, `flat[4·cell + option]`), a cell's four
    taken out once it is flown. Few entries left: a scan over all of them. Many: they are bucketed on a square
    grid of about one cell per bucket and `pop` scans rings of buckets outward from the position until no
    bucket beyond can hold anything nearer, so a step costs the neighbourhood, not every cell (a scan at every
    step is cells × entries distances a start: 1.4·10^8 for 6,000 parts). A ring search that would
    visit more buckets than there are entries left scans them all instead, which bounds the steps where the
    nearest entry is far away (the last cells of a sweep). Either way distances are np.hypot and ties go to
    the lowest index, so the order is the one a scan over all entries gives."""

    def __init__(self, flat: np.ndarray) -> None:
        self.flat = flat
        self.left = np.ones(len(flat), bool)
        self.count = len(flat)
        self.buckets: dict[tuple[int, int], list[int]] = {}
        self.key: list[tuple[int, int]] = []
        if self.count <= _SCAN_ENTRIES:
            return
        x0, y0 = flat.min(axis=0)
        x1, y1 = flat.max(axis=0)
        cells = len(flat) // 4
        self.h = max(math.sqrt((x1 - x0) * (y1 - y0) / cells), max(x1 - x0, y1 - y0) / cells, 1e-3)
        self.origin = (float(x0), float(y0))
        ij = np.floor((flat - np.array(self.origin)) / self.h).astype(np.int64)
        self.key = [(int(i), int(j)) for i, j in ij.tolist()]
        for k, key in enumerate(self.key):
            self.buckets.setdefault(key, []).append(k)

    def remove_cell(self, c: int) -> None:
        for k in range(4 * c, 4 * c + 4):
            self.left[k] = False
            if self.key:
                self.buckets[self.key[k]].remove(k)
        self.count -= 4

    def _ring(self, bi: int, bj: int, r: int) -> list[int]:
        if r == 0:
            return list(self.buckets.get((bi, bj), ()))
        out: list[int] = []
        get = self.buckets.get
        for j in range(bj - r, bj + r + 1):
            out.extend(get((bi - r, j), ()))
            out.extend(get((bi + r, j), ()))
        for i in range(bi - r + 1, bi + r):
            out.extend(get((i, bj - r), ()))
            out.extend(get((i, bj + r), ()))
        return out

    def _nearest_of(self, idx: list[int], pos: np.ndarray) -> _Nearest:
        ii = np.array(idx)
        dd = np.hypot(self.flat[ii, 0] - pos[0], self.flat[ii, 1] - pos[1])
        d = float(dd.min())
        return _Nearest(d, int(ii[dd == d].min()))

    def _nearest_left(self, pos: np.ndarray) -> _Nearest:
        dd = np.hypot(self.flat[:, 0] - pos[0], self.flat[:, 1] - pos[1])
        dd[~self.left] = np.inf
        k = int(np.argmin(dd))
        return _Nearest(float(dd[k]), k)

    def _nearest_by_rings(self, pos: np.ndarray) -> _Nearest:
        bi = int(math.floor((pos[0] - self.origin[0]) / self.h))
        bj = int(math.floor((pos[1] - self.origin[1]) / self.h))
        best = _Nearest(math.inf, -1)
        r = 0           # rings 0..r scanned: what they leave lies at least r·h from pos (less rounding)
        while True:
            ring = self._ring(bi, bj, r)
            if ring:
                best = min(best, self._nearest_of(ring, pos))
            if best.distance_m < (r - 1e-6) * self.h:
                return best
            r += 1
            if (2 * r + 1) ** 2 > self.count:
                return self._nearest_left(pos)

    def pop(self, pos: np.ndarray) -> _Nearest:
        """The nearest entry left, whose cell is then taken out."""
        nearest = self._nearest_by_rings(pos) if self.key else self._nearest_left(pos)
        self.remove_cell(nearest.index // 4)
        return nearest


class _CellWay(NamedTuple):
    """One of the four ways through a cell: from its first or its last line, the first leg flown forward or back."""

    legs: list[FlownLeg]
    entry: tuple[float, float]
    exit: tuple[float, float]


class _Tour(NamedTuple):
    """A greedy order of the cells: per step the flat index 4·cell + way, and the metres of the connections."""

    connections_m: float
    steps: list[int]


def _ways_through(legs: Sequence[Leg], cell: list[int], gap: int = 1) -> list[_CellWay]:
    ways = []
    for from_start in (True, False):
        for first_forward in (True, False):
            seq = _cell_sequence(legs, cell, from_start, first_forward, gap)
            ways.append(_CellWay(seq, _ends(legs[seq[0].index], seq[0].reversed)[0],
                                 _ends(legs[seq[-1].index], seq[-1].reversed)[1]))
    return ways


def _greedy_tour(entries: np.ndarray, exits: np.ndarray, first: int,
                 start_xy: tuple[float, float] | None) -> _Tour:
    """From way `first` (a flat index), the nearest next cell entry from each exit; ties go to the lowest
    (cell, way). `entries`, `exits`: cells × 4 ways × xy."""
    nearest = _NearestEntry(entries.reshape(-1, 2))
    c0, o0 = divmod(first, 4)
    nearest.remove_cell(c0)
    steps = [first]
    pos = exits[c0, o0]
    total = 0.0 if start_xy is None else float(math.dist(start_xy, entries[c0, o0]))
    for _ in range(len(entries) - 1):
        hit = nearest.pop(pos)
        total += hit.distance_m
        steps.append(hit.index)
        pos = exits[divmod(hit.index, 4)]
    return _Tour(total, steps)


def _tour_starts(legs: Sequence[Leg], cells: list[list[int]], entries: np.ndarray,
                 start_xy: tuple[float, float] | None, max_starts: int) -> list[int]:
    """The ways (flat indices) the greedy starts from: nearest the start position, else at the extremes of the
    sweep, the natural starts. 24 starts up to 100 cells, one above 2400: the search stays near 2400·cells steps."""
    n = len(cells)
    starts = list(range(4 * n))
    if start_xy is not None:
        starts.sort(key=lambda k: math.dist(start_xy, entries[divmod(k, 4)]))
    else:
        starts.sort(key=lambda k: (min(legs[i].line for i in cells[k // 4]), k % 4))
    return starts[:max(1, min(max_starts, 2400 // max(n, 1)))]


def order_legs(legs: Sequence[Leg], start_xy: tuple[float, float] | None = None,
               max_starts: int = 24, gap: int = 1) -> list[FlownLeg]:
    """The legs in flying order: cell by cell, nearest next (see module doc, step 2); within a cell, consecutive
    legs at least `gap` lines apart where possible (`skip_line_order`: a plane's turn)."""
    if not legs:
        return []
    cells = build_cells(legs)
    ways = [_ways_through(legs, cell, gap) for cell in cells]
    entries = np.array([[w.entry for w in cell_ways] for cell_ways in ways])      # cells×4×2
    exits = np.array([[w.exit for w in cell_ways] for cell_ways in ways])
    best: _Tour | None = None
    for first in _tour_starts(legs, cells, entries, start_xy, max_starts):
        tour = _greedy_tour(entries, exits, first, start_xy)
        if best is None or tour.connections_m < best.connections_m:
            best = tour
    assert best is not None
    return [step for k in best.steps for step in ways[k // 4][k % 4].legs]


class _InsidePaths:
    """Shortest paths inside one polygon (visibility graph over its vertices), built on first use.
    `keep_out`: ground the paths stay off (the exclusion zones grown by their clearance), when taking it away
    leaves the polygon in one piece; the gaps that call for a detour are the polygon's own either way."""

    def __init__(self, poly: Any, keep_out: Any = None) -> None:
        import shapely
        # gaps = holes and notches: outside the area but inside its convex hull. A straight connection
        # through them is what QGC flies over houses (#5215); beyond the hull it is just a turn.
        gaps = poly.convex_hull.difference(poly).buffer(-_INSIDE_TOL_M)
        if keep_out is not None and poly.intersects(keep_out):
            walk = poly.difference(keep_out)
            poly = walk if walk.geom_type == "Polygon" else poly
        self.poly = poly
        self.region = poly.buffer(_INSIDE_TOL_M, join_style="mitre")
        shapely.prepare(self.region)
        # notches smaller than this are boundary noise (GIS exports, hand-drawn jitter), not worth a detour
        pieces = [g for g in getattr(gaps, "geoms", [gaps]) if not g.is_empty and g.area >= MIN_GAP_M2]
        for g in pieces:
            shapely.prepare(g)
        self.gap_pieces = pieces
        self.gap_tree = shapely.STRtree(pieces) if pieces else None
        verts = [np.asarray(poly.exterior.coords)[:-1]] + [np.asarray(r.coords)[:-1] for r in poly.interiors]
        self.v = np.concatenate(verts) if verts else np.zeros((0, 2))
        self.ok = len(self.v) <= MAX_GRAPH_VERTICES
        self._adj: list[list[tuple[int, float]]] | None = None

    def crosses_gap(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        import shapely
        from shapely.geometry import LineString
        if self.gap_tree is None or math.dist(a, b) < 1e-9:
            return False
        seg = LineString([a, b])
        hits = self.gap_tree.query(seg, predicate="intersects")
        if len(hits) == 0:
            return False
        # length inside the gaps, sampled (an exact overlay costs ~1 ms per segment on a jagged boundary)
        L = seg.length
        n = int(min(400, max(20, L / 0.5)))
        t = (np.arange(n) + 0.5) / n
        xs = a[0] + (b[0] - a[0]) * t
        ys = a[1] + (b[1] - a[1]) * t
        inside = np.zeros(n, bool)
        for i in hits.tolist():
            inside |= shapely.contains_xy(self.gap_pieces[i], xs, ys)
        return inside.mean() * L > max(0.5, 0.02 * L)

    def _visible(self, a: np.ndarray, bs: np.ndarray) -> np.ndarray:
        import shapely
        if len(bs) == 0:
            return np.zeros(0, bool)
        segs = shapely.linestrings(np.stack([np.broadcast_to(a, bs.shape), bs], axis=1))
        return shapely.covers(self.region, segs)

    def _graph(self) -> list[list[tuple[int, float]]]:
        import shapely
        if self._adj is None:
            n = len(self.v)
            adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
            ii, jj = np.triu_indices(n, 1)
            if len(ii):
                segs = shapely.linestrings(np.stack([self.v[ii], self.v[jj]], axis=1))
                vis = shapely.covers(self.region, segs)
                for i, j in zip(ii[vis].tolist(), jj[vis].tolist()):
                    w = float(np.hypot(*(self.v[i] - self.v[j])))
                    adj[i].append((j, w))
                    adj[j].append((i, w))
            self._adj = adj
        return self._adj

    def _anchor(self, p: tuple[float, float]) -> tuple[np.ndarray, list[tuple[float, float]]]:
        from shapely.geometry import Point
        from shapely.ops import nearest_points
        P = Point(p)
        if self.region.covers(P):
            return np.asarray(p, float), []
        q = nearest_points(self.poly, P)[0]
        return np.asarray((q.x, q.y), float), [(q.x, q.y)]

    def path(self, a: tuple[float, float], b: tuple[float, float]) -> list[tuple[float, float]] | None:
        """Intermediate points of the shortest inside path a→b ([] if direct), None if not possible.
        An end outside the area (an extended leg end) is first joined to its nearest boundary point."""
        A, pre = self._anchor(a)
        B, post = self._anchor(b)
        if self._visible(A, B[None, :])[0]:
            return pre + post
        if not self.ok:
            return None
        adj = self._graph()
        n = len(self.v)
        va = self._visible(A, self.v)
        vb = self._visible(B, self.v)
        if not va.any() or not vb.any():
            return None
        dist = np.full(n, np.inf)
        prev = np.full(n, -1)
        heap: list[tuple[float, int]] = []
        for i in np.nonzero(va)[0].tolist():
            dist[i] = float(np.hypot(*(self.v[i] - A)))
            heapq.heappush(heap, (dist[i], i))
        db = np.hypot(self.v[:, 0] - B[0], self.v[:, 1] - B[1])
        best, best_i = math.inf, -1
        while heap:
            dcur, i = heapq.heappop(heap)
            if dcur > dist[i] or dcur >= best:
                continue
            if vb[i] and dcur + db[i] < best:
                best, best_i = dcur + db[i], i
            for j, w in adj[i]:
                nd = dcur + w
                if nd < dist[j]:
                    dist[j] = nd
                    prev[j] = i
                    heapq.heappush(heap, (nd, j))
        if best_i < 0:
            return None
        out = []
        i = best_i
        while i >= 0:
            out.append((float(self.v[i][0]), float(self.v[i][1])))
            i = int(prev[i])
        return pre + out[::-1] + post


class _Avoid:
    """The zones a route keeps out of: how far a stub may go, how much of a hop crosses them, and the shortest
    way around them (visibility graph over free space: a box around everything less the zones)."""

    def __init__(self, zones: Any, around: Any) -> None:
        import shapely
        self.zones = zones
        shapely.prepare(zones)
        # their interior: a hop along a zone's edge is beside it, not in it
        self.core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
        shapely.prepare(self.core)
        self.around = around
        # detours keep their clearance from the zones (a zone's edge is often the area's boundary)
        self.keep_out = zones.buffer(_AVOID_CLEARANCE_M, join_style="mitre")
        self._free: _InsidePaths | None | bool = False

    def clear_length(self, p: tuple[float, float], d: tuple[float, float], length: float) -> float:
        """How far from p along unit vector d (at most `length`) stays out of the zones, less the clearance."""
        from shapely.geometry import LineString, Point
        if length <= 0:
            return 0.0
        seg = LineString([p, (p[0] + d[0] * length, p[1] + d[1] * length)])
        if not self.zones.intersects(seg):
            return length
        hit = Point(p).distance(seg.intersection(self.zones))
        return max(0.0, hit - _AVOID_CLEARANCE_M)

    def crossing_m(self, p: tuple[float, float], q: tuple[float, float]) -> float:
        """Metres of the hop p→q inside the zones beyond what its ends force: an end that is itself inside (an
        exit point a metre past the last photo) has to get out, and that much does not count."""
        from shapely.geometry import LineString, Point
        if math.dist(p, q) < 1e-9:
            return 0.0
        seg = LineString([p, q])
        if not self.core.intersects(seg):
            return 0.0
        inside = seg.intersection(self.core).length
        for e in (p, q):
            P = Point(e)
            if self.core.contains(P):
                inside -= self.core.boundary.distance(P)
        return max(0.0, inside)

    def path(self, a: tuple[float, float], b: tuple[float, float]) -> list[tuple[float, float]] | None:
        """Intermediate points of the shortest way a→b around the zones, None when there is none to offer."""
        if self._free is False:
            from shapely.geometry import box
            x0, y0, x1, y1 = self.around.union(self.zones.envelope).bounds
            free = box(x0 - 50.0, y0 - 50.0, x1 + 50.0, y1 + 50.0).difference(self.keep_out)
            # a zone that encloses ground (a ring) splits free space: no single graph joins both sides
            self._free = _InsidePaths(free) if free.geom_type == "Polygon" else None
        if self._free is None:
            return None
        return self._free.path(a, b)  # type: ignore[union-attr]


class _LegEnds(NamedTuple):
    """A leg as flown: from `entry` to `end` (its first and last photos) heading (dx, dy), the camera off at `exit`,
    the exit margin beyond the end."""

    entry: tuple[float, float]
    end: tuple[float, float]
    dx: float
    dy: float
    exit: tuple[float, float]

    @classmethod
    def of(cls, leg: Leg, rev: bool, exit_margin_m: float, exit_stretch: float = 0.0) -> "_LegEnds":
        """`exit_stretch`: the exit also lies that fraction of the leg's length further on (a firmware whose
        photos come on average further apart than the trigger distance reaches the last one that much later)."""
        (ax, ay), (bx, by) = _ends(leg, rev)
        d, _n = frame(leg.angle_deg)
        dx, dy = (-d[0], -d[1]) if rev else (d[0], d[1])
        m = exit_margin_m + exit_stretch * math.hypot(bx - ax, by - ay)
        return cls((ax, ay), (bx, by), dx, dy, (bx + dx * m, by + dy * m))

    @property
    def margin_m(self) -> float:
        return math.hypot(self.exit[0] - self.end[0], self.exit[1] - self.end[1])

    def before(self, m: float) -> tuple[float, float]:
        """The point `m` metres before the entry, on the line."""
        return (self.entry[0] - self.dx * m, self.entry[1] - self.dy * m)

    def beyond(self, m: float) -> tuple[float, float]:
        """The point `m` metres beyond the end, on the line."""
        return (self.end[0] + self.dx * m, self.end[1] + self.dy * m)


class _Ways:
    """How a route may get from one leg to the next: the shortest paths inside each polygon part (built on first
    use) and the zones it keeps out of (None without any)."""

    def __init__(self, geometry: Any, avoid: Any) -> None:
        self.parts = list(geometry.geoms) if geometry.geom_type == "MultiPolygon" else [geometry]
        self.zones = _Avoid(avoid, geometry) if avoid is not None and not avoid.is_empty else None
        self._inside: dict[int, _InsidePaths] = {}

    def inside(self, part: int) -> _InsidePaths:
        if part not in self._inside:
            self._inside[part] = _InsidePaths(self.parts[part], self.zones.keep_out if self.zones is not None else None)
        return self._inside[part]

    def stub_before_m(self, ends: _LegEnds, turnaround_m: float) -> float:
        """Length of the turnaround stub before the entry: cut short where it would enter a zone, none when less
        than MIN_STUB_M would be left."""
        if self.zones is None or turnaround_m <= 0:
            return turnaround_m
        m = self.zones.clear_length(ends.entry, (-ends.dx, -ends.dy), turnaround_m)
        return 0.0 if m < min(turnaround_m, MIN_STUB_M) else m

    def stub_after_m(self, ends: _LegEnds, turnaround_m: float, exit_margin_m: float) -> float:
        """Length of the turnaround stub beyond the end (it counts only beyond the exit), cut short likewise."""
        if self.zones is None or turnaround_m <= exit_margin_m:
            return turnaround_m
        m = self.zones.clear_length(ends.end, (ends.dx, ends.dy), turnaround_m)
        return 0.0 if m < min(turnaround_m, exit_margin_m + MIN_STUB_M) else m


class _RouteBuilder:
    """The route's points as its legs are added in flying order (see module doc, steps 3-5)."""

    def __init__(self, ways: _Ways, turnaround_m: float, exit_margin_m: float, exit_stretch: float = 0.0) -> None:
        self.ways = ways
        self.turnaround_m = turnaround_m
        self.exit_margin_m = exit_margin_m
        self.exit_stretch = exit_stretch
        self.points: list[RoutePoint] = []
        self.spans: list[CameraSpan] = []
        self.flown: list[Leg] = []
        self.reversed: list[bool] = []
        self.last_exit: tuple[float, float] | None = None

    def add(self, leg: Leg, rev: bool) -> None:
        """Stub in, entry, exit, stub out, after whatever connection the previous leg's exit needs."""
        ends = _LegEnds.of(leg, rev, self.exit_margin_m, self.exit_stretch)
        k = len(self.flown)
        stub_in = self.ways.stub_before_m(ends, self.turnaround_m)
        stubs = self._connect(leg, ends, stub_in, self.last_exit) if self.last_exit is not None else stub_in > 0
        pts = self.points
        if stubs:
            pts.append(RoutePoint(*ends.before(stub_in), KIND_TURN_IN, k))
        pts.append(RoutePoint(*ends.entry, KIND_ENTRY, k))
        pts.append(RoutePoint(*ends.exit, KIND_EXIT, k))
        self.spans.append(CameraSpan(len(pts) - 2, len(pts) - 1))
        margin = ends.margin_m if self.exit_stretch else self.exit_margin_m
        stub_out = self.ways.stub_after_m(ends, self.turnaround_m, margin)
        if stub_out > margin:
            pts.append(RoutePoint(*ends.beyond(stub_out), KIND_TURN_IN, k))
        self.flown.append(leg)
        self.reversed.append(rev)
        self.last_exit = ends.exit

    def route(self) -> Route:
        return Route(tuple(self.points), tuple(self.flown), tuple(self.reversed), tuple(self.spans))

    def _connect(self, leg: Leg, ends: _LegEnds, stub_in: float, prev_exit: tuple[float, float]) -> bool:
        """Join the previous leg's exit to this leg's entry; whether the stub before the entry is kept."""
        prev = self.flown[-1]
        if prev.part == leg.part and self._detour_inside(leg.part, prev_exit, ends.entry):
            return False
        if self.ways.zones is not None:
            return self._keep_out_of_zones(leg, prev.part, prev_exit, ends, stub_in)
        return stub_in > 0

    def _detour_inside(self, part: int, prev_exit: tuple[float, float], entry: tuple[float, float]) -> bool:
        """Where the straight hop crosses a hole or notch of the part: a detour inside it, without the turnaround
        stubs (which would leave the area). Whether it was taken."""
        inside = self.ways.inside(part)
        if not inside.crosses_gap(prev_exit, entry):
            return False
        via = inside.path(prev_exit, entry)
        if via is None:
            return False
        self._drop_last_stub()
        self.points.extend(RoutePoint(x, y, KIND_VIA) for x, y in via)
        return True

    def _keep_out_of_zones(self, leg: Leg, prev_part: int, prev_exit: tuple[float, float], ends: _LegEnds,
                           stub_in: float) -> bool:
        """Where the hop between the stubs crosses a zone: without them, and around the zone when the hop from
        exit to entry still crosses it (inside the part when both legs are in one, else through free space).
        Whether the stub before the entry is kept."""
        zones = self.ways.zones
        assert zones is not None
        last = (self.points[-1].x, self.points[-1].y)
        start = ends.before(stub_in) if stub_in > 0 else ends.entry
        if zones.crossing_m(last, start) <= ZONE_EDGE_TOL_M:
            return stub_in > 0
        self._drop_last_stub()
        if zones.crossing_m(prev_exit, ends.entry) > ZONE_EDGE_TOL_M:
            via = self.ways.inside(leg.part).path(prev_exit, ends.entry) if prev_part == leg.part else None
            if via is None:
                via = zones.path(prev_exit, ends.entry)
            self.points.extend(RoutePoint(x, y, KIND_VIA) for x, y in via or [])
        return False

    def _drop_last_stub(self) -> None:
        """The turnaround stub after the previous leg, if it has one."""
        pts = self.points
        if pts and pts[-1].kind == KIND_TURN_IN and pts[-1].leg == len(self.flown) - 1:
            pts.pop()


def build_route(legs: Sequence[Leg], geometry: Any, turnaround_m: float, exit_margin_m: float = 0.0,
                start_xy: tuple[float, float] | None = None, order: Sequence[FlownLeg] | None = None,
                avoid: Any = None, exit_stretch: float = 0.0) -> Route:
    """Waypoints for the legs in flying order (see module doc). `geometry` is the area (metres).
    `exit_stretch`: see _LegEnds.of.
    (Hover surveys fly this route with photo stops in place of each leg's entry and exit: survey._hover_route.)

    `avoid`: holes and exclusion zones (shapely, metres) the stubs and connections keep out of (step 5).
    """
    if order is None:
        order = order_legs(legs, start_xy)
    builder = _RouteBuilder(_Ways(geometry, avoid), max(0.0, turnaround_m), max(0.0, exit_margin_m),
                            max(0.0, exit_stretch))
    for li, rev in order:
        builder.add(legs[li], rev)
    return builder.route()
