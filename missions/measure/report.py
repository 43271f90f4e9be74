"""The measured report of a compiled mission, from the re-flight of its items (`missions.measure.flight`).

    sim = simulate(compiled)        # missions.measure.flight
    rep = report(compiled, sim)     # a MissionReport; rep.to_json() is the `wiris mission check --json` object

How the flight is measured:
* Measuring: per survey/corridor step and payload with `missions.measure.coverage`, in one metric plane (the first
  area's projection, so photos on a line stay exactly collinear). Coverage takes every photo whose footprint can
  reach the area, whichever step took it, grouped by altitude (one footprint size per group; coverage is the
  union over all groups). The rest is the step's own, so that a neighbouring step does not blur it: its overlaps,
  photo count and metres outside the area take the photos taken and the path flown while the mission executes
  the step's items (`AreaInfo.items`; the vehicle executes a NAV item while it flies towards it and holds at it,
  so the approach to the step's first waypoint is the step's). Front
  overlap pairs consecutive photos of one camera-on stretch; a turn of more than TURN_SPLIT_DEG starts a new
  stretch (a turnaround is not a front pair; a corridor's gentle bend is, and its lower overlap is real).
  Coverage below COVERAGE_TARGET and overlaps more than OVERLAP_SLACK below the request are warnings, not
  errors: the mission flies, the result is worse than asked.
* Holes and exclusion zones: the whole flown path is measured inside each step's zones as drawn
  (`Area.excluded`, so an exclusion across the boundary counts too), deeper than route.ZONE_EDGE_TOL_M (a
  path along a zone's edge is beside it), split into metres with the camera on (distance or interval
  triggering) and off, with the photos centred inside; more than a metre is the path_over_exclusion warning.
  Unlike the figures above these stay the whole flight's: an exclusion is ground not to fly over or photograph
  (the plan schema's words), and another step flying over it is as real as this one.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from types import MappingProxyType
from typing import Any, Iterable, Mapping, Sequence, TypeVar

import numpy as np

from cdf.catalogue import catalogue
from missions.compiled import AreaInfo, Compiled, PayloadInfo
from missions.geometry.footprint import Footprint
from missions.geometry.geo import leaf_parts
from missions.geometry.route import ZONE_EDGE_TOL_M
from missions.geometry.triggers import PhotoPoint
from missions.measure.coverage import (coverage_fraction, footprint_polygons, min_front_overlap, min_side_overlap,
                                       outside_length_m)
from missions.measure.flight import Photo, Simulation, self_triggering, simulate
from missions.measure.numbers import StepNumbers, step_numbers
from missions.measure.seams import measure_sorties, table_lines
from missions.measure.zones import ZoneMeasure, ZoneRow, measure_zones, photographed_warnings
from missions.plan.schema import MAX_AGL_M
from missions.terrain.reflight import GROUND_FLAT

# Coverage below this is worth a warning: the examples and the tests hold the compiler to it.
COVERAGE_TARGET = 0.995
# Measured minimum overlaps within this of the request are rounding at the edges, not a planning fault.
OVERLAP_SLACK = 0.01

K = TypeVar("K")
V = TypeVar("V")


def _frozen(table: Mapping[K, V]) -> Mapping[K, V]:
    """A read-only copy: the report is a value, its tables too."""
    return MappingProxyType(dict(table))


def _r(v: float, nd: int = 4) -> float:
    """`v` rounded as the report shows it."""
    return round(float(v), nd)


def _r_or_none(v: float | None, nd: int = 4) -> float | None:
    return None if v is None else _r(v, nd)


# --------------------------------------------------------------------------------------------- the report's values

@dataclass(frozen=True)
class Finding:
    """A warning or an error of the report: `code` is stable (scripts match on it), `message` says what and where."""

    code: str
    message: str

    def to_json(self) -> dict[str, str]:
        return {"code": self.code, "message": self.message}


@dataclass(frozen=True)
class OverlapMin:
    """The lowest front and side overlap measured (fractions); None where no pair of photos was measured."""

    front_min: float | None
    side_min: float | None

    def rounded(self) -> OverlapMin:
        return OverlapMin(_r_or_none(self.front_min), _r_or_none(self.side_min))

    def to_json(self) -> dict[str, float | None]:
        return {"front_min": self.front_min, "side_min": self.side_min}


@dataclass(frozen=True)
class GsdRange:
    """Ground sample distance of a payload's photos at its lowest and at its highest photo (cm/px)."""

    min_cm: float
    max_cm: float

    def to_json(self) -> list[float]:
        return [self.min_cm, self.max_cm]


@dataclass(frozen=True)
class RequestedOverlap:
    """The overlaps a step's plan asks for (fractions; `*_pct` in the JSON as the plan writes them)."""

    front: float
    side: float

    def to_json(self) -> dict[str, float]:
        return {"front": self.front, "side": self.side,
                "front_pct": round(100 * self.front, 4), "side_pct": round(100 * self.side, 4)}


@dataclass(frozen=True)
class StepPath:
    """Metres of flown path measured for a step: its own outside its area, and the whole flight's inside its
    holes and exclusion zones (and how many of those with the camera on)."""

    outside_m: float
    over_gaps_m: float
    over_gaps_camera_m: float

    def rounded(self) -> StepPath:
        return StepPath(_r(self.outside_m, 1), _r(self.over_gaps_m, 1), _r(self.over_gaps_camera_m, 1))

    def to_json(self) -> dict[str, float]:
        return {"outside_m": self.outside_m, "over_gaps_m": self.over_gaps_m,
                "over_gaps_camera_m": self.over_gaps_camera_m}


