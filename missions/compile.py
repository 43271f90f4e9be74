"""compile_plan: capture plan -> Compiled (mission items, parts, setup sequence, Lua bridge, params, warnings).

    compiled = compile_plan("plan.yaml")                 # the plan's firmware
    compiled = compile_plan(plan, firmware="px4")        # a loaded Plan, another firmware

Pipeline, as `compile_plan` reads: load (schema, locations) -> the payloads' cameras and optics -> per step, the
function `_STEPS` names for its type: a survey or corridor goes area -> geometry (missions.geometry.survey,
missions.geometry.corridor) -> items (missions.emit.emitter, firmware × camera) -> firmware check
(missions.emit.firmware) -> item limit / parts -> setup sequence (missions.emit.setup) -> Lua bridge
(missions.emit.lua) -> autopilot params (missions.emit.params) -> warnings -> fence (the survey steps' exclusion
zones and the plan's inclusion fence, missions.geometry.fence). What the steps add up as they go
(warnings, areas, altitudes, what the RedEdges fly) is one `_State`, local to the compile. Pure: no sockets, no
files written; errors are PlanError with the plan's file:line:col.

Warnings are `PlanWarning(code, message)` values. Codes: altitude_above_120m, assumed_optics, trigger_interval_near_min,
area_smaller_than_footprint (and the survey planner's own codes), no_takeoff, component_id_chosen,
no_optics, mission_split, px4_single_capture_all; with a DEM (missions.terrain) terrain_rate_limited,
home_elevation_differs, rededge_over_terrain.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from pathlib import Path

import numpy as np
from typing import Any, Callable, NamedTuple

from pymavlink.dialects.v20 import common as mavlink

from cdf.catalogue import catalogue
from missions.compiled import (AreaInfo, CaptureSize, Compiled, PayloadInfo, PlanWarning, SetupStep, StepFacts,
                               TransectPattern)
from missions.emit.emitter import Emitted, Emitter, Track, TrackPoint, HOVER_HOLD_S
from missions.emit.firmware import FirmwareProfile, check_items, profile
from missions.emit.items import MissionItem
from missions.emit.lua import render_script
from missions.emit.params import Param, autopilot_params
from missions.emit.setup import RedEdgeSurvey, setup_steps
from missions.errors import PlanError, Problem
from missions.geometry import optics, survey
from missions.geometry.area import Area
from missions.geometry.corridor import CorridorPlan, plan_corridor
from missions.geometry.footprint import Footprint
from missions.geometry.geo import MAX_EXTENT_M, LocalProjection
from missions.geometry.survey import DEFAULT_EXIT_MARGIN_M, SurveyPlan, plan_survey
from missions.geometry.zones import (RESUME_MARGIN_M, CameraPoint, StepZones, TransitRouter, Zone, ZoneRouter, area_clear_of,
                                     capture_reaches, grown_union, keep_path_out, keep_photos_out, path_inside,
                                     place_zones, plan_zones, zones_near)
from missions.plan.load import (CameraStep, CorridorStep, LandStep, Plan, RtlStep, SurveyStep, TakeoffStep,
                                WaypointStep, input_files, load_plan_partly, raise_problems)
from missions.plan.meaning import Ceiling, ceiling_problem
from missions.sorties import in_sorties
from missions.plan_turns import default_turnaround_m, line_end, turn_radius_of, turn_warnings
from missions.plan.schema import MAX_AGL_M, MAX_ALTITUDE_M, MIN_ALTITUDE_M, SPEED_RANGE_MPS
from missions.thermal.assess import assess
from missions.thermal.speed import SpeedLimit, check_sharp, choose_speed, line_limits

NEAR_MIN_INTERVAL = 1.2      # warn when photos come less than 20 % slower than the camera's minimum
TURNAROUND_DEFAULT_M = {"copter": 10.0, "plane": 30.0, "vtol": 30.0}   # QGC's defaults (survey-planners §1.4)


# ------------------------------------------------------------------------------------------------ values

class _Altitude(NamedTuple):
    """An altitude the mission flies at, and where the plan sets it."""

    altitude_m: float
    where: str


class _RedEdgeFlight(NamedTuple):
    """A survey or corridor a RedEdge flies: its one overlap mode must cover them all (`_rededge_survey`)."""

    altitude_m: float
    front_pct: float
    side_pct: float


class _RedEdgeCheck(NamedTuple):
    """A RedEdge flying beside another payload's lines: it captures by its own footprint and front overlap, so
    its interval at this altitude is checked once its overlap (the most demanding of its surveys) is known."""

    payload: str
    altitude_m: float
    where: str


@dataclass(frozen=True)
class _Payloads:
    """The plan's payloads as the catalogue resolves them, by payload name."""

    cameras: dict[str, Any]                  # catalogue Camera
    instances: dict[str, int]                # ArduPilot CAMn instance (WIRIS only)
    optics: dict[str, PayloadInfo]           # payloads whose optics are known
    optics_errors: dict[str, PlanError]      # the others: an error only where a footprint is needed

    def is_rededge(self, name: str) -> bool:
        """A RedEdge triggers itself (overlap mode): no trigger items, no AP_Camera instance."""
        return self.cameras[name].protocol == "rededge-serial"


@dataclass
class _State:
    """Mutable bookkeeping of one compile (local to `compile_plan`, never shared), added to step by step."""

    warnings: list[PlanWarning | str]
    areas: list[AreaInfo] = field(default_factory=list)
    intent: list[SurveyPlan | CorridorPlan] = field(default_factory=list)
    patterns: list[TransectPattern] = field(default_factory=list)
    altitudes: list[_Altitude] = field(default_factory=list)
    rededge_flights: dict[str, list[_RedEdgeFlight]] = field(default_factory=dict)
    rededge_checks: list[_RedEdgeCheck] = field(default_factory=list)
    # each payload's settings as the camera holds them at this point of the mission (wire values by key)
    settings_now: dict[str, dict[str, float | int]] = field(default_factory=dict)
    step_facts: list[StepFacts] = field(default_factory=list)


@dataclass(frozen=True)
class _Compile:
    """One compile: what every step reads (plan, firmware, payloads) and what it adds to (emitter, state)."""

    plan: Plan
    profile: FirmwareProfile
    payloads: _Payloads
    emitter: Emitter
    state: _State
    speed_mps: float                         # the plan's, or the one `auto` chose (`_mission_speed`)
    turn_radius_m: float | None = None       # a plane's or VTOL's (`missions.plan_turns.turn_radius_of`)
    zones: tuple[Zone, ...] = ()             # every zone of the plan (missions.geometry.zones.plan_zones)
    transits: TransitRouter | None = None    # routes the flight between steps around the no-fly zones
    terrain: Any = None                      # missions.terrain.model.Terrain when the plan names a DEM

    def warn(self, code: str, message: str) -> None:
        self.state.warnings.append(PlanWarning(code, message))


class _LineInputs(NamedTuple):
    """What the survey and corridor planners take beside the step's own fields."""

    footprint: Footprint
    turnaround_m: float
    start_latlon: tuple[float, float]        # where the vehicle is when the lines begin
    photos_left: int                         # of MAX_PHOTOS, after the plan's earlier lines
    min_interval_s: float | None


class _Lines(NamedTuple):
    """A planned survey or corridor and the area it covers (what the report measures against)."""

    route: SurveyPlan | CorridorPlan
    area: Area


