"""The audit of a flight against its compiled plan, measured from what was captured (not from the plan):
each photo's footprint at its logged position, height above ground, heading, pitch and roll, measured with the
report's footprint and overlap code (missions.terrain.reflight); coverage, minimum overlaps, photos missing against
the plan's prediction (missions.measure.flight), photos inside the plan's exclusion zones, gaps, and where
the flight left the plan.

    audit = audit_flight(compiled, read_log("flight.tlog"))
    audit.steps[0].coverage, audit.steps[0].gaps, audit.flight.left_plan, audit.to_json()

Height above ground: a plan with a `terrain:` DEM measures each photo over the DEM as its report does
(missions.terrain.reflight): the camera's altitude (the plan's home elevation plus the logged height above
home) less the ground below it, and the footprint where the image's rays meet the DEM, so a photo over a
rising slope covers less than one at the same height above home. Without a DEM the ground is flat at home's
elevation and the footprint is a rectangle at the logged height above home.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.compiled import AreaInfo, Compiled, PayloadInfo
from missions.measure.report import COVERAGE_TARGET, area_geometry, photo_zones
from wiris_tools.audit.logs import FlightLog, Shot
from wiris_tools.errors import LinkError

# A heading change larger than this between consecutive photos starts a new line (a turnaround): the front
# overlap pairs photos of one line only, as the report's does.
LINE_TURN_DEG = 30.0
# A gap smaller than this (m²) is the sliver between two rectangles at a corner, not ground left unseen.
MIN_GAP_M2 = 1.0
# A photo taken this far (m) outside every area is no photo of the survey (take-off, transit).
NEAR_AREA_M = 5.0
# A log whose photos lie farther than this (m) from the plan's home is another flight's.
OTHER_FLIGHT_M = 5000.0


@dataclass(frozen=True)
class Gap:
    """Ground of a step's area under no captured footprint: lat/lon rings (outer first) and its size."""

    rings: tuple[tuple[tuple[float, float], ...], ...]
    area_m2: float

    def to_geojson(self, step: int, payload: str) -> dict:
        return {"type": "Feature", "properties": {"kind": "gap", "step": step, "payload": payload,
                                                  "area_m2": round(self.area_m2, 1)},
                "geometry": {"type": "Polygon",
                             "coordinates": [[[lon, lat] for lat, lon in ring] for ring in self.rings]}}


class _GroundShot(NamedTuple):
    """A captured photo as missions.terrain.reflight reads one: its centre (simulation metres), height above
    home, heading, the stretch it belongs to, and no mission item (its height is above home, not terrain)."""

    x: float
    y: float
    alt_m: float
    heading_deg: float
    span: int
    item: int = -1


@dataclass(frozen=True)
class HeightsAboveGround:
    """The captured photos' heights above the ground below them, from the DEM or above home (flat ground)."""

    source: str                    # "dem" | "home" (flat ground at home's elevation)
    min_m: float | None
    max_m: float | None

    def to_json(self) -> dict:
        r = lambda v: None if v is None else round(v, 2)   # noqa: E731
        return {"source": self.source, "min_m": r(self.min_m), "max_m": r(self.max_m)}


@dataclass(frozen=True)
class Footprints:
    """The captured footprints of one payload over one step, in the audit's projection (shapely polygons)."""

    polygons: Any
    centres: np.ndarray


@dataclass(frozen=True)
class StepAudit:
    step: int
    kind: str
    payload: str
    area_m2: float
    altitude_m: float
    planned: int                       # photos the plan's re-flight predicts for this step
    captured: int                      # photos of this payload whose footprint reaches the area
    missing_planned: int               # predicted photos with no captured photo within half a trigger distance
    coverage: float                    # fraction of the area under the captured footprints
    planned_coverage: float
    front_min: float | None
    side_min: float | None
    requested_front: float
    requested_side: float
    photos_in_zones: int
    gaps: tuple[Gap, ...]
    footprints: Footprints | None = None
    heights: HeightsAboveGround | None = None

    @property
    def gap_m2(self) -> float:
        return sum(g.area_m2 for g in self.gaps)

    def to_json(self) -> dict:
        return {"step": self.step, "kind": self.kind, "payload": self.payload, "area_m2": round(self.area_m2, 1),
                "altitude_m": self.altitude_m, "planned": self.planned, "captured": self.captured,
                "missing_planned": self.missing_planned, "coverage": round(self.coverage, 5),
                "planned_coverage": round(self.planned_coverage, 5),
                "overlap": {"front_min": _r(self.front_min), "side_min": _r(self.side_min),
                            "front_requested": self.requested_front, "side_requested": self.requested_side},
                "photos_in_zones": self.photos_in_zones, "gaps": len(self.gaps), "gap_m2": round(self.gap_m2, 1),
                "height_above_ground": None if self.heights is None else self.heights.to_json()}