@dataclass(frozen=True)
class AreaRow:
    """One survey or corridor step as the report shows it (an entry of `areas`): the tables are per payload."""

    step: int
    kind: str
    area_m2: float
    altitude_m: float
    trigger: str
    requested: RequestedOverlap
    coverage: Mapping[str, float]
    overlap: Mapping[str, OverlapMin]
    photos: Mapping[str, int]                 # the step's own photos
    path: StepPath | None                     # None: the step has no payload, its path was not measured
    photos_in_zones: Mapping[str, int]        # the whole flight's photos centred inside the step's zones
    # the no_fly / no_photo / exclude zones near the step (missions.measure.zones); coverage is measured on the
    # coverable area when there are any
    zones: tuple[ZoneRow, ...] = ()
    coverable_m2: float | None = None
    zone_margin_m: float | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"step": self.step, "kind": self.kind, "area_m2": self.area_m2,
                               "altitude_m": self.altitude_m, "trigger": self.trigger,
                               "requested": self.requested.to_json(), "coverage": dict(self.coverage),
                               "overlap": {n: o.to_json() for n, o in self.overlap.items()},
                               "photos": dict(self.photos)}
        if self.path is not None:
            out.update(self.path.to_json())
            out["photos_in_zones"] = dict(self.photos_in_zones)
        if self.zones:
            out["zone_margin_m"] = self.zone_margin_m
            out["coverable_m2"] = self.coverable_m2
            out["zones"] = [z.to_json() for z in self.zones]
        return out


@dataclass(frozen=True)
class MissionReport:
    """The measured report of a compiled mission. `to_json()` is `wiris mission check --json` and
    NAME.report.json (cli.md's binding fields, then the rest), rounded as shown there."""

    plan: str
    name: str
    firmware: str
    frame: str
    mission_items: int
    item_limit: int
    parts: int
    part_items: tuple[int, ...]
    photos: Mapping[str, int]                 # per payload, the whole flight
    path_length_m: float
    climb_m: float
    flight_time_s: float
    flight_time_qgc_s: float
    max_altitude_m: float
    area_m2: float
    gsd_cm: Mapping[str, GsdRange | None]     # None: the payload takes no photo above the ground
    coverage: Mapping[str, float]             # per payload, the steps' weighted by their area
    overlap: Mapping[str, OverlapMin]         # per payload, the lowest of the steps'
    areas: tuple[AreaRow, ...]
    warnings: tuple[Finding, ...]
    errors: tuple[Finding, ...]
    speed_mps: float = 0.0                    # the survey speed flown (the plan's, or the one `auto` chose)
    sun: tuple[Any, ...] = ()                 # missions.thermal.assess.StepSun per timed step (a plan with `when`)
    steps: tuple[StepNumbers, ...] = ()      # per survey or corridor step, the numbers a pilot reads
    sorties: Any = None                       # missions.measure.seams.SortieTable (a mission flown in sorties)
    endurance: Any = None                     # missions.sorties.Endurance the compile judged the flight by
    ground: str = GROUND_FLAT                 # where heights above ground come from
    terrain: Any = None                       # missions.terrain.reflight.GroundReport when a DEM is given

    def to_json(self) -> dict[str, Any]:
        return {
            "plan": self.plan,
            "name": self.name,
            "firmware": self.firmware,
            "frame": self.frame,
            "mission_items": self.mission_items,
            "item_limit": self.item_limit,
            "parts": self.parts,
            "part_items": list(self.part_items),
            "photos": dict(self.photos),
            "path_length_m": self.path_length_m,
            "climb_m": self.climb_m,
            "flight_time_s": self.flight_time_s,
            "flight_time_qgc_s": self.flight_time_qgc_s,
            "max_altitude_m": self.max_altitude_m,
            "area_m2": self.area_m2,
            "gsd_cm": {n: None if g is None else g.to_json() for n, g in self.gsd_cm.items()},
            "coverage": dict(self.coverage),
            "overlap": {n: o.to_json() for n, o in self.overlap.items()},
            "areas": [a.to_json() for a in self.areas],
            "warnings": [w.to_json() for w in self.warnings],
            "errors": [e.to_json() for e in self.errors],
            "speed_mps": self.speed_mps,
            "sun": [s.to_json() for s in self.sun],
            "steps": [s.to_json() for s in self.steps],
            "ground": self.ground,
            "endurance": None if self.endurance is None else self.endurance.to_json(),
            "sorties": [] if self.sorties is None else list(self.sorties.rows),
            "sorties_union": None if self.sorties is None else
            {"coverage": dict(self.sorties.coverage),
             "overlap": {n: o.to_json() for n, o in self.sorties.overlap.items()}},
        } | ({"terrain": self.terrain.to_json()} if self.terrain is not None else {})


@dataclass(frozen=True)
class PlanFinding:
    """What is wrong with a plan that does not compile, and where (file:line:col) and what to do, when known."""

    message: str
    where: str | None = None
    hint: str | None = None
    code: str = "plan"

    def to_json(self) -> dict[str, str | None]:
        return {"code": self.code, "message": self.message, "where": self.where, "hint": self.hint}


@dataclass(frozen=True)
class UncompiledReport:
    """`check --json` for a plan that does not compile: the binding keys, nothing measured, the errors located."""

    plan: str
    errors: tuple[PlanFinding, ...]

    def to_json(self) -> dict[str, Any]:
        return {"plan": self.plan, "firmware": None, "mission_items": 0, "item_limit": None, "parts": 0,
                "photos": {}, "path_length_m": None, "flight_time_s": None, "area_m2": None, "gsd_cm": {},
                "coverage": {}, "overlap": {}, "warnings": [], "errors": [e.to_json() for e in self.errors]}


# --------------------------------------------------------------------------------------------- measuring

def area_geometry(area: Any, proj: Any) -> Any:
    """`area` (missions.geometry.area.Area) as a shapely geometry in projection `proj` (re-projected through
    lat/lon when it was built in another plane; its edges are short enough to stay straight in both)."""
    from shapely.geometry import MultiPolygon, Polygon   # heavy: loads only when a plan has an area

    if area.projection == proj:
        return area.geometry
    polys = []
    for rings in area.latlon_rings():
        xy = []
        for ring in rings:
            x, y = proj.to_xy([p[0] for p in ring], [p[1] for p in ring])
            xy.append(list(zip(x.tolist(), y.tolist())))
        polys.append(Polygon(xy[0], xy[1:]))
    return polys[0] if len(polys) == 1 else MultiPolygon(polys)