# ----------------------------------------------------------------------------------------------- helpers

def _relocate(err: PlanError, where: str) -> PlanError:
    """Geometry errors name a field ("overlap.front") or nothing; give them the plan's file:line:col."""
    w = err.where
    if w is None or (":" not in w and "/" not in w and not w.endswith((".kml", ".geojson", ".json"))):
        new = PlanError(err.message, where=where + (f" ({w})" if w else ""), hint=err.hint)
        return new
    return err


def _check_reach(home: Any, lat: float, lon: float, what: str, where: str) -> None:
    """A step must lie within MAX_EXTENT_M of home, like an area's own extent: farther is a typo in a
    coordinate, and the flight there (along which a RedEdge keeps shooting) would be thousands of km."""
    from pyproj import Geod   # heavy: loads only for a plan with a positioned step

    distance = Geod(ellps="WGS84").inv(home.lon, home.lat, lon, lat)[2]
    if not distance <= MAX_EXTENT_M:
        raise PlanError(f"this {what} lies {distance / 1000:,.0f} km from home, more than the "
                        f"{MAX_EXTENT_M / 1000:.0f} km one plan may reach", where=where,
                        hint="check the coordinates of home and of this step (latitude and longitude swapped?)")


def _rededge_survey(flights: list[_RedEdgeFlight]) -> RedEdgeSurvey:
    """The RedEdge overlap-mode parameters covering every survey it flies, in the camera's integers: it captures
    from operatingAlt - opAltTolerance up, so the target is the lowest survey altitude (rounded down: were the
    camera to space its captures by the target altitude's footprint, higher surveys only gain overlap) and the
    tolerance reaches a margin below it, so that it does not shoot while climbing (a quarter of the altitude, at
    least 10 m: our choice, not MicaSense's). The overlaps are the most demanding of the surveys (rounded up)."""
    lowest = min(f.altitude_m for f in flights)
    target = max(int(math.floor(lowest)), 1)
    threshold = lowest - max(10.0, 0.25 * lowest)
    return RedEdgeSurvey(target, max(int(math.ceil(target - threshold)), 0),
                         int(math.ceil(max(f.front_pct for f in flights))),
                         int(math.ceil(max(f.side_pct for f in flights))))


# -------------------------------------------------------------------------------------- before the steps

def _resolve_payloads(plan: Plan, prof: FirmwareProfile, state: _State) -> _Payloads:
    """Each payload's catalogue camera, ArduPilot instance and optics (their warnings go to `state`)."""
    cat = catalogue()
    cameras = {p.name: cat.get(p.camera) for p in plan.payloads}
    # ArduPilot drives each WIRIS as an AP_Camera instance (CAMn_TYPE 6); the RedEdge is not one (it triggers
    # itself). PX4 addresses cameras by component id instead.
    wiris = [p.name for p in plan.payloads if cameras[p.name].protocol != "rededge-serial"]
    if len(wiris) > prof.max_camera_instances:
        raise PlanError(f"{prof.title} drives at most {prof.max_camera_instances} MAVLink cameras (CAM1..CAM"
                        f"{prof.max_camera_instances}); the plan has {len(wiris)}", where=plan.where("payloads"),
                        hint="fly fewer WIRIS payloads")
    known: dict[str, PayloadInfo] = {}
    unknown: dict[str, PlanError] = {}
    for p in plan.payloads:
        try:
            info, warn = optics.payload_info(p, cameras[p.name], where=plan.where("payloads", p.name))
            known[p.name] = info
            state.warnings.extend(warn)
        except PlanError as e:
            unknown[p.name] = e
    return _Payloads(cameras, _camera_instances(plan, prof, wiris), known, unknown)


def _camera_instances(plan: Plan, prof: FirmwareProfile, wiris: list[str]) -> dict[str, int]:
    """Each WIRIS payload's ArduPilot camera instance (CAMn). ArduPilot's MAVLinkCamV2 backend looks for
    instance n at component 100 + n - 1 only (AP_Camera_MAVLinkCamV2::find_camera), so the instance follows
    from the component id; a camera at a component no instance looks at would never be found and would take
    no photo, silently: refused. PX4 addresses cameras by component id (the numbers are only an order)."""
    if prof.camera_target != "instance":
        return {name: i + 1 for i, name in enumerate(wiris)}
    out: dict[str, int] = {}
    for name in wiris:
        component = plan.payload(name).component_id
        instance = component - mavlink.MAV_COMP_ID_CAMERA + 1
        if not 1 <= instance <= prof.max_camera_instances:
            last = mavlink.MAV_COMP_ID_CAMERA + prof.max_camera_instances - 1
            raise PlanError(f"{prof.title} would never find {name} at component {component}: its MAVLinkCamV2 "
                            f"backend looks for camera instance n at component 100 + n - 1 only, and it has "
                            f"CAM1..CAM{prof.max_camera_instances} (components 100..{last})",
                            where=plan.where("payloads", name, "component_id"),
                            hint=f"set the camera's MAVLink id (camera menu) to one of 100..{last} and "
                                 "component_id to the same")
        out[name] = instance
    return out


def _emitter(plan: Plan, prof: FirmwareProfile, payloads: _Payloads, speed_mps: float) -> Emitter:
    return Emitter(prof, plan.vehicle.frame, speed_mps, (plan.home.lat, plan.home.lon),
                   payloads.cameras, {p.name: p.component_id for p in plan.payloads}, payloads.instances,
                   {p.name: dict(p.values) for p in plan.payloads})


def _warn_about_the_start(c: _Compile) -> None:
    if c.emitter.speed_is_airspeed:
        c.warn("speed_is_airspeed", f"ArduPilot flies a {c.plan.vehicle.frame}'s vehicle.speed_mps "
               f"({c.speed_mps:g} m/s) as airspeed (a ground-speed DO_CHANGE_SPEED would set its minimum ground "
               "speed instead); with wind the ground speed differs, so photo intervals and flight time vary "
               "(distance triggering keeps its spacing)")
    if not any(isinstance(s, TakeoffStep) for s in c.plan.mission):
        c.warn("no_takeoff", "the mission has no takeoff step; it must be started with the vehicle in the air")


# ------------------------------------------------------------------------------------------------- steps

def _takeoff(c: _Compile, step: TakeoffStep) -> None:
    c.emitter.takeoff(step.alt_m)
    c.state.altitudes.append(_Altitude(step.alt_m, c.plan.step_where(step, "alt_m")))


def _waypoint(c: _Compile, step: WaypointStep) -> None:
    _check_reach(c.plan.home, step.lat, step.lon, "waypoint", c.plan.step_where(step))
    _transit_to(c, step.lat, step.lon, step.alt_m, "flight to this waypoint", c.plan.step_where(step))
    c.emitter.waypoint(step.lat, step.lon, step.alt_m, step.hold_s, _capture_clear_of_zones(c, step),
                       where=c.plan.step_where(step, "capture"))
    c.state.altitudes.append(_Altitude(step.alt_m, c.plan.step_where(step, "alt_m")))


def _camera(c: _Compile, step: CameraStep) -> None:
    c.emitter.camera_change(step.payload, step.values, where=c.plan.step_where(step, "settings"))
    c.state.settings_now.setdefault(step.payload, {}).update(step.values)


