"""Zones a plan keeps clear of: `no_fly`, `no_photo` and `exclude` (both), declared on survey and corridor steps.

    zones = plan_zones(plan)                     # every zone of the plan, with its kind (reads the zone files)
    [z for z in zones if z.keeps_path_out]       # the path, transits and turnarounds stay out
    [z for z in zones if z.keeps_photos_out]     # no photo footprint touches them (grown by z.margin_m)

A zone holds for the whole flight, whichever step declares it: transits, other steps' lines and waypoint captures
keep clear of it too. `margin_m` (the step's `zone_margin_m`, default DEFAULT_ZONE_MARGIN_M) is the position error
allowed for: a footprint must stay that far from a no-photo zone, lines stay that far from a no-fly zone.

Photos (`keep_photos_out`): a footprint is the rectangle the report places (missions.measure.report.footprint_ring:
the payload's footprint at the track's altitude, along the direction of travel). Along every camera-on span the
stretches where a photo's footprint would reach a zone grown by the margin are found exactly (the zone's Minkowski
sum with the footprint rectangle, intersected with each straight piece of the span), and the span is split around
them: the camera goes off (DO_SET_CAM_TRIGG_DIST 0 on both firmwares: ArduPilot's AP_Camera stops distance
triggering and forgets its reference position; PX4's camera_trigger pauses) at the last good position and on again
(DO_SET_CAM_TRIGG_DIST d with "shoot now": ArduPilot takes a picture and measures the next from there; PX4 resumes
with a fresh reference position and one shot) RESUME_MARGIN_M past the first good position, because both execute a
DO item once the waypoint before it is accepted, which ArduCopter does up to WPNAV_RADIUS (2 m) early. A hover stop
whose footprint, at any heading, could reach such a zone is dropped (flown through without a photo).

The path (`keep_path_out`, `area_clear_of`): a survey's lines are laid on its area less the no-fly and exclude zones
grown by their margin; a camera-on stretch its photo grid extends into one ends at it, points inside are left out,
and every hop that would cross one goes round it (`ZoneRouter`). Transits (`TransitRouter`: to the first line,
between steps, home): the straight way, or when it crosses a grown no-fly or exclude zone, the shortest way round
them (visibility graph over the grown zones' vertices, route._InsidePaths). A zone that cannot be avoided (an end
inside it, or no way round) is a PlanError naming it.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np

from missions.errors import PlanError
from missions.geometry.area import LatLonPolygon, build_area, read_area_source
from missions.geometry.footprint import Footprint
from missions.geometry.geo import LocalProjection, leaf_parts
from missions.geometry.route import ZONE_EDGE_TOL_M, _InsidePaths
from missions.geometry.survey import DEFAULT_EXIT_MARGIN_M
from missions.plan.schema import ZONE_KINDS
from missions.plan.types import CorridorStep, Plan, SurveyStep

DEFAULT_ZONE_MARGIN_M = 2.0
# The camera comes on this far past the first position whose photo keeps clear of the zones: a DO item after a
# waypoint runs when the waypoint is accepted, up to WPNAV_RADIUS (ArduCopter's default 2 m) before it (the same
# allowance as the exit margin a leg's last photo is kept by; PX4's NAV_ACC_RAD is 2 m too), plus the travel of
# one 50 ms trigger check at survey speed (PX4's camera_trigger and ArduPilot's camera library shoot at the first
# check past their mark, missions.measure.flight): 0.5 m holds up to 10 m/s.
RESUME_MARGIN_M = DEFAULT_EXIT_MARGIN_M + 0.5
# A transit is routed around zones within this of its straight line (farther ones cannot be in the way of the
# shortest path round the near ones by much, and a smaller graph keeps routing fast).
_TRANSIT_CORRIDOR_M = 2_000.0
# Zones this close to a survey area shape its lines and turnarounds (farther ones only its transits).
_NEAR_AREA_M = 1_000.0
# Free space for a detour: the box around the ends and the zones, this much bigger on every side.
_DETOUR_BOX_M = 100.0
# A zone of more vertices is routed round a simpler outline containing it (_routable), by this much.
_ROUTE_VERTICES = 60
_SIMPLIFY_M = 1.0
# A way round is taken this much outside the grown zones, so that a path along one's edge is beside it.
_ROUTE_CLEARANCE_M = 0.1


@dataclass(frozen=True)
class Zone:
    """One zone polygon as the plan gives it: its kind, a name for messages and reports, and where it is written."""

    kind: str                  # "no_fly" | "no_photo" | "exclude"
    name: str                  # the file (with #k when it holds several polygons) or the step's inline entry
    polygon: LatLonPolygon
    step: int                  # the mission step that declares it
    where: str                 # file:line:col of its entry in the plan
    margin_m: float = DEFAULT_ZONE_MARGIN_M

    @property
    def keeps_path_out(self) -> bool:
        return self.kind in ("no_fly", "exclude")

    @property
    def keeps_photos_out(self) -> bool:
        return self.kind in ("no_photo", "exclude")

    @property
    def label(self) -> str:
        """How messages name it: `no_fly zone 'tower.geojson' (plan.yaml:12:7)`."""
        return f"{self.kind} zone '{self.name}' ({self.where})"

    def xy(self, proj: LocalProjection) -> Any:
        """The zone as drawn, a shapely Polygon in metres of `proj` (cleaned and checked like an area)."""
        return build_area([self.polygon], source=self.where, projection=proj).geometry


def step_margin_m(step: SurveyStep | CorridorStep) -> float:
    return DEFAULT_ZONE_MARGIN_M if step.zone_margin_m is None else float(step.zone_margin_m)


def plan_zones(plan: Plan) -> tuple[Zone, ...]:
    """Every zone of the plan with its kind, in plan order (reads the zone files; a bad one is a located
    PlanError). What the .plan's geoFence and the report's zone table are written from."""
    out: list[Zone] = []
    for step in plan.mission:
        if not isinstance(step, (SurveyStep, CorridorStep)):
            continue
        margin = step_margin_m(step)
        for kind in ZONE_KINDS:
            for j, src in enumerate(getattr(step, kind)):
                where = plan.step_where(step, kind, j)
                polys = read_area_source(src, plan.base_dir, where)
                base = src if isinstance(src, str) else f"step {step.index} {kind}[{j}]"
                for k, poly in enumerate(polys):
                    name = base if len(polys) == 1 else f"{base} #{k + 1}"
                    out.append(Zone(kind, name, poly, step.index, where, margin))
    return tuple(out)


@dataclass(frozen=True)
class PlacedZone:
    """A zone in one projection's metres: as drawn, and grown by its margin."""

    zone: Zone
    drawn: Any
    grown: Any