def footprint_ring(photo: Photo, payload: PayloadInfo) -> list[tuple[float, float]]:
    """The photo's footprint corners in the simulation's metres (x, y), closed ring."""
    across, along = payload.footprint_m(max(photo.alt_m, 0.0))
    h = math.radians(photo.heading_deg)
    d = np.array([math.sin(h), math.cos(h)])
    n = np.array([math.cos(h), -math.sin(h)])
    c = np.array([photo.x, photo.y])
    pts = [c - d * along / 2 - n * across / 2, c + d * along / 2 - n * across / 2,
           c + d * along / 2 + n * across / 2, c - d * along / 2 + n * across / 2]
    pts.append(pts[0])
    return [(float(p[0]), float(p[1])) for p in pts]


@dataclass(frozen=True)
class PayloadMeasure:
    """One payload's photos measured over one step, unrounded (`_measure_payload`)."""

    name: str
    coverage: float
    overlap: OverlapMin
    photos: int               # the step's own
    photos_in_zones: int      # the whole flight's, centred inside the step's zones


@dataclass(frozen=True)
class StepMeasure:
    """One step measured, unrounded: per payload, and its path (None: no payload, nothing measured)."""

    area: AreaInfo
    payloads: tuple[PayloadMeasure, ...]
    path: StepPath | None
    zones: ZoneMeasure | None = None


@dataclass(frozen=True)
class _PhotoArrays:
    """One payload's photos as arrays in the simulation's metres, altitudes clamped at the ground."""

    photos: Sequence[Photo]
    x: np.ndarray
    y: np.ndarray
    alt: np.ndarray

    @staticmethod
    def of(photos: Sequence[Photo]) -> _PhotoArrays:
        if not photos:
            return _PhotoArrays(photos, np.zeros(0), np.zeros(0), np.zeros(0))
        return _PhotoArrays(photos, np.array([p.x for p in photos]), np.array([p.y for p in photos]),
                            np.array([max(p.alt_m, 0.0) for p in photos]))

    def reaching(self, geom: Any, payload: PayloadInfo) -> np.ndarray:
        """Indices of the photos whose footprint can reach `geom` (the others cover other ground)."""
        import shapely

        if not self.photos:
            return np.zeros(0, int)
        reach = max(payload.footprint_m(1.0)) * self.alt        # footprints scale with altitude
        return np.nonzero(shapely.dwithin(shapely.points(self.x, self.y), geom, reach))[0]

    def taken_during(self, items: tuple[int, int]) -> np.ndarray:
        """Indices of the photos taken while the mission executes items [first, end)."""
        first, end = items
        return np.array([k for k, p in enumerate(self.photos) if first <= p.item < end], dtype=int)

    def on_lines(self, idx: np.ndarray, line_items: tuple[int, ...]) -> np.ndarray:
        """Of the photos `idx`, those taken flying towards one of `line_items` (a line's leg)."""
        wanted = set(line_items)
        return np.array([k for k in idx.tolist() if self.photos[k].item in wanted], dtype=int)

    def by_altitude(self, idx: np.ndarray) -> dict[float, list[int]]:
        """The photos `idx` above the ground grouped by altitude (one Footprint per group), in mission order."""
        groups: dict[float, list[int]] = {}
        for k in idx.tolist():
            if self.alt[k] > 0:
                groups.setdefault(round(float(self.alt[k]), 2), []).append(k)
        return groups

    def points(self, ks: list[int]) -> list[PhotoPoint]:
        return [PhotoPoint(float(self.x[k]), float(self.y[k]), self.photos[k].heading_deg, self.photos[k].span)
                for k in ks]


def _coverage(geom: Any, ph: _PhotoArrays, groups: dict[float, list[int]], payload: PayloadInfo) -> float:
    """Fraction of `geom` under the footprints of the photos `groups` (by altitude): the union over all groups."""
    import shapely   # heavy: loads only when a plan has an area

    if len(groups) == 1:
        (alt, ks), = groups.items()
        return coverage_fraction(geom, ph.points(ks), Footprint(*payload.footprint_m(alt)))[1]
    if not groups or geom.area <= 0:
        return 0.0
    polys = [footprint_polygons(np.column_stack([ph.x[ks], ph.y[ks]]),
                                np.radians([ph.photos[k].heading_deg for k in ks]),
                                Footprint(*payload.footprint_m(alt))) for alt, ks in groups.items()]
    union = shapely.union_all(np.concatenate(polys))
    return float(shapely.intersection(geom, union).area / geom.area)


def _lowest(values: Iterable[float | None]) -> float | None:
    return min((v for v in values if v is not None), default=None)


def _min_overlaps(ph: _PhotoArrays, groups: dict[float, list[int]], payload: PayloadInfo) -> OverlapMin:
    """The lowest front and side overlap of the photos `groups` (by altitude; pairs within a group)."""
    fronts, sides = [], []
    for alt, ks in groups.items():
        fp = Footprint(*payload.footprint_m(alt))
        fronts.append(min_front_overlap(ph.points(ks), fp))
        sides.append(min_side_overlap(ph.points(ks), fp))
    return OverlapMin(_lowest(fronts), _lowest(sides))


def _measure_payload_over_dem(area_info: AreaInfo, geom: Any, zones: Any, name: str, payload: PayloadInfo,
                              photos: Sequence[Photo], ground: Any) -> PayloadMeasure:
    """`_measure_payload` with footprints cut by the DEM (missions.terrain.reflight): coverage of every photo
    whose ground footprint meets the area, overlaps of the step's own."""
    import shapely
    from missions.terrain import reflight

    ph = _PhotoArrays.of(photos)
    near = np.flatnonzero(shapely.intersects(ground.polygons, geom)) if len(photos) else np.zeros(0, int)
    own = near if area_info.items is None else ph.taken_during(area_info.items)
    overlap = OverlapMin(reflight.min_front_overlap(photos, ground, own),
                         reflight.min_side_overlap(photos, ground, own, payload))
    return PayloadMeasure(name, reflight.coverage_on_ground(geom, ground, near), overlap, int(len(own)),
                          _photos_in(zones, photos))