def _rtl(c: _Compile, step: RtlStep) -> None:
    last = c.emitter.s.last_pos
    if last is not None:
        # the vehicle flies home straight from where it is: from the last way round the zones, that is clear
        _transit_to(c, c.plan.home.lat, c.plan.home.lon, last[2], "return home", c.plan.step_where(step))
    c.emitter.rtl()


def _land(c: _Compile, step: LandStep) -> None:
    here = c.plan.step_where(step)
    if step.lat is not None:
        _check_reach(c.plan.home, step.lat, step.lon, "landing point", here)
        last = c.emitter.s.last_pos
        if last is not None:
            _transit_to(c, step.lat, step.lon, last[2], "flight to the landing point", here)
    c.emitter.land(step.lat, step.lon, where=here)


def _survey(c: _Compile, step: SurveyStep) -> None:
    _lines_step(c, step, "survey", _plan_survey_lines)


def _corridor(c: _Compile, step: CorridorStep) -> None:
    _lines_step(c, step, "corridor", _plan_corridor_lines)


# ------------------------------------------------------------------------------------ survey or corridor

def _lines_step(c: _Compile, step: SurveyStep | CorridorStep, kind: str,
                plan_lines: Callable[[_Compile, Any, _LineInputs], _Lines]) -> None:
    """A survey or corridor: its first payload's optics set the altitude, footprint and trigger distance, every
    payload must keep up with the trigger, and the planned lines become the emitter's track."""
    here = c.plan.step_where(step)
    lead = _lead_optics(c.plan, c.payloads, step, kind)
    alt = _line_altitude(c.plan, step, lead)
    c.state.altitudes.append(_Altitude(alt, c.plan.step_where(
        step, "altitude_m" if step.altitude_m is not None else "gsd_cm")))
    footprint = optics.footprint(lead, alt)
    trig = optics.trigger_m(lead, alt, step.front_pct)
    _check_triggering(c, step, lead, trig)
    check_sharp(_step_limits(c.plan, c.payloads, step, lead, alt), c.speed_mps, c.plan.where("vehicle", "speed_mps"))
    _record_rededges(c, step, lead, alt)
    try:
        lines = plan_lines(c, step, _line_inputs(c, step, lead, footprint))
        if c.terrain is not None:
            lines = _lines_for_the_ground(c, step, lead, alt, footprint, lines, plan_lines)
    except PlanError as e:
        raise _relocate(e, here) from None
    first = c.emitter.item_count
    track = _track_clear_of_zones(c, step, lines, _track(c, step, lines.route, alt, lead), alt, kind)
    if c.terrain is not None:
        track = _terrain_track(c, step, kind, track)
    _check_path_clear_of_zones(c, step, lines, track, kind)
    _transit_to(c, track.points[0].lat, track.points[0].lon, alt, f"flight to the {kind}'s first line", here)
    c.emitter.track(track, where=c.plan.step_where(step, "trigger"))
    for w in lines.route.warnings:
        c.warn(w.code, f"{kind} at {here}: {w.message}")
    for w in turn_warnings(lines.route, c.turn_radius_m, _line_inputs_turnaround(c, step)):
        c.warn(w.code, f"{kind} at {here}: {w.message}")
    c.state.areas.append(AreaInfo(
        step=step.index, kind=kind, payloads=step.payloads, area=lines.area, altitude_m=alt,
        front_overlap=step.front_pct / 100.0, side_overlap=step.side_pct / 100.0, trigger=step.trigger,
        trigger_distance_m=lines.route.trigger_distance_m, items=(first, c.emitter.item_count),
        zones=_step_zones(c, step, lines, alt),
        line_items=_line_items(c.emitter.s.track_navs, lines.route)))
    c.state.intent.append(lines.route)
    c.state.step_facts.append(_step_facts(c, step, kind, lead, footprint, lines.route))
    c.state.patterns.append(_pattern(c, step, kind, lines, lead, alt, first))


def _pattern(c: _Compile, step: SurveyStep | CorridorStep, kind: str, lines: _Lines, lead: PayloadInfo, alt: float,
             first: int) -> TransectPattern:
    """The step as QGC's survey or corridor editor holds it, around the items it just emitted."""
    from missions.formats.qgc_complex import transect_start

    end = c.emitter.item_count
    common = dict(kind=kind, items=(transect_start(c.emitter.s.items, first, end), end), payload=lead.name,
                  altitude_m=alt, front_pct=step.front_pct, side_pct=step.side_pct,
                  spacing_m=lines.route.spacing_m, trigger_distance_m=lines.route.trigger_distance_m,
                  turnaround_m=_turnaround_m(c, step), hover=step.trigger == "hover")
    if isinstance(step, CorridorStep):
        return TransectPattern(**common, line=tuple(tuple(p) for p in step.line), width_m=step.width_m)
    return TransectPattern(**common, polygon=_outline(lines.area), angle_deg=lines.route.angle_deg,
                           refly_90=step.refly_90)


def _outline(area: Area) -> tuple[tuple[float, float], ...]:
    """One polygon around the surveyed area, (lat, lon), not closed: QGC's survey has one outline and no holes, so
    an area the exclusions cut into pieces (or several polygons) is written as their convex hull."""
    g = area.geometry
    ring = g.exterior if g.geom_type == "Polygon" else g.convex_hull.exterior
    return _latlon_ring(area, ring)


def _latlon_ring(area: Area, ring: Any) -> tuple[tuple[float, float], ...]:
    import numpy as np

    xy = np.asarray(ring.coords)[:-1]
    lat, lon = area.projection.to_latlon(xy[:, 0], xy[:, 1])
    return tuple((round(float(a), 7), round(float(b), 7)) for a, b in zip(lat, lon))


def _turnaround_m(c: _Compile, step: SurveyStep | CorridorStep) -> float:
    return step.turnaround_m if step.turnaround_m is not None else TURNAROUND_DEFAULT_M[c.plan.vehicle.frame]


def _step_facts(c: _Compile, step: SurveyStep | CorridorStep, kind: str, lead: PayloadInfo, footprint: Footprint,
                route: SurveyPlan | CorridorPlan) -> StepFacts:
    """The numbers a pilot reads for one step, and what they assume."""
    survey_step = isinstance(step, SurveyStep)
    return StepFacts(
        step=step.index, kind=kind, where=c.plan.step_where(step), lead=lead.name,
        angle_deg=route.angle_deg if survey_step else None,
        angle_auto=survey_step and step.angle_deg == "auto",
        spacing_m=route.spacing_m, lines=route.lines if survey_step else route.stats.lines,
        trigger=step.trigger, trigger_distance_m=route.trigger_distance_m, speed_mps=c.speed_mps,
        footprint_m=(footprint.across_m, footprint.along_m),
        capture=tuple(_capture_size(c, name) for name in step.payloads),
        assumptions=tuple(_assumptions(c, step)))


def _capture_size(c: _Compile, name: str) -> CaptureSize:
    """The files each photo of payload `name` writes with the settings it holds now, and their size."""
    cam = c.payloads.cameras[name]
    held = c.state.settings_now.setdefault(name, dict(c.plan.payload(name).values))
    formats, mb = cam.capture_formats(held)
    if mb is not None:
        source = cam.capture_sizes.source
    else:
        source = f"{cam.model}: no published image sizes in the catalogue (cdf/tables/{cam.table})"
    return CaptureSize(name, formats, mb, source)


