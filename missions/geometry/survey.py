"""Survey planning: the one call the compiler makes per `survey` step. Pure geometry — no MAVLink.

    from missions.geometry.area import load_area
    from missions.geometry.footprint import Footprint
    from missions.geometry.survey import plan_survey

    area = load_area("areas/north.kml", exclude=[...], base_dir=plan_dir)
    plan = plan_survey(area, Footprint(across_m=50.2, along_m=40.2), front_pct=80, side_pct=70,
                       angle_deg="auto", turnaround_m=10, speed_mps=6, min_interval_s=1.0)

`SurveyPlan` (frozen):
  waypoints       ordered `Waypoint`s (x/y metres in area.projection, lat/lon degrees, kind, leg):
                  kind "turnaround" (stub before/after a leg), "entry" (camera starts here),
                  "exit" (camera stops here), "via" (connection kept inside the area), "photo" (hover mode:
                  stop, shoot, go on; the route is the one distance triggering flies, turnaround stubs included,
                  with the photo stops in place of each leg's entry and exit; `yaw_deg` is the line's heading).
  camera_spans    `TriggerSpan(start_index, stop_index, distance_m, shoot_at_start=True, shoot_at_stop=False)`
                  per leg, indices into waypoints: emit DO_SET_CAM_TRIGG_DIST(distance, 0, 1) after the entry
                  waypoint and DO_SET_CAM_TRIGG_DIST(0, 0, 0) after the exit waypoint. The exit lies
                  `exit_margin_m` past the last photo, so an early waypoint acceptance keeps that photo.
                  Empty in hover mode (then shoot once at each "photo" waypoint).
  trigger_distance_m, spacing_m, angle_deg (of the first pass)
  photos          `PhotoPoint`s with lat/lon: `simulate_distance_trigger` run on the planned path — the same
                  function the report must run on the path rebuilt from the emitted items.
  legs            the legs in flying order; stats (`SurveyStats`); warnings (`PlanWarning(code, message)`).

The angle search (`best_angle`) minimises an objective, a plain function of what a pass at a candidate angle
would fly (`objectives.PassEstimate`); the default is the estimated flight time, turns included
(`objectives.flight_time_s`), and `plan_survey(objective=...)` takes another (`objectives.turn_count`,
`objectives.path_length_m`, or the caller's own).

Errors: `PlanError` for overlap out of range, a trigger interval shorter than the camera's minimum
(hint: the highest speed that works), an area that produces no legs, an area of more than MAX_SURVEY_PARTS
separate polygons.

Complexity (n = photos, L = lines, V = area vertices, C = boustrophedon cells, P = polygon parts):
  swaths O(L·V) vectorised + one union of O(legs) rectangles; route O(legs) plus greedy cell order
  O(C·starts) (the nearest next entry found on a grid of buckets) with starts ≤ 2400/C; connections that would
  cross a hole/notch get a visibility-graph path (built once per part, O(V²) segment tests, parts ≤ 400
  vertices); photos O(n) (vectorised per straight segment). angle_deg="auto" ranks ~30–60 candidate angles on
  bare inside segments, then plans once; above EXHAUSTIVE_ANGLE_PARTS parts it ranks ~200 angles on the bare
  inside segments measured from the edges alone and a hop per part to its nearest neighbour (O(V + crossings
  + P) each, `parts_estimate`) and plans the whole area at no more than its four best. Measured on 2 shared
  cores: 100 km² (785k photos) plans in 4–9 s and measures in ~2 s; a jagged 2000-vertex boundary takes ~3 s at
  a fixed angle, ~30 s with "auto"; 20,000 small triangles (P = 20,000) compile in ~25 s of CPU with "auto"
  (bench/bench_survey_scaling.py).
"""

from __future__ import annotations

from dataclasses import dataclass
import functools
import math
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np

from missions.compiled import PlanWarning
from missions.geometry.area import Area
from missions.errors import PlanError
from missions.geometry.footprint import Footprint, transect_spacing_m, trigger_distance_m
from missions.geometry.objectives import Objective, PassEstimate, estimated_time_s, flight_time_s
from missions.geometry.route import KIND_PHOTO, FlownLeg, Route, RoutePoint, build_route, order_legs
from missions.geometry.swaths import (Leg, PartEdges, SwathSet, bare_lines, candidate_angles, frame, generate_swaths,
                             normalise_angle)