def _measure_payload(area_info: AreaInfo, geom: Any, zones: Any, name: str, payload: PayloadInfo,
                     photos: Sequence[Photo], ground: Any = None, self_shooting: bool = False) -> PayloadMeasure:
    """Coverage and overlaps of one payload's photos over one step's area `geom`.

    Coverage counts every photo whose footprint can reach the area: a neighbouring step's photo covers ground
    too. The overlaps and the photo count take the photos the step took (`area_info.items`): another step's
    photos are measured against its own area. Without a range (an AreaInfo built by hand) the photos near the
    area stand in for them. The zones are checked against every photo: an exclusion is ground not to
    photograph, whichever step does it. A payload that shoots by itself (`self_shooting`: a RedEdge in overlap
    mode) shoots on the turnarounds and transits too; its overlaps take the photos on the step's lines
    (`area_info.line_items`): a turnaround's photos beside a line of the crossing pass (refly_90) are no side
    neighbour of it."""
    if ground is not None:
        return _measure_payload_over_dem(area_info, geom, zones, name, payload, photos, ground)
    ph = _PhotoArrays.of(photos)
    near = ph.reaching(geom, payload)
    own = near if area_info.items is None else ph.taken_during(area_info.items)
    on_lines = own if not self_shooting or area_info.line_items is None else ph.on_lines(own, area_info.line_items)
    return PayloadMeasure(name, _coverage(geom, ph, ph.by_altitude(near), payload),
                          _min_overlaps(ph, ph.by_altitude(on_lines), payload), int(len(own)), _photos_in(zones, photos))


def _measure_step(compiled: Compiled, area_info: AreaInfo, path: np.ndarray | None,
                  photos_of: Mapping[str, Sequence[Photo]], sim: Simulation,
                  grounds: Mapping[str, Any] | None = None) -> StepMeasure:
    """One step's payloads and path, in the simulation's projection. The metres outside the area take the path
    segments the step flew (`path`, a mask over the simulation's segments, `_step_paths`; None: the whole path);
    the metres over its zones the whole flight, whichever step flies there."""
    if not area_info.payloads:
        return StepMeasure(area_info, (), None)
    geom = area_geometry(area_info.area, sim.projection)
    zones = photo_zones(area_info.area, sim.projection)
    own = self_triggering(compiled)
    table = _zone_table(compiled, area_info, geom, photos_of, sim) if area_info.zones is not None else None
    measured = geom if table is None else table.coverable
    payloads = tuple(_measure_payload(area_info, measured, zones, n, compiled.payload(n), photos_of.get(n, []),
                                      (grounds or {}).get(n), n in own) for n in area_info.payloads)
    over_m, over_camera_m = _over_zones_m(sim, zones)
    return StepMeasure(area_info, payloads, StepPath(_outside_m(sim.xy, path, geom), over_m, over_camera_m), table)


def measured_ground(compiled: Compiled, sim: Simulation, payload: str) -> Any | None:
    """The ground the report measures `payload`'s coverage on (shapely, the simulation's metres): the areas of
    the steps it photographs, less what their zones leave uncoverable. None when it photographs no area. A
    coverage measured elsewhere (from the photos a flight took) is comparable with the report's only on this."""
    import shapely   # heavy: loads only when a plan has an area

    photos_of = {p.name: [ph for ph in sim.photos if p.name in ph.payloads] for p in compiled.payloads}
    grounds = []
    for a in compiled.areas:
        if payload not in a.payloads:
            continue
        geom = area_geometry(a.area, sim.projection)
        grounds.append(geom if a.zones is None else _zone_table(compiled, a, geom, photos_of, sim).coverable)
    return shapely.union_all(grounds) if grounds else None


def _footprint_union(ph: _PhotoArrays, idx: np.ndarray, payload: PayloadInfo) -> Any:
    """The ground under the footprints of the photos `idx` (the simulation's metres)."""
    import shapely   # heavy: loads only when a plan has an area
    from shapely.geometry import Polygon

    polys = [footprint_polygons(np.column_stack([ph.x[ks], ph.y[ks]]),
                                np.radians([ph.photos[k].heading_deg for k in ks]),
                                Footprint(*payload.footprint_m(alt))) for alt, ks in ph.by_altitude(idx).items()]
    return shapely.union_all(np.concatenate(polys)) if polys else Polygon()


def _zone_table(compiled: Compiled, area_info: AreaInfo, geom: Any, photos_of: Mapping[str, Sequence[Photo]],
                sim: Simulation) -> ZoneMeasure:
    """The step's zone table (missions.measure.zones): photographed by any photo of the flight, lost as the step's
    lead payload leaves it uncovered."""
    import shapely   # heavy: loads only when a plan has an area

    zones_xy = shapely.union_all([z.xy(sim.projection) for z in area_info.zones.zones])
    everything = []
    for p in compiled.payloads:
        ph = _PhotoArrays.of(photos_of.get(p.name, []))
        everything.append(_footprint_union(ph, ph.reaching(zones_xy, p), p))
    lead = next((n for n in area_info.payloads if any(p.name == n for p in compiled.payloads)), None)
    if lead is None:
        from shapely.geometry import Polygon
        lead_covered = Polygon()
    else:
        ph = _PhotoArrays.of(photos_of.get(lead, []))
        pay = compiled.payload(lead)
        lead_covered = _footprint_union(ph, ph.reaching(geom.union(zones_xy), pay), pay)
    return measure_zones(area_info.zones, area_info.area, sim.projection, sim.xy, lead_covered,
                         shapely.union_all(everything))


def _step_paths(compiled: Compiled, sim: Simulation) -> list[np.ndarray | None]:
    """Per area step, the path segments it flew (a mask over the simulation's segments; None: unknown, a
    hand-built AreaInfo). Segment k (vertex k to k + 1) is flown executing the NAV item of vertex k + 1, so a step's
    path is what it flies towards its own waypoints, the approach to its first one included."""
    seg_item = np.array([v.item for v in sim.vertices[1:]], dtype=int)
    return [None if a.items is None else (seg_item >= a.items[0]) & (seg_item < a.items[1]) for a in compiled.areas]