def place_zones(zones: Sequence[Zone], proj: LocalProjection) -> tuple[PlacedZone, ...]:
    out = []
    for z in zones:
        g = z.xy(proj)
        out.append(PlacedZone(z, g, g.buffer(z.margin_m, join_style="mitre") if z.margin_m > 0 else g))
    return tuple(out)


def grown_union(placed: Sequence[PlacedZone]) -> Any:
    """The zones grown by their margins, as one geometry (empty when there are none)."""
    return _union([z.grown for z in placed])


@dataclass(frozen=True)
class StepZones:
    """The zones the report measures a survey or corridor step against (AreaInfo.zones): those within `reach_m`
    (the step's largest footprint side) of its area, whichever step declares them."""

    zones: tuple[Zone, ...]
    reach_m: float


def zones_near(zones: Sequence[Zone], area: Any, reach_m: float) -> tuple[Zone, ...]:
    """The zones that a footprint of a photo over `area` (an Area), or its margin, could reach."""
    drawn = area.drawn if area.drawn is not None else area.geometry
    return tuple(z for z in zones if z.xy(area.projection).distance(drawn) <= reach_m + z.margin_m)


def _union(geoms: Sequence[Any]) -> Any:
    import shapely
    from shapely.geometry import Polygon
    return shapely.union_all(list(geoms)) if geoms else Polygon()