def _assumptions(c: _Compile, step: SurveyStep | CorridorStep) -> list[str]:
    """Every assumption the step's numbers rest on."""
    if c.terrain is None:
        out = ["flat ground at home's height: altitudes, footprints and GSD are above home, not above the terrain"]
    else:
        out = ["ground from the plan's DEM (terrain.dem): altitudes, footprints and GSD are above the ground below "
               "the camera, as the DEM gives it"]
    for name in step.payloads:
        info = c.payloads.optics.get(name)
        if info is None:
            out.append(f"{name}: optics unknown, its photos are not measured")
            continue
        imager = c.payloads.cameras[name].imager(info.imager)
        assumed = [a.replace("_", " ") for a in imager.assumed] if imager is not None else []
        if assumed:
            out.append(f"{name}: {', '.join(assumed)} of {info.camera_id}/{info.imager} assumed, not from a "
                       f"datasheet (cdf/tables/{c.payloads.cameras[name].table})")
    if step.trigger != "hover":
        what = "airspeed" if c.emitter.speed_is_airspeed else "ground speed"
        out.append(f"{c.speed_mps:g} m/s {what} held along the lines, no wind: the time between photos and the "
                   "flight time scale with it")
    return out


def _line_items(navs: tuple[int, ...], route: SurveyPlan | CorridorPlan) -> tuple[int, ...]:
    """The items of the points after each camera span's entry up to its exit: flying towards them is flying a line."""
    return tuple(navs[k] for s in route.camera_spans for k in range(s.start_index + 1, s.stop_index + 1)
                 if k < len(navs))


def _lead_optics(plan: Plan, payloads: _Payloads, step: SurveyStep | CorridorStep, kind: str) -> PayloadInfo:
    """The optics of the step's first payload, which sets the lines: without them there is no footprint."""
    lead = step.payloads[0]
    if lead in payloads.optics_errors:
        e = payloads.optics_errors[lead]
        raise PlanError(f"{kind} lines need {lead}'s footprint: {e.message}",
                        where=plan.step_where(step, "payloads", 0), hint=e.hint)
    return payloads.optics[lead]


def _line_altitude(plan: Plan, step: SurveyStep | CorridorStep, lead: PayloadInfo) -> float:
    """The step's altitude, or the one at which the lead payload images with the step's GSD."""
    if step.altitude_m is not None:
        return step.altitude_m
    alt = optics.altitude_for_gsd(lead, step.gsd_cm)
    if not MIN_ALTITUDE_M <= alt <= MAX_ALTITUDE_M:
        raise PlanError(f"gsd_cm {step.gsd_cm:g} needs {alt:.1f} m above ground with {lead.name}'s optics, "
                        f"outside {MIN_ALTITUDE_M:g}..{MAX_ALTITUDE_M:g} m",
                        where=plan.step_where(step, "gsd_cm"), hint="choose another GSD")
    too_high = ceiling_problem(alt, f"gsd_cm {step.gsd_cm:g} with {lead.name}'s optics", _ceiling(plan),
                               lower="a smaller gsd_cm (finer detail) flies lower")
    if too_high is not None:
        raise PlanError(too_high[0], where=plan.step_where(step, "gsd_cm"), hint=too_high[1])
    return alt


def _ceiling(plan: Plan) -> Ceiling:
    given = plan.vehicle.max_altitude_m
    return Ceiling(given, True) if given is not None else Ceiling(MAX_AGL_M, False)


def _check_triggering(c: _Compile, step: SurveyStep | CorridorStep, lead: PayloadInfo, trig: float) -> None:
    """Every payload the autopilot triggers must be reached by the trigger and keep up with its interval; a
    payload of unknown optics flies along unmeasured (warned). RedEdges are checked in `_setup`."""
    _check_distance_trigger_reach(c, step)
    moving = step.trigger != "hover"
    where = c.plan.step_where(step, "overlap", "front")
    interval = optics.check_interval(lead, trig, c.speed_mps, where=where) if moving else None
    for other in step.payloads:
        if other == lead.name or c.payloads.is_rededge(other):
            continue
        if other not in c.payloads.optics:
            c.warn("no_optics", f"{other} triggers alongside {lead.name} but its optics are unknown, so its "
                                "coverage cannot be measured")
        elif moving:
            optics.check_interval(c.payloads.optics[other], trig, c.speed_mps, where=where)
    if moving and lead.min_interval_s and interval < NEAR_MIN_INTERVAL * lead.min_interval_s:
        c.warn("trigger_interval_near_min", f"{lead.name} shoots every {interval:.2f} s at "
               f"{c.plan.step_where(step)}, close to its minimum of {lead.min_interval_s:g} s; a gust of tail "
               "wind loses photos")


def _check_distance_trigger_reach(c: _Compile, step: SurveyStep | CorridorStep) -> None:
    prof = c.profile
    triggered = [n for n in step.payloads if not c.payloads.is_rededge(n)]
    if step.trigger == "distance" and len(triggered) > 1 and not prof.distance_trigger_all:
        raise PlanError(f"{prof.title} distance-triggers only its primary camera: {', '.join(triggered[1:])} "
                        f"would take just the first photo of each line",
                        where=c.plan.step_where(step, "payloads"),
                        hint="AP_Camera::set_trigger_distance() drives the primary instance only. Use "
                             "trigger: hover (one IMAGE_START_CAPTURE reaches every instance), one WIRIS "
                             "per survey with that camera as CAM1, or PX4 (camera_trigger addresses "
                             "components 100..105)")


def _record_rededges(c: _Compile, step: SurveyStep | CorridorStep, lead: PayloadInfo, alt: float) -> None:
    """What each RedEdge of the step flies: its overlap mode (set once, in `_setup`) must cover it."""
    where = c.plan.step_where(step, "overlap", "front")
    for name in step.payloads:
        if not c.payloads.is_rededge(name):
            continue
        if name in c.payloads.optics and name != lead.name:
            c.state.rededge_checks.append(_RedEdgeCheck(name, alt, where))
        c.state.rededge_flights.setdefault(name, []).append(_RedEdgeFlight(alt, step.front_pct, step.side_pct))


def _line_inputs(c: _Compile, step: SurveyStep | CorridorStep, lead: PayloadInfo,
                 footprint: Footprint) -> _LineInputs:
    last = c.emitter.s.last_pos
    return _LineInputs(
        footprint=footprint,
        turnaround_m=step.turnaround_m if step.turnaround_m is not None
        else default_turnaround_m(TURNAROUND_DEFAULT_M[c.plan.vehicle.frame], c.turn_radius_m, c.profile.name,
                                  c.speed_mps),
        start_latlon=last[:2] if last else (c.plan.home.lat, c.plan.home.lon),
        photos_left=max(0, survey.MAX_PHOTOS - sum(len(g.photos) for g in c.state.intent)),
        min_interval_s=lead.min_interval_s)


def _line_inputs_turnaround(c: _Compile, step: SurveyStep | CorridorStep) -> float | None:
    """The step's own turnaround_m (None: the default, which a plane's turn already sizes)."""
    return step.turnaround_m