from missions.geometry.triggers import PhotoPoint, TriggerSpan, simulate_distance_trigger

# ArduCopter accepts a waypoint within WPNAV_RADIUS (200 cm default) — before the vehicle is on it.
DEFAULT_EXIT_MARGIN_M = 2.0
# The photos of one plan's survey and corridor steps together, flown in as many sorties as it takes: 100 km² at
# 60 m with a WIRIS is ~660,000 (bench/bench_compile_scaling.py plans and measures it within 2 GB); three times
# that is no survey anyone flies from one plan but a typo (an area in the wrong units), refused from an estimate
# before anything is generated.
MAX_PHOTOS = 2_000_000
# Separate polygons one survey plans. The planner's cost grows about linearly with them (20,000 small triangles
# compile in ~25 s of one core: bench/bench_survey_scaling.py), and an area of more is better merged or split
# over several plans. Checked before any swaths are generated.
MAX_SURVEY_PARTS = 20_000
# Up to this many polygon parts the angle search plans the whole area at each candidate angle (~1 s at 100 small
# parts, growing with parts × angles); above, it ranks angles on a per-part estimate (`parts_estimate`), whose
# pick flies within ~1-3 % of that search's on grids of 100-1,500 small triangles (better at 600 and 1,500).
# No area of the survey-quality benchmark or the examples has more than three parts.
EXHAUSTIVE_ANGLE_PARTS = 100
# The many-parts search re-ranks FULL_RANK_PARTS // parts of its best angles (1 to 4) on the full swaths, each a
# whole plan of the area: four up to 1,000 parts, none (the estimate's best) above 2,000.
FULL_RANK_PARTS = 4000


def check_photo_budget(estimate: float, what: str, left: int | None = None) -> None:
    """PlanError when a step's estimated photos exceed what the plan has `left` of MAX_PHOTOS (None: all)."""
    left = MAX_PHOTOS if left is None else left
    if estimate > left:
        earlier = f" after {MAX_PHOTOS - left:,} in earlier steps" if left < MAX_PHOTOS else ""
        raise PlanError(f"this {what} would take about {estimate:,.0f} photos{earlier}, more than the "
                        f"{MAX_PHOTOS:,} one plan can hold",
                        hint="split it into several plans, or fly higher (fewer, larger photos)")


def check_part_count(geometry: Any, source: str = "") -> None:
    """PlanError when the area has more than MAX_SURVEY_PARTS separate polygons."""
    n = len(_polygons(geometry))
    if n > MAX_SURVEY_PARTS:
        raise PlanError(f"the area has {n:,} separate polygons, more than the {MAX_SURVEY_PARTS:,} one survey "
                        "can plan", where=source or None,
                        hint="merge or simplify the polygons (dissolve neighbours into blocks, drop the smallest) "
                             "or split them over several survey steps or plans")


@dataclass(frozen=True)
class Waypoint:
    x: float
    y: float
    lat: float
    lon: float
    kind: str
    leg: int = -1
    yaw_deg: float | None = None     # a photo stop's heading (its line's), degrees from true north


@dataclass(frozen=True)
class SurveyStats:
    area_m2: float
    angle_deg: float
    spacing_m: float
    trigger_distance_m: float
    lines: int
    legs: int
    photo_count: int
    path_length_m: float
    leg_length_m: float
    est_time_s: float
    trigger_interval_s: float