@dataclass(frozen=True)
class FlightAudit:
    """How the flight went against the plan, from the log's modes and mission items."""

    modes: tuple[str, ...]             # the mode sequence while armed
    sorties: int                       # armed periods (more than one: landed and flew again, e.g. a battery swap)
    last_item: int | None              # the highest mission item reached, counted from 1 (None: no mission progress)
    mission_items: int                 # the plan's
    left_plan: tuple[str, ...]         # what took the vehicle off its plan, as sentences

    def to_json(self) -> dict:
        return {"modes": list(self.modes), "sorties": self.sorties, "last_item": self.last_item,
                "mission_items": self.mission_items, "left_plan": list(self.left_plan)}


@dataclass(frozen=True)
class Audit:
    plan: str
    log: str
    log_kind: str
    photos_source: str                 # "captures" (the camera's reports) or "triggers" (the autopilot's only)
    triggered: int | None              # None: the log has no trigger record
    captured: int | None               # None: the log has no capture record
    failed: int                        # captures the camera reported as failed
    triggered_not_captured: tuple[int, ...]   # trigger numbers with no capture within TIME_PAIR_S
    captured_not_triggered: tuple[int, ...]   # image indices with no trigger near them (captured, not logged)
    steps: tuple[StepAudit, ...]
    flight: FlightAudit
    notes: tuple[str, ...]
    images: Any = None                 # wiris_tools.audit.images.ImageMatch when a folder of images was given

    @property
    def complete(self) -> bool:
        return all(s.coverage >= COVERAGE_TARGET for s in self.steps)

    def to_json(self) -> dict:
        return {"plan": self.plan, "log": self.log, "log_kind": self.log_kind, "photos_source": self.photos_source,
                "triggered": self.triggered, "captured": self.captured, "failed": self.failed,
                "triggered_not_captured": list(self.triggered_not_captured),
                "captured_not_triggered": list(self.captured_not_triggered),
                "complete": self.complete, "coverage_target": COVERAGE_TARGET,
                "steps": [s.to_json() for s in self.steps], "flight": self.flight.to_json(),
                "images": None if self.images is None else self.images.to_json(), "notes": list(self.notes)}


def _r(v: float | None) -> float | None:
    return None if v is None else round(v, 4)


# Trigger and capture of one photo are this close in time (s): the camera answers within its capture time.
TIME_PAIR_S = 1.5