def area_clear_of(source: Any, zones: Sequence[Zone], base_dir: Any, where: str) -> Any:
    """A survey's area (missions.geometry.area.Area) less the no-fly and exclude zones near it, grown by their
    margin (the largest of theirs): its lines, turnarounds and connections keep out of them. `Area.drawn` keeps
    the area as drawn."""
    polys = read_area_source(source, base_dir, where)
    label = str(source) if isinstance(source, str) else where
    plain = build_area(polys, (), label)
    near = [z for z in zones if z.keeps_path_out
            and z.xy(plain.projection).distance(plain.geometry) < _NEAR_AREA_M]
    if not near:
        return plain
    return build_area(polys, [z.polygon for z in near], label, plain.projection,
                      margin_m=max(z.margin_m for z in near))


# ------------------------------------------------------------------------------------------------- photos

class CameraPoint(NamedTuple):
    """A point of a camera track in metres: kind as the emitter names it (entry/exit/turnaround/via/photo)."""

    x: float
    y: float
    kind: str
    yaw_deg: float | None = None


class CameraPlan(NamedTuple):
    """A track with its camera kept off near the no-photo zones: the points, the camera-on spans (index pairs) and
    what changed (camera-off stretches added, hover photos dropped)."""

    points: tuple[CameraPoint, ...]
    spans: tuple[tuple[int, int], ...]
    stretches_off: int
    photos_dropped: int


def _rect(fp: Footprint, heading_deg: float) -> np.ndarray:
    """The footprint's corners (4 x 2) centred on the origin, the along side on the heading."""
    h = math.radians(heading_deg)
    d = np.array([math.sin(h), math.cos(h)]) * fp.along_m / 2.0
    n = np.array([math.cos(h), -math.sin(h)]) * fp.across_m / 2.0
    return np.array([-d - n, d - n, d + n, -d + n])


def reach_of(zone: Any, fp: Footprint, heading_deg: float) -> Any:
    """Where a photo centre puts its footprint (heading `heading_deg`) on `zone`: the zone's Minkowski sum with the
    footprint rectangle (symmetric, so no reflection): the zone and every edge swept by the rectangle."""
    import shapely
    corners = _rect(fp, heading_deg)
    hulls = []
    for poly in leaf_parts(zone, "Polygon"):
        for ring in (poly.exterior, *poly.interiors):
            xy = np.asarray(ring.coords)
            pts = np.concatenate([xy[:-1, None, :] + corners[None], xy[1:, None, :] + corners[None]], axis=1)
            hulls.append(shapely.convex_hull(shapely.multipoints(pts)))
    return _union([zone, *np.concatenate(hulls).tolist()]) if hulls else zone


def _bad_stretches(seg_a: np.ndarray, seg_b: np.ndarray, reach: Any) -> list[tuple[float, float]]:
    """[t0, t1] (metres from seg_a) of the straight piece seg_a -> seg_b inside `reach`."""
    from shapely.geometry import LineString
    L = float(np.hypot(*(seg_b - seg_a)))
    if L < 1e-9:
        return []
    u = (seg_b - seg_a) / L
    cut = LineString([seg_a, seg_b]).intersection(reach)
    out = []
    for part in (*leaf_parts(cut, "LineString"), *leaf_parts(cut, "Point")):
        t = (np.asarray(part.coords) - seg_a) @ u
        out.append((max(0.0, float(t.min())), min(L, float(t.max()))))
    return out


def _merge(intervals: list[tuple[float, float]]) -> list[tuple[float, float]]:
    out: list[tuple[float, float]] = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1] + 1e-9:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


class _Polyline:
    """A span's points by distance along them."""

    def __init__(self, xy: np.ndarray) -> None:
        self.xy = xy
        self.s = np.concatenate([[0.0], np.cumsum(np.hypot(*(xy[1:] - xy[:-1]).T))])

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def at(self, s: float) -> np.ndarray:
        k = int(np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.s) - 2))
        L = self.s[k + 1] - self.s[k]
        t = 0.0 if L < 1e-12 else (s - self.s[k]) / L
        return self.xy[k] + (self.xy[k + 1] - self.xy[k]) * t