def _plan_survey_lines(c: _Compile, step: SurveyStep, inputs: _LineInputs) -> _Lines:
    area = area_clear_of(step.area, c.zones, c.plan.base_dir, c.plan.step_where(step, "area"))
    _check_reach(c.plan.home, area.projection.lat0, area.projection.lon0, "area", c.plan.step_where(step))
    end = line_end(c.profile.name, c.plan.vehicle.frame, c.speed_mps,
                   survey.trigger_distance_m(inputs.footprint, step.front_pct), survey.DEFAULT_EXIT_MARGIN_M)
    route = plan_survey(area, inputs.footprint, step.front_pct, step.side_pct, angle_deg=step.angle_deg,
                        turnaround_m=inputs.turnaround_m, speed_mps=c.speed_mps,
                        min_interval_s=inputs.min_interval_s, refly_90=step.refly_90,
                        hover=step.trigger == "hover", start_latlon=inputs.start_latlon,
                        photos_left=inputs.photos_left, turn_radius_m=c.turn_radius_m,
                        exit_margin_m=end.margin_m, exit_stretch=end.stretch)
    return _Lines(route, area)


def _plan_corridor_lines(c: _Compile, step: CorridorStep, inputs: _LineInputs) -> _Lines:
    if step.trigger == "hover":
        raise PlanError("corridors are flown with distance or interval triggering",
                        where=c.plan.step_where(step, "trigger"), hint="use trigger: distance")
    _check_reach(c.plan.home, *step.line[0], "corridor", c.plan.step_where(step))
    route = plan_corridor(step.line, step.width_m, inputs.footprint, step.front_pct, step.side_pct,
                          turnaround_m=inputs.turnaround_m, speed_mps=c.speed_mps,
                          min_interval_s=inputs.min_interval_s, where=c.plan.step_where(step, "line"),
                          photos_left=inputs.photos_left)
    return _Lines(route, route.area)


def _track(c: _Compile, step: SurveyStep | CorridorStep, route: SurveyPlan | CorridorPlan, alt: float,
           lead: PayloadInfo) -> Track:
    """The planned lines as the emitter flies them; a hover photo holds at least the camera's interval."""
    return Track(points=tuple(TrackPoint(w.lat, w.lon, w.kind, w.yaw_deg) for w in route.waypoints),
                 spans=tuple((s.start_index, s.stop_index) for s in route.camera_spans),
                 altitude_m=alt, trigger=step.trigger, trigger_distance_m=route.trigger_distance_m,
                 interval_s=(route.trigger_distance_m / c.speed_mps),
                 hold_s=_hover_hold_s(lead),
                 autopilot_triggers=any(not c.payloads.is_rededge(n) for n in step.payloads))


def _hover_hold_s(lead: PayloadInfo) -> float:
    """A hover photo waits until the vehicle has settled: QGC's hover delay at least, and long enough for a
    microbolometer to settle on the still scene (five time constants: 99 % of a first-order step response) and
    then take the photo (the camera's minimum capture interval)."""
    settle = 5.0 * (lead.time_constant_ms or 0.0) / 1000.0
    return max(HOVER_HOLD_S, settle + (lead.min_interval_s or 0.0))


# ------------------------------------------------------------------------------------------------- zones

def _step_footprint(c: _Compile, step: SurveyStep | CorridorStep, alt: float) -> Footprint | None:
    """The footprint holding every photo the autopilot triggers on the step (the largest across and along of its
    payloads of known optics), None when it triggers none."""
    sizes = [c.payloads.optics[n].footprint_m(alt) for n in step.payloads
             if n in c.payloads.optics and not c.payloads.is_rededge(n)]
    return Footprint(max(s[0] for s in sizes), max(s[1] for s in sizes)) if sizes else None


def _track_clear_of_zones(c: _Compile, step: SurveyStep | CorridorStep, lines: _Lines, track: Track, alt: float,
                          kind: str) -> Track:
    """The track kept out of the no-fly and exclude zones (stretches ending at them, hops round them) and with its
    camera off wherever a footprint would reach a no-photo or exclude zone (grown by its margin); hover photos in
    either are dropped. Warned, with how many."""
    path_zones = [z for z in c.zones if z.keeps_path_out]
    photo_zones = [z for z in c.zones if z.keeps_photos_out]
    if not path_zones and not photo_zones:
        return track
    proj = lines.area.projection
    here = c.plan.step_where(step)
    start = tuple(CameraPoint(w.x, w.y, w.kind, w.yaw_deg) for w in lines.route.waypoints)
    points, spans, dropped = start, tuple(track.spans), 0
    if path_zones:
        cam = keep_path_out(points, spans, ZoneRouter(place_zones(path_zones, proj)), f"{kind}'s path", here)
        if cam.points != points:
            c.warn("zone_detour", f"{kind} at {here}: its lines stop at no-fly or exclude zones (grown by their "
                   "margin) and its hops go round them")
        points, spans, dropped = cam.points, cam.spans, cam.photos_dropped
    fp = _step_footprint(c, step, alt)
    if photo_zones and fp is not None and track.autopilot_triggers:
        forbidden = grown_union(place_zones(photo_zones, proj))
        cam = keep_photos_out(points, spans, forbidden, fp, track.trigger_distance_m, step.trigger == "hover")
        if cam.stretches_off:
            # the camera comes back on RESUME_MARGIN_M past the zone's reach, for a copter's 2 m early acceptance and
            # one trigger check; a fixed-wing accepts a waypoint much earlier (ArduPlane's WP_RADIUS is 90 m by default)
            plane = (" A fixed-wing accepts a waypoint up to its acceptance radius early (ArduPlane WP_RADIUS, PX4 "
                     f"NAV_ACC_RAD): set it to at most {DEFAULT_EXIT_MARGIN_M:g} m for this mission, or the camera comes "
                     "back on before the zone is behind it.") if c.plan.vehicle.frame != "copter" else ""
            c.warn("zone_camera_off", f"{kind} at {here}: the camera is off over {cam.stretches_off} stretch(es) "
                   "of its lines where a footprint would reach a no-photo or exclude zone (DO_SET_CAM_TRIGG_DIST 0, "
                   "then on again past it)." + plane)
        points, spans, dropped = cam.points, cam.spans, dropped + cam.photos_dropped
    if dropped:
        c.warn("zone_photo_dropped", f"{kind} at {here}: {dropped} hover photo(s) dropped (flown through or left "
               "out without a photo) because their footprint could reach a no-photo zone or they lie in a no-fly one")
    if points == start and spans == tuple(track.spans):
        return track
    lat, lon = proj.to_latlon([p.x for p in points], [p.y for p in points])
    pts = tuple(TrackPoint(float(a), float(o), p.kind, p.yaw_deg) for p, a, o in zip(points, lat, lon))
    return replace(track, points=pts, spans=spans)


def _check_path_clear_of_zones(c: _Compile, step: SurveyStep | CorridorStep, lines: _Lines, track: Track,
                               kind: str) -> None:
    """A step's own path (lines, turnarounds, connections) must not enter a no-fly or exclude zone."""
    path_zones = [z for z in c.zones if z.keeps_path_out]
    if not path_zones:
        return
    proj = lines.area.projection
    x, y = proj.to_xy([p.lat for p in track.points], [p.lon for p in track.points])
    for pz, metres in path_inside(np.column_stack([x, y]), place_zones(path_zones, proj)):
        hint = ("a corridor's lines are not routed around zones: move its line or narrow it so the lines keep "
                "clear of the zone, or make the zone no_photo if it may be flown over") if kind == "corridor" \
            else "redraw the zone or the area so that a way round the zone is left inside the area"
        raise PlanError(f"the {kind}'s path runs {metres:.1f} m inside {pz.zone.label}",
                        where=c.plan.step_where(step), hint=hint)