def _pair(triggers: Sequence[Shot], captures: Sequence[Shot]) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Triggers with no capture, captures with no trigger (their logged numbers, or places), one to one. A
    capture pairs with the unpaired trigger nearest to it in position among those logged within TIME_PAIR_S of
    it: the two messages travel different links and arrive in either order, but the vehicle stood where the
    camera says it took the photo (a dropped photo's trigger lies a trigger distance away)."""
    from missions.geometry.geo import great_circle_m
    used = [False] * len(triggers)
    lone_captures = []
    for c, cap in sorted(enumerate(captures), key=lambda kc: kc[1].pose.time_s):
        t = cap.pose.time_s
        near = [k for k, tr in enumerate(triggers) if not used[k] and abs(tr.pose.time_s - t) <= TIME_PAIR_S]
        if not near:
            lone_captures.append(cap.seq if cap.seq is not None else c)
            continue
        best = min(near, key=lambda k: great_circle_m(cap.pose.lat, cap.pose.lon, triggers[k].pose.lat,
                                                      triggers[k].pose.lon))
        used[best] = True
    lone_triggers = [tr.seq if tr.seq is not None else k for k, tr in enumerate(triggers) if not used[k]]
    return tuple(lone_triggers), tuple(lone_captures)


def _lines(headings: np.ndarray, flights: np.ndarray) -> np.ndarray:
    """A line number per photo: a new line where the heading turns more than LINE_TURN_DEG, and where the
    photos of another flight (log) begin."""
    if len(headings) == 0:
        return np.zeros(0, int)
    turn = np.degrees(np.abs(np.angle(np.exp(1j * np.radians(np.diff(headings))))))
    return np.concatenate([[0], np.cumsum((turn > LINE_TURN_DEG) | (np.diff(flights) != 0))]).astype(int)


def _tilted_centres(xy: np.ndarray, alt: np.ndarray, heading: np.ndarray, pitch: np.ndarray,
                    roll: np.ndarray) -> np.ndarray:
    """Where the optical axis meets flat ground: a camera fixed to the airframe (no gimbal logged) looks ahead
    by alt·tan(pitch) (nose down = behind) and to the right by alt·tan(roll)."""
    h = np.radians(heading)
    d = np.column_stack([np.sin(h), np.cos(h)])
    n = np.column_stack([np.cos(h), -np.sin(h)])
    ahead = alt * np.tan(np.radians(pitch))
    right = alt * np.tan(np.radians(roll))
    return xy + d * ahead[:, None] + n * right[:, None]


class _Measured(NamedTuple):
    covered: Any                       # the union of the footprints (shapely)
    centres: np.ndarray                # where each photo's optical axis meets the ground, projection metres
    front_min: float | None
    side_min: float | None
    heights: HeightsAboveGround


def _footprints(shots: Sequence[Shot], proj: Any, info: PayloadInfo, fallback_alt_m: float,
                fallback_heading: np.ndarray, mount: str, over_dem: Any = None) -> _Measured:
    """The shots' footprints, their union and minimum overlaps: over the DEM when `over_dem` is (compiled,
    sim) of a plan with one, else on flat ground at home's elevation."""
    lat = np.array([s.pose.lat for s in shots])
    lon = np.array([s.pose.lon for s in shots])
    x, y = proj.to_xy(lat, lon)
    xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)]).reshape(-1, 2)
    alt = np.array([s.pose.alt_rel_m if s.pose.alt_rel_m is not None else fallback_alt_m for s in shots], float)
    heading = np.array([s.pose.heading_deg if s.pose.heading_deg is not None else fallback_heading[k]
                        for k, s in enumerate(shots)], float)
    # a gimbal holds the camera at nadir whatever the airframe does; a fixed mount tilts with it; an image's own
    # gimbal angles say where that camera looked
    tilt = [mount == "fixed" or s.oriented for s in shots]
    pitch = np.array([(s.pose.pitch_deg or 0.0) if tilt[k] else 0.0 for k, s in enumerate(shots)], float)
    roll = np.array([(s.pose.roll_deg or 0.0) if tilt[k] else 0.0 for k, s in enumerate(shots)], float)
    centres = _tilted_centres(xy, alt, heading, pitch, roll)
    shots_xy = [_GroundShot(float(centres[k, 0]), float(centres[k, 1]), float(alt[k]), float(heading[k]), int(span))
                for k, span in enumerate(_lines(heading, np.array([s.flight for s in shots], int)))]
    if over_dem is not None:
        from missions.terrain.reflight import ground_photos
        gp, source = ground_photos(*over_dem, shots_xy, info), "dem"
    else:
        from missions.terrain.reflight import flat_ground_photos
        gp, source = flat_ground_photos(centres, alt, heading, info), "home"
    return _measure(shots_xy, gp, source, info)


def _measure(shots: Sequence[_GroundShot], gp: Any, source: str, info: PayloadInfo) -> _Measured:
    """Union and minimum overlaps of the footprints of photos taken above the ground (missions.terrain.reflight:
    front between consecutive photos of a line, side to the nearest photo of another line)."""
    import shapely
    from missions.terrain import reflight
    centres = np.array([(p.x, p.y) for p in shots], float).reshape(-1, 2)
    up = np.flatnonzero(gp.hag_m > 0) if len(shots) else np.zeros(0, int)
    covered = shapely.union_all(gp.polygons[up]) if len(up) else shapely.Polygon()
    hag = gp.hag_m[np.isfinite(gp.hag_m)] if len(shots) else np.zeros(0)
    return _Measured(covered, centres, reflight.min_front_overlap(shots, gp, up),
                     reflight.min_side_overlap(shots, gp, up, info),
                     HeightsAboveGround(source, float(hag.min()) if len(hag) else None,
                                        float(hag.max()) if len(hag) else None))