def _complement(bad: list[tuple[float, float]], length: float) -> list[tuple[float, float]]:
    """[0, length] less the stretches `bad`, in order (a stretch of no length, a touch, takes nothing away)."""
    bad = [(a, b) for a, b in bad if b - a > 1e-6]
    good, pos = [], 0.0
    for a, b in _merge(bad):
        if a > pos + 1e-6:
            good.append((pos, a))
        pos = max(pos, b)
    if pos < length - 1e-6 or not bad:
        good.append((pos, length))
    return good


class _Reach:
    """`reach_of` the forbidden ground by footprint heading, each computed once (a survey's lines share a few)."""

    def __init__(self, forbidden: Any, fp: Footprint) -> None:
        self.forbidden = forbidden
        self.fp = fp
        self.half_diag = math.hypot(fp.across_m, fp.along_m) / 2.0
        self.by_heading: dict[float, Any] = {}

    def of(self, heading_deg: float) -> Any:
        h = round(heading_deg % 180.0, 6)      # the rectangle is symmetric: a heading and its reverse alike
        if h not in self.by_heading:
            self.by_heading[h] = reach_of(self.forbidden, self.fp, h)
        return self.by_heading[h]


def _good_stretches(line: _Polyline, reach: _Reach) -> list[tuple[float, float]]:
    """[s0, s1] of the span where every photo's footprint keeps clear of the forbidden ground (distance along it)."""
    import shapely
    from shapely.geometry import LineString
    bad: list[tuple[float, float]] = []
    for k in range(len(line.xy) - 1):
        a, b = line.xy[k], line.xy[k + 1]
        if np.hypot(*(b - a)) < 1e-9 or not shapely.dwithin(LineString([a, b]), reach.forbidden, reach.half_diag):
            continue
        heading = math.degrees(math.atan2(b[0] - a[0], b[1] - a[1]))
        bad.extend((line.s[k] + t0, line.s[k] + t1) for t0, t1 in _bad_stretches(a, b, reach.of(heading)))
    return _complement(bad, line.length)


def _camera_on_stretches(line: _Polyline, good: list[tuple[float, float]], trigger_m: float,
                         exit_margin_m: float) -> list[tuple[float, float]]:
    """Where the camera runs within each good stretch: from its start (RESUME_MARGIN_M later where the camera comes
    back on after a zone) to its end (or exit_margin_m past its last photo where it goes off before a zone)."""
    out = []
    for a, b in good:
        on = a if a <= 1e-9 else a + RESUME_MARGIN_M
        if on >= b - 1e-6:         # too short for a photo clear of the zones on both sides
            continue
        off = b
        if b < line.length - 1e-9 and trigger_m > 0:
            last = on + math.floor((b - on) / trigger_m + 1e-9) * trigger_m
            off = min(b, last + exit_margin_m)
        out.append((on, off))
    return out


def keep_photos_out(points: Sequence[CameraPoint], spans: Sequence[tuple[int, int]], forbidden: Any,
                    fp: Footprint, trigger_m: float, hover: bool) -> CameraPlan:
    """`points`/`spans` (a track in metres) with the camera off wherever a photo's footprint `fp` would reach
    `forbidden` (the no-photo and exclude zones grown by their margin, in the track's metres); see the module doc."""
    if forbidden.is_empty:
        return CameraPlan(tuple(points), tuple(spans), 0, 0)
    if hover:
        return _hover_photos_out(points, spans, forbidden, fp)
    exit_margin = min(DEFAULT_EXIT_MARGIN_M, 0.45 * trigger_m)
    reach = _Reach(forbidden, fp)

    def camera_on(line: _Polyline) -> list[tuple[float, float]] | None:
        on = _camera_on_stretches(line, _good_stretches(line, reach), trigger_m, exit_margin)
        return None if on == [(0.0, line.length)] else on

    out, new_spans, added = _walk_spans(points, spans, camera_on)
    return CameraPlan(tuple(out), tuple(new_spans), added, 0)