@dataclass(frozen=True)
class SurveyPlan:
    """A planned survey. `photos` and `stats` are derived on first use: the compiler needs only the waypoints
    and spans (the report re-derives photos from the emitted items), and a 100 km² survey has ~10^6 photos,
    so building them eagerly made compile time grow with the area instead of with the mission."""

    waypoints: tuple[Waypoint, ...]
    camera_spans: tuple[TriggerSpan, ...]
    hover: bool
    trigger_distance_m: float
    spacing_m: float
    angle_deg: float
    legs: tuple[Leg, ...]
    warnings: tuple[PlanWarning, ...]
    area: Area
    route: Route
    lines: int
    speed_mps: float

    @property
    def path_xy(self) -> np.ndarray:
        return np.array([(w.x, w.y) for w in self.waypoints], dtype=float).reshape(-1, 2)

    @functools.cached_property
    def photos(self) -> tuple[PhotoPoint, ...]:
        route = self.route
        if self.hover:
            raw = [PhotoPoint(p.x, p.y, _leg_heading(route, p.leg), p.leg) for p in route.points if p.kind == KIND_PHOTO]
        else:
            raw = simulate_distance_trigger(route.xy, self.camera_spans)
        pxy = np.array([(p.x, p.y) for p in raw], dtype=float).reshape(-1, 2)
        plat, plon = _latlon(self.area, pxy)
        return tuple(PhotoPoint(p.x, p.y, p.heading_deg, p.span, float(a), float(o)) for p, a, o in zip(raw, plat, plon))

    @functools.cached_property
    def stats(self) -> SurveyStats:
        length = self.route.length_m
        hover_stops = sum(1 for p in self.route.points if p.kind == KIND_PHOTO) if self.hover else 0
        return SurveyStats(
            area_m2=float(self.area.geometry.area), angle_deg=self.angle_deg, spacing_m=self.spacing_m,
            trigger_distance_m=self.trigger_distance_m, lines=self.lines, legs=len(self.route.legs),
            photo_count=len(self.photos), path_length_m=length,
            leg_length_m=float(sum(l.length_m for l in self.route.legs)),
            est_time_s=estimated_time_s(length, 2 * len(self.route.legs), self.speed_mps, hover_stops=hover_stops),
            trigger_interval_s=self.trigger_distance_m / self.speed_mps)


# ---------------------------------------------------------------------------------------- the angle search

@dataclass(frozen=True)
class LineSettings:
    """How the lines are laid and flown whatever their angle: what the angle search holds fixed."""

    across_m: float          # footprint across the lines
    spacing_m: float
    trigger_m: float
    along_m: float           # footprint along the lines
    turnaround_m: float
    speed_mps: float

    def swaths(self, geometry: Any, angle_deg: float, estimate: bool = False) -> SwathSet:
        return generate_swaths(geometry, angle_deg, self.across_m, self.spacing_m, self.trigger_m, self.along_m,
                               estimate=estimate)


def _order_length(legs: Sequence[Leg], order: Sequence[FlownLeg], turnaround_m: float) -> float:
    """Straight-line length of a leg order with turnaround stubs (cheap estimate for angle search)."""
    total = 0.0
    prev = None
    for i, rev in order:
        l = legs[i]
        a, b = ((l.x1, l.y1), (l.x0, l.y0)) if rev else ((l.x0, l.y0), (l.x1, l.y1))
        total += l.length_m + 2.0 * turnaround_m
        if prev is not None:
            total += math.dist(prev, a)
        prev = b
    return total


def swaths_estimate(sw: SwathSet, turnaround_m: float) -> PassEstimate:
    """What flying the swaths costs: a quick leg order (two greedy starts) and its straight hops."""
    order = order_legs(sw.legs, max_starts=2)
    # two turns per leg (its two ends)
    return PassEstimate(_order_length(sw.legs, order, turnaround_m), max(0, len(order) - 1) * 2 + 2, len(order))


def angle_objective(sw: SwathSet, turnaround_m: float, speed_mps: float,
                    objective: Objective = flight_time_s) -> float:
    """The angle search's score of one pass (lower is better): `objective` of its estimate."""
    return objective(swaths_estimate(sw, turnaround_m), speed_mps)


class _Costs:
    """An angle's score, computed once per angle (normalised, rounded to 1e-6°): the refinement revisits
    angles, and `_finalists` ranks what was computed."""

    def __init__(self, score: Callable[[float], float]) -> None:
        self.score = score
        self.cache: dict[float, float] = {}

    def __call__(self, angle_deg: float) -> float:
        a = round(normalise_angle(angle_deg), 6)
        if a not in self.cache:
            self.cache[a] = self.score(a)
        return self.cache[a]


def _refined(cost: _Costs, candidates: Sequence[float], steps_deg: Sequence[float]) -> float:
    """The best candidate (ties: the smallest |angle|), then for each step in turn moved by it either way where
    that scores lower."""
    best = min(candidates, key=lambda a: (cost(a), abs(a)))
    for step in steps_deg:
        for a in (best - step, best + step):
            if cost(a) < cost(best) - 1e-9:
                best = round(normalise_angle(a), 6)
    return best