def _outside_m(xy: np.ndarray, path: np.ndarray | None, geom: Any) -> float:
    """Metres of the path segments `path` selects (None: all) outside `geom`, one polyline per run of them."""
    if path is None:
        return outside_length_m(xy, geom)
    k = np.flatnonzero(path)
    if not len(k):
        return 0.0
    cut = np.flatnonzero(np.diff(k) > 1)
    return sum(outside_length_m(xy[a:b + 2], geom) for a, b in zip(np.r_[k[0], k[cut + 1]], np.r_[k[cut], k[-1]]))


def photo_zones(area: Any, proj: Any) -> Any:
    """The area's holes and exclusion zones as drawn (`Area.excluded`: an exclusion that touches, crosses or
    splits the boundary is no hole of the surveyed geometry) in projection `proj`. An Area built without that
    record (by hand) has only its geometry's holes."""
    import shapely   # heavy: loads only when a plan has an area
    from shapely.geometry import Polygon

    zones = getattr(area, "excluded", None)
    if zones is None:
        holes = [Polygon(r) for p in leaf_parts(area.geometry, "Polygon") for r in p.interiors]
        zones = shapely.union_all(holes) if holes else Polygon()
    if zones.is_empty or area.projection == proj:
        return zones

    def move(xy: np.ndarray) -> np.ndarray:
        lat, lon = area.projection.to_latlon(xy[:, 0], xy[:, 1])
        return np.column_stack(proj.to_xy(lat, lon))

    return shapely.transform(zones, move)


def _over_zones_m(sim: Simulation, zones: Any) -> tuple[float, float]:
    """Metres of the flown path inside `zones`, and how many of them with the camera on. Inside means deeper than
    route.ZONE_EDGE_TOL_M: a path along a zone's edge (a detour inside the area) is beside it."""
    import shapely   # heavy: loads only when a plan has an area

    xy = sim.xy
    if zones.is_empty or len(xy) < 2:
        return 0.0, 0.0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    shapely.prepare(core)
    segs = shapely.linestrings(np.stack([xy[:-1], xy[1:]], axis=1))
    inside = np.zeros(len(segs))
    hit = shapely.intersects(core, segs)
    if hit.any():
        inside[hit] = shapely.length(shapely.intersection(segs[hit], core))
    on = np.zeros(len(segs), bool)
    for stretch in sim.camera_on:
        on[stretch.start:stretch.end] = True
    return float(inside.sum()), float(inside[on].sum())


def _photos_in(zones: Any, photos: Sequence[Photo]) -> int:
    """Photos centred inside `zones` (deeper than the edge tolerance, as for the path)."""
    import shapely   # heavy: loads only when a plan has an area

    if zones.is_empty or not photos:
        return 0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    return int(shapely.contains_xy(core, [p.x for p in photos], [p.y for p in photos]).sum())


# --------------------------------------------------------------------------------------------- the report

def report(compiled: Compiled, sim: Simulation | None = None, plan_path: str | None = None) -> MissionReport:
    """The measured report (its `to_json()` is `wiris mission check --json`)."""
    sim = sim or simulate(compiled)
    names = [p.name for p in compiled.payloads]
    photos_of = {n: [p for p in sim.photos if n in p.payloads] for n in names}
    grounds = _ground_photos(compiled, sim, photos_of)
    steps = [_measure_step(compiled, a, path, photos_of, sim, grounds)
             for a, path in zip(compiled.areas, _step_paths(compiled, sim))]
    rows = tuple(_area_row(s) for s in steps)
    terrain = _ground_report(compiled, sim, photos_of, grounds)
    return MissionReport(
        plan=plan_path or compiled.name,
        name=compiled.name,
        firmware=compiled.firmware,
        frame=compiled.frame,
        mission_items=len(compiled.items),
        item_limit=compiled.item_limit,
        parts=len(compiled.parts),
        part_items=tuple(len(p) for p in compiled.parts),
        photos=_frozen({n: len(photos_of[n]) for n in names}),
        path_length_m=_r(sim.path_length_m, 1),
        climb_m=_r(sim.climb_m, 1),
        flight_time_s=_r(sim.flight_time_s, 1),
        flight_time_qgc_s=_r(sim.flight_time_qgc_s, 1),
        max_altitude_m=_r(max((v.alt_m for v in sim.vertices), default=0.0), 2),
        area_m2=_r(sum(a.area.area_m2 for a in compiled.areas), 1),
        gsd_cm=_gsd_ranges(compiled, photos_of, grounds),
        coverage=_mission_coverage(steps),
        overlap=_mission_overlap(steps),
        areas=rows,
        warnings=tuple(_warnings(compiled, sim, steps, rows)) + _ground_warnings(terrain),
        errors=tuple(_errors(compiled)),
        speed_mps=compiled.speed_mps,
        sun=tuple(compiled.sun),
        steps=step_numbers(compiled, sim),
        sorties=measure_sorties(compiled),
        endurance=compiled.endurance,
        ground=GROUND_FLAT if terrain is None else terrain.ground,
        terrain=terrain,
    )


def _ground_photos(compiled: Compiled, sim: Simulation, photos_of: Mapping[str, Sequence[Photo]]) -> dict[str, Any]:
    """Per payload, its photos over the DEM (heights above ground, footprints cut by the terrain); {} without one."""
    if getattr(compiled, "terrain", None) is None:
        return {}
    from missions.terrain.reflight import ground_photos
    return {n: ground_photos(compiled, sim, photos_of[n], compiled.payload(n)) for n in photos_of}


def _ground_report(compiled: Compiled, sim: Simulation, photos_of: Mapping[str, Sequence[Photo]],
                   grounds: Mapping[str, Any]) -> Any:
    """The terrain section: DEM, minimum clearance, each step's heights above ground (its first payload's)."""
    if not grounds:
        return None
    from missions.terrain.reflight import ground_report, step_ground

    rows = []
    for a in compiled.areas:
        if not a.payloads or a.payloads[0] not in grounds:
            continue
        ph = _PhotoArrays.of(photos_of[a.payloads[0]])
        own = ph.taken_during(a.items) if a.items is not None else np.arange(len(ph.photos))
        rows.append(step_ground(a, compiled.terrain.tolerance_for(a.altitude_m), grounds[a.payloads[0]], own))
    return ground_report(compiled, sim, rows)