def _walk_spans(points: Sequence[CameraPoint], spans: Sequence[tuple[int, int]],
                camera_on: Callable[[_Polyline], list[tuple[float, float]] | None],
                ) -> tuple[list[CameraPoint], list[tuple[int, int]], int]:
    """The track with each camera-on span cut to the stretches `camera_on` gives for its line (distances along it;
    None: the span is kept whole), its points outside spans kept; and how many camera-off stretches the cut spans
    now have (`_split_span`)."""
    starts = {a: b for a, b in spans}
    out: list[CameraPoint] = []
    new_spans: list[tuple[int, int]] = []
    added = 0
    i = 0
    while i < len(points):
        if i not in starts:
            out.append(points[i])
            i += 1
            continue
        a, b = i, starts[i]
        seg = points[a:b + 1]
        line = _Polyline(np.array([(p.x, p.y) for p in seg], dtype=float))
        on = camera_on(line)
        if on is None:
            new_spans.append((len(out), len(out) + b - a))
            out.extend(seg)
        else:
            added += _split_span(seg, line, on, out, new_spans)
        i = b + 1
    return out, new_spans, added


def _split_span(seg: Sequence[CameraPoint], line: _Polyline, on: list[tuple[float, float]],
                out: list[CameraPoint], spans: list[tuple[int, int]]) -> int:
    """Append the span's points with the camera-on stretches `on` (distances along it, in order, apart) as entry
    and exit points of their own; the span's own entry and exit become vias where the camera is off there.
    Returns how many camera-off stretches the span now has."""
    marks = [m for a, b in on for m in ((a, "entry"), (b, "exit"))]
    m = 0
    for k, p in enumerate(seg):
        while m < len(marks) and marks[m][0] < line.s[k] - 1e-6:
            x, y = line.at(marks[m][0])
            _mark(out, spans, CameraPoint(float(x), float(y), marks[m][1]))
            m += 1
        if m < len(marks) and abs(marks[m][0] - line.s[k]) <= 1e-6:
            _mark(out, spans, p._replace(kind=marks[m][1]))
            m += 1
        else:
            out.append(p._replace(kind="via") if p.kind in ("entry", "exit") else p)
    if not on:
        return 1
    return len(on) + 1 - (on[0][0] <= 1e-9) - (on[-1][1] >= line.length - 1e-9)


def _mark(out: list[CameraPoint], spans: list[tuple[int, int]], p: CameraPoint) -> None:
    """Append an entry (a span opens) or an exit (it closes)."""
    if p.kind == "entry":
        spans.append((len(out), -1))
    else:
        spans[-1] = (spans[-1][0], len(out))
    out.append(p)


def _hover_photos_out(points: Sequence[CameraPoint], spans: Sequence[tuple[int, int]], forbidden: Any,
                      fp: Footprint) -> CameraPlan:
    """Hover stops whose footprint could reach `forbidden` at any heading become vias (no photo)."""
    import shapely
    half_diag = math.hypot(fp.across_m, fp.along_m) / 2.0
    xy = np.array([(p.x, p.y) for p in points], dtype=float).reshape(-1, 2)
    near = shapely.dwithin(shapely.points(xy), forbidden, half_diag) if len(xy) else np.zeros(0, bool)
    out, dropped = [], 0
    for p, hit in zip(points, near.tolist()):
        if p.kind == "photo" and hit:
            out.append(p._replace(kind="via", yaw_deg=None))
            dropped += 1
        else:
            out.append(p)
    return CameraPlan(tuple(out), tuple(spans), 0, dropped)


def capture_reaches(x: float, y: float, forbidden: Any, fp: Footprint) -> bool:
    """Whether a single photo at (x, y), at whatever heading the vehicle holds, could see `forbidden`."""
    from shapely.geometry import Point
    return not forbidden.is_empty and Point(x, y).distance(forbidden) < math.hypot(fp.across_m, fp.along_m) / 2.0