def best_angle(geometry: Any, lines: LineSettings, objective: Objective = flight_time_s) -> float:
    """Minimum-`objective` line azimuth: candidate edge directions and a coarse sweep ranked on bare inside
    segments, a 1° refinement, then the best four distinct angles re-ranked on the full swaths. An area of more
    than EXHAUSTIVE_ANGLE_PARTS parts is ranked on a per-part estimate instead (`_best_angle_of_many_parts`)."""
    if len(_polygons(geometry)) > EXHAUSTIVE_ANGLE_PARTS:
        return _best_angle_of_many_parts(geometry, lines, objective)

    def on_bare_segments(a: float) -> float:
        sw = lines.swaths(geometry, a, estimate=True)
        return angle_objective(sw, lines.turnaround_m, lines.speed_mps, objective) if sw.legs else math.inf

    cost = _Costs(on_bare_segments)
    best = _refined(cost, candidate_angles(geometry), (4.0, 2.0, 1.0))
    # the estimate ignores leg-end rules and repairs, which matter on concave areas: re-rank the best few
    # distinct angles on the full swaths
    return _rank_on_full_swaths(_finalists(cost.cache, best, 4), geometry, lines, objective)


def _finalists(cache: dict[float, float], best: float, k: int) -> list[float]:
    """`best` and the next best angles of `cache` (angle -> cost), at most k, at least 3° apart."""
    ranked = sorted(cache, key=lambda a: (cache[a], abs(a)))
    finalists: list[float] = []
    for a in [best] + ranked:
        if all(abs(normalise_angle(a - f)) >= 3.0 for f in finalists):
            finalists.append(a)
        if len(finalists) == k:
            break
    return finalists


def _rank_on_full_swaths(finalists: list[float], geometry: Any, lines: LineSettings, objective: Objective) -> float:
    if len(finalists) == 1:
        return finalists[0]

    def full_cost(a: float) -> float:
        sw = lines.swaths(geometry, a)
        return angle_objective(sw, lines.turnaround_m, lines.speed_mps, objective) if sw.legs else math.inf

    return min(finalists, key=lambda a: (full_cost(a), abs(a)))


def _polygons(geometry: Any) -> list[Any]:
    return list(geometry.geoms) if geometry.geom_type == "MultiPolygon" else [geometry]


@dataclass(frozen=True)
class PartNeighbours:
    """Pairs (i[k], j[k]) of parts, sorted by i, whose centroids lie within 1.5 times the distance from i's
    centroid to its nearest neighbour's: the hops a route over many small parts takes are among them."""

    i: np.ndarray
    j: np.ndarray

    @classmethod
    def of(cls, geometry: Any) -> "PartNeighbours":
        import shapely
        pts = shapely.centroid(np.array(_polygons(geometry), dtype=object))
        tree = shapely.STRtree(pts)
        (src, _dst), dist = tree.query_nearest(pts, exclusive=True, return_distance=True, all_matches=False)
        nearest = np.zeros(len(pts))
        nearest[src] = dist
        i, j = tree.query(pts, predicate="dwithin", distance=1.5 * nearest + 1e-6)
        keep = i != j
        order = np.lexsort((j[keep], i[keep]))
        return cls(i[keep][order], j[keep][order])


def parts_estimate(edges: PartEdges, neighbours: PartNeighbours, angle_deg: float, lines: LineSettings) -> PassEstimate:
    """What flying the area at `angle_deg` costs, estimated part by part: the bare inside segments of every part's
    lines (`swaths.bare_lines`: what generate_swaths(estimate=True) gives, from the edges in one vectorised pass),
    each leg with its turnaround stubs and two turns, a spacing's hop from line to line within a part, and a hop
    from each part to its nearest neighbour. A part is flown as a run along the lines (its extent along them less
    a footprint, plus the stubs), so lines pointing from one part to the next make progress towards it and the
    hop between them is that much shorter: the effect that makes lines along a row of small parts pay."""
    bare = bare_lines(edges, angle_deg, lines.across_m, lines.spacing_m, lines.along_m)
    d, n = frame(angle_deg)
    run = lines.turnaround_m + np.where(bare.one_photo, 0.0, np.maximum(bare.along_m - lines.along_m, 0.0) / 2.0)
    i, j = neighbours.i, neighbours.j
    step = bare.centre_xy[j] - bare.centre_xy[i]
    hop = np.hypot(np.maximum(np.abs(step @ d) - run[i] - run[j], 0.0), step @ n)
    first = np.flatnonzero(np.r_[True, i[1:] != i[:-1]]) if len(i) else np.zeros(0, np.int64)
    hops_m = float(np.minimum.reduceat(hop, first).sum()) if len(i) else 0.0
    path_m = bare.length_m + 2.0 * lines.turnaround_m * bare.legs + lines.spacing_m * bare.line_hops + hops_m
    return PassEstimate(path_m, 2 * bare.legs, bare.legs)