def _transit_to(c: _Compile, lat: float, lon: float, alt: float, what: str, where: str) -> None:
    """Waypoints round the no-fly and exclude zones between where the vehicle is and (lat, lon), at `alt`."""
    if c.transits is None:
        return
    last = c.emitter.s.last_pos
    start = last[:2] if last else (c.plan.home.lat, c.plan.home.lon)
    for la, lo in c.transits.route(start, (lat, lon), what, where):
        c.emitter.via(la, lo, alt)


def _capture_clear_of_zones(c: _Compile, step: WaypointStep) -> str | None:
    """The waypoint's capture, or None (dropped, warned) when its footprint could reach a no-photo zone."""
    name = step.capture
    photo_zones = [z for z in c.zones if z.keeps_photos_out]
    if name is None or not photo_zones or name not in c.payloads.optics or c.transits is None:
        return name
    proj = c.transits.proj
    fp = Footprint(*c.payloads.optics[name].footprint_m(step.alt_m))
    x, y = proj.point_to_xy(step.lat, step.lon)
    for z in place_zones(photo_zones, proj):
        if capture_reaches(x, y, z.grown, fp):
            c.warn("zone_photo_dropped", f"waypoint at {c.plan.step_where(step)}: the photo of {name} is dropped "
                   f"(the waypoint is flown without it): its footprint could reach {z.zone.label}")
            return None
    return name


def _step_zones(c: _Compile, step: SurveyStep | CorridorStep, lines: _Lines, alt: float) -> StepZones | None:
    """The zones the report measures against this step: its own, and any other a footprint from its area could
    reach."""
    fp = _step_footprint(c, step, alt)
    if not c.zones:
        return None
    reach = max(fp.across_m, fp.along_m) if fp is not None else 0.0
    near = set(zones_near(c.zones, lines.area, reach))
    mine = tuple(z for z in c.zones if z.step == step.index or z in near)
    return StepZones(mine, reach) if mine else None


def _check_rededge_and_zones(plan: Plan, payloads: _Payloads, zones: tuple[Zone, ...]) -> None:
    """A RedEdge shoots by itself whenever it is at its altitude: it cannot be switched off near a no-photo zone."""
    photo_zones = [z for z in zones if z.keeps_photos_out]
    flying = {n for s in plan.mission if isinstance(s, (SurveyStep, CorridorStep)) for n in s.payloads}
    rededges = [n for n in flying if payloads.is_rededge(n)]
    if photo_zones and rededges:
        z = photo_zones[0]
        raise PlanError(f"{rededges[0]} (a RedEdge) captures by itself in its overlap mode and cannot be switched "
                        f"off near {z.label}", where=z.where,
                        hint="fly the RedEdge in a plan without no_photo/exclude zones, or make the zone no_fly "
                             "if only the flight over it is forbidden")


def _lines_for_the_ground(c: _Compile, step: SurveyStep | CorridorStep, lead: PayloadInfo, alt: float,
                          footprint: Footprint, lines: _Lines,
                          plan_lines: Callable[[_Compile, Any, _LineInputs], _Lines]) -> _Lines:
    """The lines planned again, once, with a shorter trigger distance and line spacing where the ground needs them
    to hold the requested overlaps (missions.terrain.lines): footprints on a slope along the track are
    trapezoids that consecutive photos share less of, and lines that fly higher than the target (within the
    tolerance, where the ground bends) have wider photos beside narrower ones. Kept as planned when both
    factors are within half a percent of 1."""
    from missions.terrain.lines import front_overlap_scale, side_overlap_scale, terrain_track

    track = _track(c, step, lines.route, alt, lead)
    k_front = front_overlap_scale(track, c.terrain, footprint.along_m, alt)
    followed = terrain_track(track, c.terrain, c.speed_mps, c.plan.step_where(step))
    k_side = side_overlap_scale(step.side_pct, alt, followed.highest_agl_m)
    if k_front > 0.995 and k_side > 0.995:
        return lines
    _check_triggering(c, step, lead, optics.trigger_m(lead, alt, step.front_pct) * k_front)
    shorter = Footprint(footprint.across_m * k_side, footprint.along_m * k_front)
    return plan_lines(c, step, _line_inputs(c, step, lead, shorter))


def _terrain_track(c: _Compile, step: SurveyStep | CorridorStep, kind: str, track: Track) -> Track:
    """The track following the DEM (missions.terrain.lines); where the rates keep it above its band, a warning."""
    from missions.terrain.lines import terrain_track

    height = c.plan.step_where(step, "altitude_m" if step.altitude_m is not None else "gsd_cm")
    followed = terrain_track(track, c.terrain, c.speed_mps, height)
    if followed.over_tolerance_m > 0.01:
        c.warn("terrain_rate_limited", f"{kind} at {c.plan.step_where(step)}: the ground falls or rises faster than "
               f"vehicle.climb_mps {c.terrain.climb_mps:g} / descent_mps {c.terrain.descent_mps:g} m/s allow at "
               f"{c.speed_mps:g} m/s: the lines fly up to {followed.over_tolerance_m:.1f} m above the tolerance "
               "there (coarser GSD, never lower than the target)")
    return followed


_STEPS: dict[type, Callable[[_Compile, Any], None]] = {
    TakeoffStep: _takeoff, SurveyStep: _survey, CorridorStep: _corridor, WaypointStep: _waypoint,
    CameraStep: _camera, RtlStep: _rtl, LandStep: _land}


# --------------------------------------------------------------------------------------- after the steps

def _warn_about_altitudes(c: _Compile) -> None:
    """One note for a mission above MAX_AGL_M under the plan's permit (without one the loader refused it)."""
    high = [a for a in c.state.altitudes if a.altitude_m > MAX_AGL_M]
    if high and c.plan.vehicle.max_altitude_m is not None:
        top = max(high, key=lambda a: a.altitude_m)
        ground = ("ground assumed flat at home's height" if c.terrain is None else
                  "a survey's or corridor's altitude is above the DEM's ground, the other steps' above home")
        c.warn("altitude_above_120m", f"the mission flies up to {top.altitude_m:g} m above home (at {top.where}), "
               f"above the {MAX_AGL_M:g} m most rules allow without a permit: flown under the permit the plan "
               f"states (vehicle.max_altitude_m: {c.plan.vehicle.max_altitude_m:g} at "
               f"{c.plan.where('vehicle', 'max_altitude_m')}); {ground}")


def _setup(c: _Compile) -> tuple[SetupStep, ...]:
    """The pre-flight sequence, with each RedEdge's overlap mode covering what it flies."""
    rededge = {name: _rededge_survey(flights) for name, flights in c.state.rededge_flights.items()}
    for check in c.state.rededge_checks:
        info = c.payloads.optics[check.payload]
        own = dict(c.plan.payload(check.payload).values)   # the plan's setting wins
        front = own.get("overlap_along_pct", rededge[check.payload].front_pct)
        optics.check_interval(info, optics.trigger_m(info, check.altitude_m, front), c.speed_mps, where=check.where)
    try:
        return setup_steps(c.plan.payloads, c.payloads.cameras, rededge)
    except PlanError as e:
        raise _relocate(e, c.plan.where("payloads")) from None


def _lua_bridge(c: _Compile, emitted: Emitted) -> str | None:
    return render_script(c.plan.name) if emitted.needs_lua else None