def _ground_warnings(terrain: Any) -> tuple[Finding, ...]:
    if terrain is None:
        return ()
    out = [Finding("height_above_ground_off", f"step {s.step}: {s.outside_tolerance} photos are taken outside "
                   f"{s.target_m:g}..{s.target_m + s.tolerance_m:g} m above the ground below them "
                   f"({s.hag_min_m:.1f}..{s.hag_max_m:.1f} m)") for s in terrain.steps if s.outside_tolerance]
    c = terrain.clearance
    if c is not None and c.min_m < terrain.clearance_m - 0.005:
        out.append(Finding("clearance", f"the path passes {c.min_m:.1f} m above the DEM at {c.lat:.6f}, {c.lon:.6f}, "
                                        f"below the {terrain.clearance_m:g} m asked for"))
    return tuple(out)


def _area_row(step: StepMeasure) -> AreaRow:
    a = step.area
    return AreaRow(step=a.step, kind=a.kind, area_m2=_r(a.area.area_m2, 1), altitude_m=_r(a.altitude_m, 2),
                   trigger=a.trigger, requested=RequestedOverlap(a.front_overlap, a.side_overlap),
                   coverage=_frozen({m.name: _r(m.coverage, 5) for m in step.payloads}),
                   overlap=_frozen({m.name: m.overlap.rounded() for m in step.payloads}),
                   photos=_frozen({m.name: m.photos for m in step.payloads}),
                   path=None if step.path is None else step.path.rounded(),
                   photos_in_zones=_frozen({m.name: m.photos_in_zones for m in step.payloads}),
                   zones=step.zones.rows if step.zones else (),
                   coverable_m2=_r(step.zones.coverable.area, 1) if step.zones else None,
                   zone_margin_m=step.zones.margin_m if step.zones else None)


def _mission_coverage(steps: Sequence[StepMeasure]) -> Mapping[str, float]:
    """Per payload, the steps' coverage weighted by their area."""
    by_payload: dict[str, list[tuple[float, float]]] = {}
    for s in steps:
        for m in s.payloads:
            by_payload.setdefault(m.name, []).append((m.coverage, s.area.area.area_m2))

    def weighted(pairs: list[tuple[float, float]]) -> float:
        total_m2 = sum(A for _, A in pairs)
        return _r(sum(c * A for c, A in pairs) / total_m2, 5) if total_m2 > 0 else 0.0

    return _frozen({n: weighted(pairs) for n, pairs in by_payload.items()})


def _mission_overlap(steps: Sequence[StepMeasure]) -> Mapping[str, OverlapMin]:
    """Per payload, the lowest of the steps' overlaps."""
    by_payload: dict[str, list[OverlapMin]] = {}
    for s in steps:
        for m in s.payloads:
            by_payload.setdefault(m.name, []).append(m.overlap)
    return _frozen({n: OverlapMin(_lowest(o.front_min for o in ov), _lowest(o.side_min for o in ov)).rounded()
                    for n, ov in by_payload.items()})


def _gsd_ranges(compiled: Compiled, photos_of: Mapping[str, Sequence[Photo]],
                grounds: Mapping[str, Any] | None = None) -> Mapping[str, GsdRange | None]:
    out: dict[str, GsdRange | None] = {}
    for n, photos in photos_of.items():
        heights = grounds[n].hag_m.tolist() if grounds else [p.alt_m for p in photos]   # above the DEM, or home
        alts = [a for a in heights if a > 0]
        pay = compiled.payload(n)
        out[n] = GsdRange(_r(pay.gsd_cm(min(alts)), 3), _r(pay.gsd_cm(max(alts)), 3)) if alts else None
    return _frozen(out)


def _seq_base(compiled: Compiled) -> int:
    """The mission sequence number of compiled.items[0] as the ground station shows it (ArduPilot's 0 is home)."""
    return 1 if compiled.firmware == "ardupilot" else 0


# --------------------------------------------------------------------------------------------- warnings and errors

def _warnings(compiled: Compiled, sim: Simulation, steps: Sequence[StepMeasure],
              rows: Sequence[AreaRow]) -> list[Finding]:
    """Every warning, in the report's order: the compiler's, each step's measured shortfalls, then the flight's."""
    warnings = [Finding(w.code, w.message) for w in compiled.warnings]
    for step, row in zip(steps, rows):
        warnings.extend(_step_warnings(step, row))
    warnings.extend(_altitude_warnings(compiled, sim))
    warnings.extend(Finding(n.code, n.message) for n in sim.notes)
    if compiled.items and not sim.ends_on_ground:
        warnings.append(Finding("no_landing", "the mission ends in the air (no RTL or LAND): the vehicle will hold "
                                              "at the last waypoint"))
    if len(compiled.parts) > 1 and not any(w.code == "mission_split" for w in warnings):
        warnings.append(Finding("mission_split", f"{len(compiled.items)} items exceed the limit of "
                                                 f"{compiled.item_limit}: split into {len(compiled.parts)} parts, "
                                                 "flown one after another"))
    warnings.extend(_trigger_interval_warnings(compiled, sim))
    if not any(w.code == "assumed_optics" for w in warnings):
        warnings.extend(_optics_warnings(compiled))
    return warnings


def _step_warnings(step: StepMeasure, row: AreaRow) -> list[Finding]:
    """Coverage and overlaps below the step's request (measured, unrounded), and its path over its zones (as
    the row shows it)."""
    a = step.area
    out = []
    for m in step.payloads:
        where = f"step {a.step} ({a.kind}), payload {m.name}"
        front, side = m.overlap.front_min, m.overlap.side_min
        if m.coverage < COVERAGE_TARGET:
            out.append(Finding("coverage_low", f"{where}: measured coverage {100 * m.coverage:.2f} % "
                                               f"(target {100 * COVERAGE_TARGET:.1f} %)"))
        if a.trigger != "hover" and front is not None and front < a.front_overlap - OVERLAP_SLACK:
            out.append(Finding("front_overlap_low", f"{where}: minimum front overlap {100 * front:.1f} % "
                                                    f"< requested {100 * a.front_overlap:.0f} %"))
        if side is not None and side < a.side_overlap - OVERLAP_SLACK:
            out.append(Finding("side_overlap_low", f"{where}: minimum side overlap {100 * side:.1f} % "
                                                   f"< requested {100 * a.side_overlap:.0f} %"))
    if row.path is not None and row.path.over_gaps_m > 1.0:
        out.append(Finding("path_over_exclusion", _over_zones_text(row, row.path)))
    out.extend(Finding(code, msg) for code, msg in photographed_warnings(a.step, a.kind, row.zones))
    return out