def _best_angle_of_many_parts(geometry: Any, lines: LineSettings, objective: Objective) -> float:
    """The angle search for an area of many parts: planning the whole area at each of ~60 angles costs
    parts × angles plans (20,000 small polygons: more than 10 minutes), so candidates and a 1° sweep
    are ranked on `parts_estimate` (edges × angles), refined to 0.25°, and only the best few (fewer as the
    parts grow: FULL_RANK_PARTS / parts) are re-ranked on the full swaths."""
    edges = PartEdges.of(geometry)
    neighbours = PartNeighbours.of(geometry)
    cost = _Costs(lambda a: objective(parts_estimate(edges, neighbours, a, lines), lines.speed_mps))
    best = _refined(cost, sorted(set(candidate_angles(geometry)) | {float(a) for a in range(-90, 90)}), (0.5, 0.25))
    k = max(1, min(4, FULL_RANK_PARTS // edges.parts))
    return _rank_on_full_swaths(_finalists(cost.cache, best, k), geometry, lines, objective)


# ---------------------------------------------------------------------------------------- planning

class OrderedLegs(NamedTuple):
    """The legs of every pass (the first at the survey's angle, a refly 90° to it) and the order they are flown in."""

    legs: tuple[Leg, ...]
    order: tuple[FlownLeg, ...]      # indices into legs
    lines: int


def plan_survey(area: Area, footprint: Footprint, front_pct: float, side_pct: float,
                angle_deg: float | str = "auto", turnaround_m: float = 10.0, speed_mps: float = 5.0,
                min_interval_s: float | None = None, refly_90: bool = False, hover: bool = False,
                start_latlon: tuple[float, float] | None = None,
                exit_margin_m: float = DEFAULT_EXIT_MARGIN_M, photos_left: int = MAX_PHOTOS,
                objective: Objective = flight_time_s, turn_radius_m: float | None = None,
                exit_stretch: float = 0.0) -> SurveyPlan:
    """Plan a survey of `area` (see module doc); `photos_left`: what the plan's earlier steps left of
    MAX_PHOTOS; `objective`: what angle_deg "auto" minimises (`objectives`); `turn_radius_m`: a plane's, whose
    consecutive lines are then flown at least two radii apart where the cell allows (skip-line order);
    `exit_stretch`: each exit lies that fraction of its leg's length further past the last photo (route._LegEnds)."""
    spacing = transect_spacing_m(footprint, side_pct)
    trig = trigger_distance_m(footprint, front_pct)
    _check_speed_and_turnaround(speed_mps, turnaround_m)
    _check_trigger_interval(trig, speed_mps, min_interval_s, hover)
    geom = area.geometry
    warnings = _sliver_warnings(area)
    check_part_count(geom, area.source)
    # a photo adds about spacing x trigger distance of new ground
    check_photo_budget(geom.area / (spacing * trig) * (2 if refly_90 else 1), "survey", photos_left)
    lines = LineSettings(footprint.across_m, spacing, trig, footprint.along_m, turnaround_m, speed_mps)
    angle = _line_angle(angle_deg, geom, lines, objective)
    start_xy = area.projection.point_to_xy(*start_latlon) if start_latlon else None
    gap = 1 if not turn_radius_m else max(1, math.ceil(2.0 * turn_radius_m / spacing - 1e-9))
    passes = _ordered_passes(geom, angle, lines, refly_90, start_xy, gap)
    if not passes.legs:
        raise PlanError("the area produced no flight lines", where=area.source or None,
                        hint="check the area's size against the footprint")
    warnings += _small_area_warnings(geom, footprint)
    route = _flown_route(area, passes, turnaround_m, exit_margin_m, trig, hover, exit_stretch)
    spans = () if hover else tuple(TriggerSpan(a, b, trig, True, False) for a, b in route.spans)
    return SurveyPlan(_waypoints(area, route, hover), spans, hover, trig, spacing, angle, route.legs, tuple(warnings),
                      area, route, passes.lines, float(speed_mps))


def _check_speed_and_turnaround(speed_mps: float, turnaround_m: float) -> None:
    if not (isinstance(speed_mps, (int, float)) and math.isfinite(speed_mps) and speed_mps > 0):
        raise PlanError(f"speed {speed_mps!r} m/s must be positive", where="vehicle.speed_mps",
                        hint="give the ground speed in m/s, e.g. speed_mps: 5")
    if not (isinstance(turnaround_m, (int, float)) and math.isfinite(turnaround_m) and turnaround_m >= 0):
        raise PlanError(f"turnaround {turnaround_m!r} m must be zero or positive", where="turnaround_m",
                        hint="the straight run beyond each line end in metres, e.g. turnaround_m: 10 (0: none)")


def _check_trigger_interval(trig: float, speed_mps: float, min_interval_s: float | None, hover: bool) -> None:
    """PlanError when distance triggering would ask the camera for photos faster than it can take them."""
    interval = trig / speed_mps
    if min_interval_s and not hover and interval < min_interval_s - 1e-9:
        raise PlanError(f"photos would be {interval:.2f} s apart, faster than the camera's minimum of "
                        f"{min_interval_s:g} s", where="overlap.front",
                        hint=f"fly at most {trig / min_interval_s:.1f} m/s, lower the front overlap or fly higher")


def _sliver_warnings(area: Area) -> list[PlanWarning]:
    if not area.dropped[0]:
        return []
    from missions.geometry.area import MIN_PART_WIDTH_M
    n, m2 = area.dropped
    return [PlanWarning("area_sliver_dropped",
                        f"{n} piece{'s' if n > 1 else ''} of the area ({m2:.1f} m² in all) that the "
                        f"exclusion zones cut off {'are' if n > 1 else 'is'} nowhere {MIN_PART_WIDTH_M:g} m "
                        "wide and not surveyed (no GNSS track that narrow misses the exclusion); "
                        "if it matters, draw the exclusion to leave a wider strip")]


def _small_area_warnings(geom: Any, footprint: Footprint) -> list[PlanWarning]:
    x0, y0, x1, y1 = geom.bounds
    if geom.area <= footprint.area_m2 and (x1 - x0) <= max(footprint.across_m, footprint.along_m) \
            and (y1 - y0) <= max(footprint.across_m, footprint.along_m):
        return [PlanWarning("area_smaller_than_footprint",
                            f"the area ({geom.area:.0f} m²) is smaller than one photo's footprint "
                            f"({footprint.across_m:.1f} × {footprint.along_m:.1f} m); a single waypoint "
                            "with one photo may serve better")]
    return []


def _line_angle(angle_deg: float | str, geom: Any, lines: LineSettings, objective: Objective) -> float:
    """The first pass's line azimuth: the plan's, or the search's for "auto"."""
    if isinstance(angle_deg, str):
        if angle_deg != "auto":
            raise PlanError(f"angle_deg must be a number or 'auto', got {angle_deg!r}", where="angle_deg",
                            hint="degrees clockwise from north, e.g. angle_deg: 30 (0 = north-south lines), or auto")
        return best_angle(geom, lines, objective)
    if not math.isfinite(float(angle_deg)):
        raise PlanError(f"angle_deg {angle_deg!r} is not a number", where="angle_deg",
                        hint="degrees clockwise from north, e.g. angle_deg: 30 (0 = north-south lines), or auto")
    return normalise_angle(float(angle_deg))


def _ordered_passes(geom: Any, angle: float, lines: LineSettings, refly_90: bool,
                    start_xy: tuple[float, float] | None, gap: int = 1) -> OrderedLegs:
    """The passes' legs in flying order: each pass ordered from where the one before it ended."""
    passes = [lines.swaths(geom, angle)]
    if refly_90:
        passes.append(lines.swaths(geom, angle + 90.0))
    legs: list[Leg] = []
    order: list[FlownLeg] = []
    pos = start_xy
    for sw in passes:
        off = len(legs)
        o = order_legs(sw.legs, pos, gap=gap)
        legs.extend(sw.legs)
        order.extend(FlownLeg(i + off, r) for i, r in o)
        if o:
            last = sw.legs[o[-1].index]
            pos = (last.x0, last.y0) if o[-1].reversed else (last.x1, last.y1)
    return OrderedLegs(tuple(legs), tuple(order), sum(sw.lines for sw in passes))


def _flown_route(area: Area, passes: OrderedLegs, turnaround_m: float, exit_margin_m: float, trig: float,
                 hover: bool, exit_stretch: float = 0.0) -> Route:
    # Hover lines are flown on the route distance triggering flies (turnaround stubs, connections kept out of
    # holes and exclusions), stopping at the photos instead of running the camera along the leg: see _hover_route.
    # A hover stop is held, so no exit margin against an early waypoint acceptance.
    margin = 0.0 if hover else min(exit_margin_m, 0.45 * trig)
    avoid = area.keep_out if getattr(area, "keep_out", None) is not None else area.excluded
    route = build_route(passes.legs, area.geometry, turnaround_m, exit_margin_m=margin, order=passes.order,
                        avoid=avoid, exit_stretch=0.0 if hover else exit_stretch)
    return _hover_route(route, trig) if hover else route


def _latlon(area: Area, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(xy) == 0:
        return np.zeros(0), np.zeros(0)
    return area.projection.to_latlon(xy[:, 0], xy[:, 1])


def _waypoints(area: Area, route: Route, hover: bool) -> tuple[Waypoint, ...]:
    lat, lon = _latlon(area, route.xy)
    yaw = _photo_yaws(area, route) if hover else {}
    return tuple(Waypoint(float(p.x), float(p.y), float(a), float(o), p.kind, p.leg, yaw.get(k))
                 for k, (p, a, o) in enumerate(zip(route.points, lat, lon)))


def _hover_route(route: Route, trig: float) -> Route:
    """The hover route: each leg's entry and exit replaced by its photo stops, one every trigger distance from the
    leg start (legs are whole trigger steps long, so the last one is on the leg end), in flying order.

    The turnaround stub before a line is what points the camera along it. A copter flying its mission faces the
    waypoint it flies to (ArduCopter's WP_YAW_BEHAVIOR and PX4's MPC_YAW_MODE defaults) and keeps that heading
    while it hovers, so a line reached straight from the previous one has its first photo taken across the line:
    on a field one photo long the footprint, longer across than along, then lay turned and coverage fell short
    (96 % on the 7 m strip of tests/missions/test_report.py). Arriving from the stub it faces along the line
    (PX4 also takes the line's heading from the waypoint itself, `Waypoint.yaw_deg`). Where the route has no stub
    (turnaround_m 0, a detour inside the area, an exclusion in the way) the report measures the turned photo. The
    stub after a line is kept: the route checks each hop to the next line against the holes and exclusions from
    it."""
    stops: dict[int, list[RoutePoint]] = {}
    for k, (entry, _exit) in enumerate(route.spans):
        l, rev = route.legs[k], route.reversed_legs[k]
        n = int(round(l.length_m / trig)) if trig > 0 and l.length_m > 1e-9 else 0
        f = trig * np.arange(n + 1) / l.length_m if n else np.zeros(1)
        pts = [RoutePoint(l.x0 + (l.x1 - l.x0) * t, l.y0 + (l.y1 - l.y0) * t, KIND_PHOTO, k) for t in f.tolist()]
        stops[entry] = pts[::-1] if rev else pts
    ends = {b for _a, b in route.spans}
    points: list[RoutePoint] = []
    for i, p in enumerate(route.points):
        if i in stops:
            points.extend(stops[i])
        elif i not in ends:
            points.append(p)
    return Route(tuple(points), route.legs, route.reversed_legs, ())


def _photo_yaws(area: Area, route: Route) -> dict[int, float]:
    """Route point index -> heading of its line at each photo stop, in degrees from true north (what a vehicle's
    yaw is)."""
    ks = [k for k, p in enumerate(route.points) if p.kind == KIND_PHOTO]
    if not ks:
        return {}
    az = area.projection.true_azimuths([route.points[k].x for k in ks], [route.points[k].y for k in ks],
                                       [_leg_heading(route, route.points[k].leg) for k in ks])
    return dict(zip(ks, az.tolist()))


def _leg_heading(route: Route, k: int) -> float:
    leg = route.legs[k]
    h = leg.angle_deg % 360.0
    return (h + 180.0) % 360.0 if route.reversed_legs[k] else h