def _fixed_wing_without_landing(c: _Compile, emitted: Emitted) -> bool:
    """A plane or VTOL mission that ends without a landing item (an RTL, a loiter)."""
    landings = (mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_NAV_VTOL_LAND, mavlink.MAV_CMD_DO_LAND_START)
    return c.plan.vehicle.frame != "copter" and not any(it.command in landings for it in emitted.items)


def _params(c: _Compile, emitted: Emitted) -> tuple[Param, ...]:
    try:
        return autopilot_params(c.profile, c.plan.payloads, c.payloads.cameras, c.payloads.optics,
                                c.payloads.instances, needs_lua=emitted.needs_lua,
                                triggers={a.trigger for a in c.state.areas},
                                version=c.plan.vehicle.firmware_version,
                                fixed_wing_without_landing=_fixed_wing_without_landing(c, emitted),
                                speed_mps=c.speed_mps)
    except PlanError as e:
        raise _relocate(e, c.plan.where("mission")) from None


def _warn_about_unknown_optics(c: _Compile) -> None:
    """A payload of unknown optics that sets no lines is only unmeasured (one that does is an error)."""
    for name, e in c.payloads.optics_errors.items():
        if not any(name in a.payloads[:1] for a in c.state.areas):
            c.warn("no_optics", f"{name}: {e.message}")


# ------------------------------------------------------------------------------------------- the speed

def _speed_limits(plan: Plan, payloads: _Payloads) -> list[SpeedLimit]:
    """Every survey's and corridor's limits on the speed (interval and blur), from the same optics, altitude and
    trigger distance the steps plan with."""
    limits: list[SpeedLimit] = []
    for step in plan.mission:
        if not isinstance(step, (SurveyStep, CorridorStep)):
            continue
        kind = "survey" if isinstance(step, SurveyStep) else "corridor"
        try:
            lead = _lead_optics(plan, payloads, step, kind)
            alt = _line_altitude(plan, step, lead)
        except PlanError:
            continue                 # the step's own pass reports it, in mission order
        limits += _step_limits(plan, payloads, step, lead, alt)
    return limits


def _step_limits(plan: Plan, payloads: _Payloads, step: SurveyStep | CorridorStep, lead: PayloadInfo,
                 alt: float) -> list[SpeedLimit]:
    kind = "survey" if isinstance(step, SurveyStep) else "corridor"
    infos = [payloads.optics[n] for n in step.payloads if n in payloads.optics]
    triggered = [n for n in step.payloads if not payloads.is_rededge(n)]
    return line_limits(f"{kind} at {plan.step_where(step)}", plan.step_where(step, "blur_px"),
                       optics.trigger_m(lead, alt, step.front_pct), infos, alt, step.blur_px,
                       moving=step.trigger != "hover", triggered=triggered)


def _mission_speed(plan: Plan, payloads: _Payloads, state: _State) -> float:
    """The plan's speed, checked against the blur budgets and vehicle.max_speed_mps; or, for `auto`, the
    fastest speed every camera allows (capped by vehicle.max_speed_mps or the frame's plausible maximum)."""
    v = plan.vehicle
    where = plan.where("vehicle", "speed_mps")
    limits = _speed_limits(plan, payloads)
    low, high = SPEED_RANGE_MPS[v.frame]
    if v.speed_mps is not None:
        if v.max_speed_mps is not None and v.speed_mps > v.max_speed_mps:
            raise PlanError(f"speed_mps {v.speed_mps:g} is above vehicle.max_speed_mps {v.max_speed_mps:g}",
                            where=where, hint=f"fly at {v.max_speed_mps:g} m/s or slower, or speed_mps: auto")
        return v.speed_mps          # each step checks it against its limits (`_check_sharp`)
    if v.max_speed_mps is not None:
        cap = SpeedLimit(v.max_speed_mps, "vehicle", "vehicle.max_speed_mps", plan.where("vehicle", "max_speed_mps"))
    elif limits:
        cap = SpeedLimit(high, "vehicle", f"the fastest plausible {v.frame} survey speed", where)
    else:
        raise PlanError("speed_mps: auto sizes the speed from the surveys and corridors, and this plan has none",
                        where=where, hint="give a number, e.g. speed_mps: 5, or vehicle.max_speed_mps")
    # auto keeps the interval NEAR_MIN_INTERVAL above the camera's minimum: a gust of tail wind loses no photo
    chosen = choose_speed([lim._replace(speed_mps=lim.speed_mps / NEAR_MIN_INTERVAL,
                                        why=lim.why + f" with a {NEAR_MIN_INTERVAL - 1:.0%} margin")
                           if lim.kind == "interval" else lim for lim in limits], cap)
    if chosen.speed_mps < low:
        raise PlanError(f"speed_mps: auto finds no speed a {v.frame} can fly: {chosen.limit.why} allows at most "
                        f"{chosen.speed_mps:g} m/s, below the {low:g} m/s minimum", where=chosen.limit.where,
                        hint="fly higher (coarser GSD, longer trigger distance), lower the front overlap, or "
                             "raise blur_px")
    state.warnings.append(PlanWarning("speed_auto", f"speed_mps: auto chose {chosen.speed_mps:g} m/s, the fastest "
                                      f"at which {chosen.limit.why}"))
    return chosen.speed_mps


# ------------------------------------------------------------------------------------------------- fence

def _fence(c: _Compile, items: tuple[MissionItem, ...]) -> tuple[MissionItem, ...]:
    """The fence: each zone the vehicle must not enter as an exclusion polygon, and with the plan's
    `fence: {margin_m: M}` an inclusion polygon M metres around everything the mission flies. (A path through a
    zone is the report's path_over_exclusion warning: with the fence enabled the vehicle breaches it there.)"""
    from missions.geometry.fence import exclusion_polygon, inclusion_polygon

    out: list[MissionItem] = []
    seen: set[tuple] = set()
    for ring in _fence_rings(c):
        if ring not in seen:
            seen.add(ring)
            out.extend(exclusion_polygon(ring))
    home = c.plan.home
    if c.plan.fence_margin_m is not None:
        out.extend(inclusion_polygon(items, (home.lat, home.lon), c.plan.fence_margin_m))
    return tuple(out)


def _fence_rings(c: _Compile) -> list[tuple[tuple[float, float], ...]]:
    """The outline (lat, lon) of every zone the vehicle must not enter (no_fly and exclude; a no_photo zone may
    be flown over), cleaned as the compiler keeps out of it."""
    import numpy as np

    proj = LocalProjection(c.plan.home.lat, c.plan.home.lon)
    rings = []
    for zone in c.zones:
        if not zone.keeps_path_out:
            continue
        g = zone.xy(proj)
        for poly in getattr(g, "geoms", [g]):
            xy = np.asarray(poly.exterior.coords)[:-1]
            lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
            rings.append(tuple((round(float(a), 7), round(float(b), 7)) for a, b in zip(lat, lon)))
    return rings


# -------------------------------------------------------------------------------------------- the driver

def _problems_of(err: PlanError) -> list[Problem]:
    return list(err.problems) or [Problem(err.where or "", err.message, err.hint)]


def _compile_steps(c: _Compile) -> list[Problem]:
    """Every step compiled in order; a step that fails is left out and the next ones still checked, so that
    one run reports every step's problem."""
    problems: list[Problem] = []
    for step in c.plan.mission:
        try:
            _STEPS[type(step)](c, step)
        except PlanError as e:
            problems.extend(_problems_of(e))
    return problems