def _over_zones_text(row: AreaRow, path: StepPath) -> str:
    """The path_over_exclusion message: how much, and on what — camera-on legs or the flight between them."""
    total, cam = path.over_gaps_m, path.over_gaps_camera_m
    shots = ", ".join(f"{n} {k}" for n, k in row.photos_in_zones.items() if k)
    parts = []
    if cam > 0.05:
        parts.append(f"{cam:.1f} m on camera-on legs" + (f" (photos centred inside: {shots})" if shots else ""))
    if total - cam > 0.05:
        parts.append(f"{total - cam:.1f} m with the camera off: turnarounds, connections, transits, take-off or "
                     "return")
    return (f"step {row.step} ({row.kind}): the flown path runs {total:.0f} m inside the area's holes or exclusion "
            f"zones — {'; '.join(parts)}. Check that overflight is allowed")


def _altitude_warnings(compiled: Compiled, sim: Simulation) -> list[Finding]:
    """The highest vertex above MAX_AGL_M, unless the compiler already warned (with the plan's file:line:col)."""
    if getattr(compiled, "terrain", None) is not None:
        return []        # above home is not above ground: the compiler checks the heights above the DEM
    high = [v for v in sim.vertices if v.alt_m > MAX_AGL_M + 1e-6]
    if not high or any(w.code == "altitude_above_120m" for w in compiled.warnings):
        return []
    v = max(high, key=lambda v: v.alt_m)
    return [Finding("altitude_above_120m", f"item {v.item + _seq_base(compiled)} flies at {v.alt_m:.1f} m above "
                                           f"home, above the {MAX_AGL_M:.0f} m most rules allow without a permit")]


def _trigger_interval_warnings(compiled: Compiled, sim: Simulation) -> list[Finding]:
    """Per payload, the shortest trigger interval below the camera's minimum, and how many more legs are."""
    fast: dict[str, list[tuple[float, int]]] = {}
    for t in sim.trigger_intervals:
        pay = compiled.payload(t.payload)
        if pay.min_interval_s and t.seconds < pay.min_interval_s - 1e-9:
            fast.setdefault(t.payload, []).append((t.seconds, t.item))
    out = []
    for pname, spans in fast.items():
        secs, src = min(spans)
        pay = compiled.payload(pname)
        out.append(Finding("trigger_interval_short",
                           f"{pname} would shoot every {secs:.2f} s ("
                           + (f"item {src + _seq_base(compiled)}" if src >= 0 else "its own overlap mode")
                           + (f" and {len(spans) - 1} more camera-on legs" if len(spans) > 1 else "")
                           + f"), faster than the camera's minimum of {pay.min_interval_s:g} s at "
                             f"{compiled.speed_mps:g} m/s — photos will be lost; fly slower or reduce the front "
                             "overlap"))
    return out


def _errors(compiled: Compiled) -> list[Finding]:
    """What makes the mission unflyable: a part over the vehicle's item limit, no item at all."""
    out = [Finding("item_limit", f"part {k + 1} has {len(part)} items, more than the limit of {compiled.item_limit}")
           for k, part in enumerate(compiled.parts) if len(part) > compiled.item_limit]
    if not compiled.items:
        out.append(Finding("empty_mission", "the mission has no items"))
    return out


def _optics_warnings(compiled: Compiled) -> list[Finding]:
    out: list[Finding] = []
    try:
        cat = catalogue()
    except Exception:  # the catalogue is checked by its own tests; a report still comes out without it
        return out
    for p in compiled.payloads:
        try:
            imager = cat.get(p.camera_id).imager(p.imager)
        except Exception:
            continue
        if imager is not None and imager.assumed:
            out.append(Finding("assumed_optics",
                               f"{p.name}: {', '.join(imager.assumed)} of {p.camera_id}/{p.imager} are assumed, not "
                               "from a published source — footprints, GSD and overlap depend on them; check them "
                               "against your camera's datasheet"))
    return out


# --------------------------------------------------------------------------------------------- text forms

def _overlap_text(ov: OverlapMin) -> tuple[str, str]:
    """Front and side minimum overlap as percent, or a dash where none was measured."""
    f = "–" if ov.front_min is None else f"{100 * ov.front_min:.1f} %"
    s = "–" if ov.side_min is None else f"{100 * ov.side_min:.1f} %"
    return f, s


def _findings_lines(rep: MissionReport) -> list[str]:
    return ([f"warning [{w.code}]: {w.message}" for w in rep.warnings]
            + [f"error [{e.code}]: {e.message}" for e in rep.errors])


def summary_lines(rep: MissionReport) -> list[str]:
    """A few lines for `wiris mission compile`."""
    mins, secs = divmod(int(round(rep.flight_time_s or 0)), 60)
    lines = [f"{rep.name}: {rep.firmware} {rep.frame}, {rep.mission_items} items "
             f"(limit {rep.item_limit}, {rep.parts} {'sorties' if rep.parts != 1 else 'sortie'}), "
             f"{rep.path_length_m / 1000:.2f} km, ~{mins} min {secs:02d} s"]
    for name, n in rep.photos.items():
        extra = ""
        if name in rep.coverage:
            f, s = _overlap_text(rep.overlap[name])
            extra = f", coverage {100 * rep.coverage[name]:.2f} %, min overlap front {f} side {s}"
        lines.append(f"  {name}: {n} photos{extra}")
    lines.extend(f"  {s.summary()}" for s in rep.steps)
    # the steps mostly share their assumptions: each is said once
    assumed = dict.fromkeys(a for s in rep.steps for a in s.facts.assumptions)
    lines.extend(f"  assumes {a}" for a in assumed)
    if rep.sorties is not None:
        lines += ["  " + t for t in table_lines(rep.sorties)]
    return lines + _findings_lines(rep)