# ------------------------------------------------------------------------------------------------- the path

def path_inside(xy: np.ndarray, zones: Sequence[PlacedZone]) -> list[tuple[PlacedZone, float]]:
    """(zone, metres) for each zone the polyline `xy` runs inside of (deeper than route.ZONE_EDGE_TOL_M), as drawn."""
    import shapely
    if len(xy) < 2:
        return []
    segs = shapely.linestrings(np.stack([xy[:-1], xy[1:]], axis=1))
    out = []
    for z in zones:
        core = z.drawn.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
        m = float(shapely.length(shapely.intersection(segs, core)).sum())
        if m > 0.0:
            out.append((z, m))
    return out


def _routable(grown: Any) -> Any:
    """`grown`, or for a zone of many vertices (a circle drawn as hundreds of points) a simpler outline that
    contains it (simplified by 1 m, grown by 1 m): the way-round graph holds a few hundred vertices at most."""
    n = sum(len(r.coords) for p in leaf_parts(grown, "Polygon") for r in (p.exterior, *p.interiors))
    if n <= _ROUTE_VERTICES:
        return grown
    return grown.simplify(_SIMPLIFY_M).buffer(_SIMPLIFY_M, join_style="mitre")


class ZoneRouter:
    """The shortest way between two points round no-fly and exclude zones placed in one projection's metres."""

    def __init__(self, placed: Sequence[PlacedZone]) -> None:
        self.zones = [z for z in placed if z.zone.keeps_path_out]

    def way_round(self, a: tuple[float, float], b: tuple[float, float], what: str,
                  where: str | None) -> list[tuple[float, float]]:
        """The points between a and b of the shortest way round the zones grown by their margin ([] when the
        straight way keeps clear of them). An end inside a zone as drawn, or no way round, is a PlanError."""
        if not self.zones:
            return []
        from shapely.geometry import LineString, Point
        for end, verb in ((a, "starts"), (b, "ends")):
            for z in self.zones:
                if z.drawn.buffer(-ZONE_EDGE_TOL_M).contains(Point(end)):
                    raise PlanError(f"the {what} {verb} inside {z.zone.label}", where=where,
                                    hint="move the point out of the zone, or redraw the zone")
        straight = LineString([a, b])
        if not any(z.grown.buffer(-ZONE_EDGE_TOL_M).intersects(straight) for z in self.zones):
            return []
        near = [z for z in self.zones if z.grown.distance(straight) < _TRANSIT_CORRIDOR_M]
        # a way round the near zones may run into a farther one: then route round that one too
        while True:
            path = self._around(a, b, near, what, where)
            way = LineString([a, *path, b])
            more = [z for z in self.zones if z not in near and z.grown.buffer(-ZONE_EDGE_TOL_M).intersects(way)]
            if not more:
                return path
            near += more

    @staticmethod
    def _around(a: tuple[float, float], b: tuple[float, float], near: list[PlacedZone], what: str,
                where: str | None) -> list[tuple[float, float]]:
        from shapely.geometry import LineString, Point, box
        keep_out = _union([_routable(z.grown).buffer(_ROUTE_CLEARANCE_M, join_style="mitre") for z in near])
        x0, y0, x1, y1 = keep_out.union(LineString([a, b])).bounds
        free = box(x0 - _DETOUR_BOX_M, y0 - _DETOUR_BOX_M, x1 + _DETOUR_BOX_M, y1 + _DETOUR_BOX_M).difference(keep_out)
        # the free piece nearest both ends (a zone ring or touching zones can enclose ground); an end within the
        # margin is joined to it straight (it is outside the zone as drawn)
        pieces = list(leaf_parts(free, "Polygon"))
        pa = min(pieces, key=lambda g: g.distance(Point(a)), default=None)
        pb = min(pieces, key=lambda g: g.distance(Point(b)), default=None)
        path = _InsidePaths(pa).path(a, b) if pa is not None and pa is pb else None
        if path is None:
            blocking = [z for z in near if z.grown.intersects(LineString([a, b]))] or near
            names = ", ".join(z.zone.label for z in blocking)
            raise PlanError(f"the {what} cannot be routed around {names}", where=where,
                            hint="leave a way round the zone (zones that touch or enclose ground close it), "
                                 "simplify the zone (at most a few hundred vertices), or move the step")
        return path