def _gaps(geom: Any, covered: Any, proj: Any) -> tuple[Gap, ...]:
    from missions.geometry.geo import leaf_parts
    rest = geom.difference(covered)
    out = []
    for part in leaf_parts(rest, "Polygon"):
        if part.area < MIN_GAP_M2:
            continue
        rings = []
        for ring in (part.exterior, *part.interiors):
            xs, ys = np.asarray(ring.coords).T
            la, lo = proj.to_latlon(xs, ys)
            rings.append(tuple((float(a), float(o)) for a, o in zip(la, lo)))
        out.append(Gap(tuple(rings), float(part.area)))
    return tuple(sorted(out, key=lambda g: -g.area_m2))


def _predicted_heading(sim_xy: np.ndarray, sim_heading: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """For photos without a logged heading: the heading of the nearest photo the plan predicts."""
    if len(sim_xy) == 0 or len(xy) == 0:
        return np.zeros(len(xy))
    d = np.hypot(xy[:, None, 0] - sim_xy[None, :, 0], xy[:, None, 1] - sim_xy[None, :, 1])
    return sim_heading[d.argmin(axis=1)]


def _audit_step(area: AreaInfo, name: str, info: PayloadInfo, shots: Sequence[Shot], sim: Any,
                planned_cov: float, mount: str, over_dem: Any = None,
                expected: Sequence[Any] | None = None) -> StepAudit:
    """`expected`: the photos this flight was to take, in the whole mission's terms (a sortie's); None: all the
    plan's."""
    import shapely
    proj = sim.projection
    geom = area_geometry(area.area, proj)
    zones = photo_zones(area.area, proj)
    photos = sim.photos if expected is None else expected
    predicted = [p for p in photos if name in p.payloads
                 and (area.items is None or area.items[0] <= p.item < area.items[1])]
    pred_xy = np.array([(p.x, p.y) for p in predicted], float).reshape(-1, 2)
    all_pred = [p for p in sim.photos if name in p.payloads]
    lat = np.array([s.pose.lat for s in shots])
    lon = np.array([s.pose.lon for s in shots])
    sx, sy = proj.to_xy(lat, lon) if len(shots) else (np.zeros(0), np.zeros(0))
    raw_xy = np.column_stack([np.asarray(sx, float), np.asarray(sy, float)]).reshape(-1, 2)
    reach = max(info.footprint_m(area.altitude_m)) + NEAR_AREA_M
    near = [k for k in range(len(shots)) if shapely.dwithin(shapely.Point(raw_xy[k]), geom, reach)]
    mine = [shots[k] for k in near]
    fallback = _predicted_heading(np.array([(p.x, p.y) for p in all_pred], float).reshape(-1, 2),
                                  np.array([p.heading_deg for p in all_pred], float), raw_xy[near])
    measured = _footprints(mine, proj, info, area.altitude_m, fallback, mount, over_dem)
    covered, centres = measured.covered, measured.centres
    cov = float(shapely.intersection(geom, covered).area / geom.area) if mine and geom.area > 0 else 0.0
    trig = area.trigger_distance_m or info.footprint_m(area.altitude_m)[1]
    missing = 0
    if len(pred_xy):
        if len(raw_xy):
            d = np.hypot(pred_xy[:, None, 0] - raw_xy[None, :, 0], pred_xy[:, None, 1] - raw_xy[None, :, 1])
            missing = int((d.min(axis=1) > trig / 2).sum())
        else:
            missing = len(pred_xy)
    in_zones = 0
    if not zones.is_empty and len(centres):
        in_zones = int(shapely.contains_xy(zones, centres[:, 0], centres[:, 1]).sum())
    return StepAudit(area.step, area.kind, name, float(geom.area), area.altitude_m, len(predicted), len(mine),
                     missing, cov, planned_cov, measured.front_min, measured.side_min, area.front_overlap,
                     area.side_overlap, in_zones, _gaps(geom, covered, proj),
                     Footprints(covered, centres), measured.heights)


def _flight(compiled: Compiled, log: FlightLog, items: int | None = None) -> FlightAudit:
    """`items`: how many mission items the flight flew (a sortie's); None: the whole mission's."""
    armed_modes = [m for m in log.modes if m.armed]
    sorties = sum(1 for a, b in zip([False] + [m.armed for m in log.modes], [m.armed for m in log.modes])
                  if b and not a)
    # ArduPilot numbers the uploaded items from 1 (home is its item 0), PX4 from 0: counted from 1 here
    first = 0 if compiled.firmware == "px4" else 1
    seq = [s - first + 1 for _, s in log.mission_seq]
    last = max(seq) if seq else None
    n = len(compiled.items) if items is None else items
    left: list[str] = []
    names = []
    for m in armed_modes:
        if not names or names[-1] != m.mode:
            names.append(m.mode)
    auto = [k for k, m in enumerate(names) if "AUTO" in m.upper() or "MISSION" in m.upper()]
    if auto:
        after = names[auto[0] + 1:]
        unfinished = last is not None and last < n
        for mode in after:
            if "RTL" in mode.upper() and unfinished:
                left.append(f"RTL before the mission's end (last item reached {last} of {n})")
            elif "LAND" in mode.upper() and unfinished:
                left.append(f"LAND before the mission's end (last item reached {last} of {n})")
            elif not any(w in mode.upper() for w in ("AUTO", "MISSION", "RTL", "LAND")):
                left.append(f"switched to {mode} during the mission")
    elif log.modes:
        left.append("the log shows no AUTO mission flight")
    if sorties > 1:
        left.append(f"{sorties} armed periods: the vehicle landed and flew again (a battery swap?)")
    if last is not None and last < n and not any("before the mission's end" in s for s in left):
        left.append(f"the mission was not finished: last item reached {last} of {n} (aborted or log cut short)")
    return FlightAudit(tuple(names), sorties, last, n, tuple(left))


def sortie_photos(compiled: Compiled, sortie: Any) -> list:
    """The photos a sortie's own re-flight takes, in the whole mission's terms (items mapped through its origin)."""
    from missions.measure.flight import simulate
    from missions.sorties import as_sortie, union_photos
    sim = sortie.flight if sortie.flight is not None else simulate(as_sortie(compiled, sortie.items))
    return union_photos(compiled, [sortie], [sim])


def _check_same_flight(compiled: Compiled, log: FlightLog, shots: Sequence[Shot]) -> None:
    from missions.geometry.geo import great_circle_m
    lat, lon, _ = compiled.home
    poses = [s.pose for s in shots] if shots else list(log.track)
    if not poses:
        return
    near = min(great_circle_m(lat, lon, p.lat, p.lon) for p in poses)
    if near > OTHER_FLIGHT_M:
        raise LinkError(f"the log's positions lie {near / 1000:.1f} km from the plan's home: a log of another "
                        "flight", where=log.path, hint="give the log of the flight of this plan")


MOUNTS = ("gimbal", "fixed")


def audit_flight(compiled: Compiled, log: FlightLog, plan_path: str = "", mount: str = "gimbal",
                 images: Sequence[Any] | None = None, sortie: Any = None) -> Audit:
    """The audit of `log` against `compiled`. Raises LinkError where nothing can be said (no photo record at
    all, another flight's log). `mount`: "gimbal" (the camera looks at nadir, the footprint turns with the
    heading only) or "fixed" (to the airframe: its logged pitch and roll move the footprint). `images`
    (wiris_tools.audit.images.ImageFile, the flight's folder): matched to the captures; a matched image's
    gimbal angles place its photo's footprint instead of the log's attitude. `sortie` (missions.sorties.Sortie):
    the log flew that sortie only: the photos missing are counted against its re-flight, the mission's progress
    against its items; coverage stays that of the plan's whole areas."""
    from missions.measure.flight import simulate
    from missions.measure.report import report

    all_captures, matched, oriented = list(log.captures), None, 0
    if images is not None:
        from wiris_tools.audit.images import match_images, oriented_by_images
        matched = match_images(images, all_captures)
        all_captures = oriented_by_images(all_captures, images, matched)
        oriented = sum(1 for s in all_captures if s.oriented)
    captures = [s for s in all_captures if s.ok]
    failed = sum(1 for s in all_captures if not s.ok)
    if captures:
        shots, source = captures, "captures"
    elif log.triggers:
        shots, source = list(log.triggers), "triggers"
    else:
        raise LinkError("the log has no camera messages (no CAMERA_IMAGE_CAPTURED, CAMERA_FEEDBACK, CAM/TRIG or "
                        "camera_capture): nothing can be said about the photos", where=log.path,
                        hint="log the camera's messages (a GCS tlog, LOG_BITMASK with camera), or give the images")
    _check_same_flight(compiled, log, shots)
    sim = simulate(compiled)
    rep = report(compiled, sim)
    expected = None if sortie is None else sortie_photos(compiled, sortie)
    steps = []
    for area in compiled.areas:
        for name in area.payloads:
            planned_cov = float("nan") if sortie is not None else next(
                (r.coverage.get(name, float("nan")) for r in rep.areas if r.step == area.step), float("nan"))
            steps.append(_audit_step(area, name, compiled.payload(name), shots, sim, planned_cov, mount,
                                     (compiled, sim) if compiled.terrain is not None else None, expected))
    notes = list(log.notes)
    if oriented:
        notes.append(f"{oriented} photo(s) placed by their image's gimbal angles (XMP) instead of the log's attitude")
    if source == "triggers":
        notes.append("no capture acknowledgements in the log: footprints are the autopilot's triggers, whether "
                     "the camera took them is unknown")
    trig = list(log.triggers)
    return Audit(plan_path or compiled.name, log.path, log.kind, source,
                 len(trig) if trig else None, len(log.captures) if log.captures else None, failed,
                 *(_pair(trig, captures) if trig and captures else ((), ())),
                 tuple(steps), _flight(compiled, log, None if sortie is None else len(sortie.items)),
                 tuple(notes), matched)


def _heights_text(h: HeightsAboveGround | None) -> str:
    if h is None or h.min_m is None:
        return ""
    where = "above the DEM" if h.source == "dem" else "above home (flat ground)"
    return f"; height {h.min_m:.1f}-{h.max_m:.1f} m {where}"


def gap_geojson(audit: Audit) -> dict:
    feats = [g.to_geojson(s.step, s.payload) for s in audit.steps for g in s.gaps]
    return {"type": "FeatureCollection", "features": feats}


def format_audit(audit: Audit, verdict: bool = True) -> str:
    """The audit as text; `verdict`: end with whether the plan's areas are covered (a sortie alone is not)."""
    def pct(v: float | None) -> str:
        return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.1f} %"
    lines = [f"audit of {audit.log} ({audit.log_kind}) against {audit.plan}",
             f"  triggered: {'unknown' if audit.triggered is None else audit.triggered}   "
             f"captured: {'unknown' if audit.captured is None else audit.captured}"
             + (f"   failed: {audit.failed}" if audit.failed else "")]
    if audit.triggered_not_captured:
        lines.append(f"  triggered but not captured: {len(audit.triggered_not_captured)} "
                     f"(trigger {', '.join(map(str, audit.triggered_not_captured[:20]))})")
    if audit.captured_not_triggered:
        lines.append(f"  captured but not logged as triggered: {len(audit.captured_not_triggered)}")
    for s in audit.steps:
        lines.append(f"  step {s.step} {s.kind} [{s.payload}]: planned {s.planned}, captured {s.captured}, "
                     f"missing {s.missing_planned}; coverage {pct(s.coverage)} (plan {pct(s.planned_coverage)}); "
                     f"front min {pct(s.front_min)} / {100 * s.requested_front:.0f} %, side min {pct(s.side_min)} "
                     f"/ {100 * s.requested_side:.0f} %; gaps {len(s.gaps)} ({s.gap_m2:.0f} m²)"
                     + (f"; {s.photos_in_zones} photo(s) in no-photo zones" if s.photos_in_zones else "")
                     + _heights_text(s.heights))
    f = audit.flight
    lines.append(f"  flight: modes {' > '.join(f.modes) or 'unknown'}; last item "
                 f"{'unknown' if f.last_item is None else f.last_item} of {f.mission_items}")
    lines += [f"  left the plan: {s}" for s in f.left_plan]
    if audit.images is not None:
        im = audit.images
        lines.append(f"  images: {im.images} in the folder, {im.matched} matched by {im.by}; "
                     f"{len(im.without_log_entry)} without a log entry, {len(im.captured_without_image)} "
                     "captured but not in the folder")
    lines += [f"  note: {n}" for n in audit.notes]
    if verdict:
        lines.append("  complete" if audit.complete else "  INCOMPLETE: fly the refly plan")
    return "\n".join(lines)