def _gsd_text(g: GsdRange | None) -> str:
    if not g:
        return ""
    if abs(g.max_cm - g.min_cm) < 0.005:
        return f", GSD {g.min_cm:.2f} cm/px"
    return f", GSD {g.min_cm:.2f}–{g.max_cm:.2f} cm/px"


def format_report(rep: MissionReport) -> str:
    """The human-readable report of `wiris mission check`."""
    parts = ("fits in one upload)" if rep.parts == 1 else
             f"{rep.parts} sorties of {', '.join(str(n) for n in rep.part_items)} items)")
    rows = [("plan", rep.plan), ("firmware", f"{rep.firmware} {rep.frame}"),
            ("mission items", f"{rep.mission_items} (limit {rep.item_limit}; " + parts),
            ("path length", f"{rep.path_length_m:.0f} m (climb {rep.climb_m:.0f} m)"),
            ("flight time", f"{rep.flight_time_s / 60:.1f} min (QGC's estimate: {rep.flight_time_qgc_s / 60:.1f} min)"),
            ("highest point", f"{rep.max_altitude_m:.1f} m above home"),
            ("area", f"{rep.area_m2:.0f} m² ({rep.area_m2 / 10000:.2f} ha)" if rep.area_m2 else
                     "none (no survey or corridor)")]
    for name, n in rep.photos.items():
        rows.append((f"photos {name}", f"{n}{_gsd_text(rep.gsd_cm.get(name))}"))
    for name, c in rep.coverage.items():
        f, s = _overlap_text(rep.overlap[name])
        rows.append((f"coverage {name}", f"{100 * c:.2f} % (minimum overlap: front {f}, side {s})"))
    for a in rep.areas:
        outside_m = a.path.outside_m if a.path is not None else 0
        rows.append((f"step {a.step} {a.kind}", f"{a.area_m2:.0f} m² at {a.altitude_m:g} m, "
                                                f"{outside_m:.0f} m flown outside the area, overlap asked "
                                                f"front {100 * a.requested.front:g} %, side "
                                                f"{100 * a.requested.side:g} %"))
        numbers = next((s for s in rep.steps if s.facts.step == a.step), None)
        rows += [(f"  {k}", v) for k, v in (numbers.rows() if numbers else [])]
        if a.zones:
            rows.append((f"  zones (margin {a.zone_margin_m:g} m)",
                         f"coverage measured on {a.coverable_m2:.0f} m² that can be covered"))
        for z in a.zones:
            rows.append((f"  {z.kind} {z.name}", f"{z.area_m2:.0f} m², {z.flown_inside_m:.0f} m flown inside, "
                                                 f"{z.photographed_m2:.0f} m² photographed, {z.lost_m2:.0f} m² of "
                                                 "the area lost to it"))
    rows.append(("speed", f"{rep.speed_mps:g} m/s"))
    rows += [(f"sun step {s.step}", _sun_text(s)) for s in rep.sun]
    rows.extend(_ground_rows(rep))
    width = max(len(k) for k, _ in rows)
    out = [f"{k.ljust(width)}  {v}" for k, v in rows]
    if rep.sorties is not None:
        out += table_lines(rep.sorties)
    out += _findings_lines(rep)
    if not rep.warnings and not rep.errors:
        out.append("no warnings")
    return "\n".join(out)


def _sun_text(s: Any) -> str:
    """One line of the sun over a step (missions.thermal.assess.StepSun)."""
    j = s.to_json()
    a, b = j["sun_start"], j["sun_end"]
    text = (f"{j['start'][11:16]}-{j['end'][11:16]} (UTC{j['start'][16:]}), solar time "
            f"{_clock_h(s.solar_time_start_h)}-{_clock_h(s.solar_time_end_h)}: sun at {a['elevation_deg']:.1f}° "
            f"elevation, {a['azimuth_deg']:.0f}° azimuth -> {b['elevation_deg']:.1f}°, {b['azimuth_deg']:.0f}°; "
            f"clear sky {j['clear_sky_min_wm2']:.0f} W/m² or more on the {'modules' if s.plane == 'target' else 'ground'}"
            " (estimate: measure on site)")
    if s.viewing_angle_deg is not None:
        text += f"; camera {s.viewing_angle_deg:.0f}° off the module normal"
    if s.glare_min_deg is not None:
        text += f", sun's reflection {s.glare_min_deg:.0f}° from the view"
    if s.profile:
        text += f"; {s.profile}"
    return text


def _clock_h(h: float) -> str:
    minutes = int(round(h * 60.0)) % (24 * 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}"


def _ground_rows(rep: MissionReport) -> list[tuple[str, str]]:
    """The ground the figures stand on; with a DEM the clearance and each step's heights above ground."""
    rows = [("ground", rep.ground)]
    t = rep.terrain
    if t is None:
        return rows
    c = t.clearance
    if c is not None:
        rows.append(("clearance", f"at least {c.min_m:.1f} m above the DEM (asked {t.clearance_m:g} m; lowest at "
                                  f"{c.lat:.6f}, {c.lon:.6f})"))
    for s in t.steps:
        if s.hag_min_m is not None:
            rows.append((f"step {s.step} above ground", f"{s.hag_min_m:.1f}–{s.hag_max_m:.1f} m (target "
                                                         f"{s.target_m:g} m, tolerance +{s.tolerance_m:g} m)"))
    return rows


def error_report(plan_path: str, err: Exception) -> UncompiledReport:
    """`check --json` for a plan that does not compile (its `to_json()`): the errors located."""
    problems = getattr(err, "problems", None) or [err]
    return UncompiledReport(plan_path, tuple(PlanFinding(getattr(p, "message", str(p)), getattr(p, "where", None),
                                                         getattr(p, "hint", None)) for p in problems))