class TransitRouter:
    """Transits round the plan's no-fly and exclude zones, in one projection (the plan's home)."""

    def __init__(self, zones: Sequence[Zone], proj: LocalProjection) -> None:
        self.proj = proj
        self.router = ZoneRouter(place_zones([z for z in zones if z.keeps_path_out], proj))

    def route(self, a_ll: tuple[float, float], b_ll: tuple[float, float], what: str,
              where: str | None) -> list[tuple[float, float]]:
        """The (lat, lon) points between a and b of the shortest way round the zones ([] when straight is clear)."""
        if not self.router.zones:
            return []
        a = tuple(float(v) for v in self.proj.point_to_xy(*a_ll))
        b = tuple(float(v) for v in self.proj.point_to_xy(*b_ll))
        xy = self.router.way_round(a, b, what, where)  # type: ignore[arg-type]
        if not xy:
            return []
        lat, lon = self.proj.to_latlon([p[0] for p in xy], [p[1] for p in xy])
        return list(zip(np.asarray(lat).tolist(), np.asarray(lon).tolist()))


def keep_path_out(points: Sequence[CameraPoint], spans: Sequence[tuple[int, int]], router: ZoneRouter,
                  what: str, where: str | None) -> CameraPlan:
    """`points`/`spans` (a step's track in metres) kept out of the router's no-fly and exclude zones grown by their
    margin: a camera-on stretch that runs into one (a leg extended past the area's edge to finish its photo grid)
    ends at the zone, points inside are left out (a hover photo there is dropped), and every hop that would cross
    a zone goes round it."""
    if not router.zones:
        return CameraPlan(tuple(points), tuple(spans), 0, 0)
    grown = _union([z.grown for z in router.zones])
    cut, cut_spans = _cut_spans_at(points, spans, grown)
    return _route_hops(cut, cut_spans, grown, router, what, where)


def _cut_spans_at(points: Sequence[CameraPoint], spans: Sequence[tuple[int, int]],
                  grown: Any) -> tuple[list[CameraPoint], list[tuple[int, int]]]:
    """The camera-on spans less their stretches inside `grown`."""
    def outside(line: _Polyline) -> list[tuple[float, float]] | None:
        bad = [(line.s[k] + t0, line.s[k] + t1) for k in range(len(line.xy) - 1)
               for t0, t1 in _bad_stretches(line.xy[k], line.xy[k + 1], grown)]
        return _complement(bad, line.length) if bad else None

    out, new_spans, _stretches_off = _walk_spans(points, spans, outside)
    return out, new_spans


def _route_hops(points: list[CameraPoint], spans: list[tuple[int, int]], grown: Any, router: ZoneRouter,
                what: str, where: str | None) -> CameraPlan:
    """Points inside `grown` left out (unless they open or close a span), hops between the others routed round."""
    from shapely.geometry import Point
    core = grown.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    ends = {k for ab in spans for k in ab}
    span_of = {a: b for a, b in spans}
    out: list[CameraPoint] = []
    index: dict[int, int] = {}
    dropped = 0
    camera_until = -1
    for k, p in enumerate(points):
        if k not in ends and core.contains(Point(p.x, p.y)):
            dropped += p.kind == "photo"
            continue
        if out and k > camera_until:
            for x, y in router.way_round((out[-1].x, out[-1].y), (p.x, p.y), what, where):
                out.append(CameraPoint(x, y, "via"))
        index[k] = len(out)
        out.append(p)
        if k in span_of:
            camera_until = span_of[k]
    new_spans = tuple((index[a], index[b]) for a, b in spans)
    return CameraPlan(tuple(out), new_spans, 0, dropped)