def _load_terrain(plan: Plan, prof: FirmwareProfile) -> Any:
    """The plan's DEM and terrain settings (missions.terrain), None without one."""
    if plan.terrain is None:
        return None
    from missions.terrain.dem import load_dem
    from missions.terrain.model import Terrain, rates_for

    t = plan.terrain
    if t.frame == "terrain" and prof.name != "ardupilot":
        raise PlanError(f"{prof.title} has no terrain frame in missions", where=plan.where("terrain", "frame"),
                        hint="use terrain.frame: amsl (waypoint altitudes above mean sea level from the DEM, which "
                             "every firmware flies), or fly ArduPilot")
    dem = load_dem(t.dem, plan.base_dir, t.vertical, where=plan.where("terrain", "dem"))
    climb, descent = rates_for(plan.vehicle.frame, plan.vehicle.climb_mps, plan.vehicle.descent_mps)
    return Terrain(dem, t.frame, t.tolerance_m, t.clearance_m, climb, descent)


def _home_amsl(plan: Plan, terrain: Any, state: _State) -> float:
    """Home's elevation: the plan's, else the DEM's below home (a plan without either is refused at loading)."""
    if terrain is None:
        return float(plan.home.alt_amsl_m)
    ground = float(terrain.dem.ground_at(plan.home.lat, plan.home.lon, "home", plan.where("home"))[0])
    if plan.home.alt_amsl_m is None:
        return round(ground, 2)
    if abs(plan.home.alt_amsl_m - ground) > 5.0:
        state.warnings.append(PlanWarning("home_elevation_differs", f"home.alt_amsl_m {plan.home.alt_amsl_m:g} m is "
                                          f"{plan.home.alt_amsl_m - ground:+.1f} m from the DEM's {ground:.1f} m "
                                          "there; relative altitudes (take-off, waypoints, RTL) use the plan's"))
    return float(plan.home.alt_amsl_m)


def _check_clearance(compiled: Compiled, terrain: Any, plan: Plan) -> None:
    """Every metre of the re-flown path at least terrain.clearance_m above the DEM, or a PlanError saying where."""
    from missions.measure.flight import simulate
    from missions.terrain.clearance import path_clearance

    c = path_clearance(compiled, simulate(compiled), terrain.dem)
    if c is None or c.min_m >= terrain.clearance_m - 0.005:
        return
    base = 1 if compiled.firmware == "ardupilot" else 0
    item = compiled.items[c.item] if 0 <= c.item < len(compiled.items) else None
    raise PlanError(f"the path passes {c.min_m:.1f} m above the ground at {c.lat:.6f}, {c.lon:.6f} (altitude "
                    f"{c.amsl_m:.1f} m AMSL over ground at {c.ground_m:.1f} m), below terrain.clearance_m "
                    f"{terrain.clearance_m:g} m, flying to item {c.item + base}"
                    + (f" ({item.comment})" if item is not None and item.comment else ""),
                    where=plan.where("terrain"),
                    hint="raise the take-off altitude or the step's altitude_m, add a waypoint step above the "
                         "ground in the way, or lower terrain.clearance_m if the ground there is known clear")


def compile_plan(path_or_plan: str | Path | Plan, firmware: str | None = None) -> Compiled:
    """The compiled mission of a plan (a path or a loaded Plan), or one PlanError listing every problem of the
    plan and of its steps, ordered by where they are written."""
    if isinstance(path_or_plan, Plan):
        plan, problems = path_or_plan, []
    else:
        part = load_plan_partly(path_or_plan)
        plan, problems = part.plan, list(part.problems)
        if plan is None:
            raise_problems(problems, part.file)
    prof = profile(firmware or plan.vehicle.firmware)
    state = _State(warnings=[f"component_id_chosen: {n}" for n in plan.notes])
    try:
        terrain = _load_terrain(plan, prof)
        home_amsl = _home_amsl(plan, terrain, state)
        payloads = _resolve_payloads(plan, prof, state)
        speed = _mission_speed(plan, payloads, state)
        zones = plan_zones(plan)
        _check_rededge_and_zones(plan, payloads, zones)
    except PlanError as e:
        raise_problems(problems + _problems_of(e), plan.path)
    radius = turn_radius_of(plan.vehicle, speed)
    router = TransitRouter(zones, LocalProjection(plan.home.lat, plan.home.lon)) if zones else None
    c = _Compile(plan, prof, payloads, _emitter(plan, prof, payloads, speed), state, speed, radius, zones, router,
                 terrain)
    c.emitter.home_amsl_m = home_amsl
    if terrain is not None and any(c.payloads.is_rededge(p.name) for p in plan.payloads):
        c.warn("rededge_over_terrain", "a RedEdge in overlap mode spaces its photos by its own height above the "
               "take-off point, not above the DEM: over rising or falling ground its front overlap and its "
               "capture threshold (operatingAlt) differ from the plan's; the report measures what it does")
    _warn_about_the_start(c)
    problems += _compile_steps(c)
    if problems:
        # the mission misses the failed steps: what follows (items, parts, setup) would judge a mission nobody
        # asked for; the pre-flight setup depends on the payloads alone and is still checked
        try:
            _setup(c)
        except PlanError as e:
            problems += _problems_of(e)
        raise_problems(problems, plan.path)
    emitted = c.emitter.result()
    state.warnings.extend(emitted.warnings)
    check_items(emitted.items, prof)
    _warn_about_altitudes(c)
    setup = _setup(c)
    lua = _lua_bridge(c, emitted)
    params = _params(c, emitted)
    if terrain is not None and terrain.frame == "terrain":
        params = (*params, ("TERRAIN_ENABLE", 1.0, "the survey lines fly in the terrain frame "
                            "(MAV_FRAME_GLOBAL_TERRAIN_ALT): ArduPilot needs terrain data, from the ground station "
                            "or its SD card, before it accepts them"))
    _warn_about_unknown_optics(c)
    fence = _fence(c, emitted.items)
    compiled = Compiled(
        name=plan.name, firmware=prof.name, frame=plan.vehicle.frame,
        home=(plan.home.lat, plan.home.lon, home_amsl), speed_mps=c.speed_mps, items=emitted.items,
        parts=(emitted.items,), item_limit=c.plan.vehicle.max_mission_items or prof.default_item_limit,
        # PayloadInfo only for payloads whose optics are known: the report measures coverage with them
        payloads=tuple(payloads.optics[p.name] for p in plan.payloads if p.name in payloads.optics),
        areas=tuple(state.areas), setup=setup, lua=lua, params=params,
        warnings=tuple(dict.fromkeys(state.warnings)), intent=tuple(state.intent), inputs=input_files(plan),
        step_facts=tuple(state.step_facts), patterns=tuple(state.patterns), corridor_scan=plan.corridor_scan,
        fence=fence, terrain=terrain, turn_radius_m=radius)
    if terrain is not None:
        _check_clearance(compiled, terrain, plan)
    return _with_the_sun(plan, in_sorties(plan, compiled))


def _with_the_sun(plan: Plan, compiled: Compiled) -> Compiled:
    """The sun over each timed step and the PV profile's findings: its violations are the plan's errors."""
    found = assess(plan, compiled)
    raise_problems(list(found.problems), plan.path)
    if not found.steps and not found.warnings:
        return compiled
    return replace(compiled, sun=found.steps, warnings=tuple(dict.fromkeys(compiled.warnings + found.warnings)))
