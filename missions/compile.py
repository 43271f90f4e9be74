"""compile_plan: capture plan -> Compiled (mission items, parts, setup sequence, Lua bridge, params, warnings).

    compiled = compile_plan("plan.yaml")                 # the plan's firmware
    compiled = compile_plan(plan, firmware="px4")        # a loaded Plan, another firmware

Pipeline: load (schema, locations) -> per step: area -> survey/corridor geometry (missions.geometry.survey,
missions.geometry.corridor) -> items (missions.emit.emitter, firmware × camera) -> firmware check
(missions.emit.firmware) -> item limit / parts -> setup sequence (missions.emit.setup) -> Lua bridge (missions.emit.lua) -> autopilot params
(missions.emit.params) -> warnings. Pure: no sockets, no files written; errors are PlanError with the plan's
file:line:col.

Warnings are `PlanWarning(code, message)` values. Codes: altitude_above_120m, assumed_optics, trigger_interval_near_min,
area_smaller_than_footprint (and the survey planner's own codes), no_takeoff, component_id_chosen,
no_optics, mission_split, px4_single_capture_all.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from missions.compiled import AreaInfo, Compiled, PayloadInfo, PlanWarning
from missions.emit.emitter import Emitter, Track, TrackPoint, HOVER_HOLD_S
from missions.errors import PlanError
from missions.emit.firmware import check_items, profile, split_parts
from missions.plan.load import (CameraStep, CorridorStep, LandStep, Plan, RtlStep, SurveyStep, TakeoffStep,
                                WaypointStep, input_files, load_plan)
from missions.plan.schema import MAX_AGL_M, MAX_ALTITUDE_M, MIN_ALTITUDE_M
from missions.geometry import optics

NEAR_MIN_INTERVAL = 1.2      # warn when photos come less than 20 % slower than the camera's minimum
TURNAROUND_DEFAULT_M = {"copter": 10.0, "plane": 30.0, "vtol": 30.0}   # QGC's defaults (survey-planners §1.4)


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
    from pyproj import Geod

    from missions.geometry.geo import MAX_EXTENT_M

    distance = Geod(ellps="WGS84").inv(home.lon, home.lat, lon, lat)[2]
    if not distance <= MAX_EXTENT_M:
        raise PlanError(f"this {what} lies {distance / 1000:,.0f} km from home, more than the "
                        f"{MAX_EXTENT_M / 1000:.0f} km one plan may reach", where=where,
                        hint="check the coordinates of home and of this step (latitude and longitude swapped?)")


def _rededge_survey(alts: list[float], overlaps: list[tuple[float, float]]):
    """The RedEdge overlap-mode parameters covering every survey it flies, in the camera's integers: it captures
    from operatingAlt - opAltTolerance up, so the target is the lowest survey altitude (rounded down: were the
    camera to space its captures by the target altitude's footprint, higher surveys only gain overlap) and the
    tolerance reaches a margin below it, so that it does not shoot while climbing (a quarter of the altitude, at
    least 10 m: our choice, not MicaSense's). The overlaps are the most demanding of the surveys (rounded up)."""
    from missions.emit.setup import RedEdgeSurvey

    lowest = min(alts)
    target = max(int(math.floor(lowest)), 1)
    threshold = lowest - max(10.0, 0.25 * lowest)
    return RedEdgeSurvey(target, max(int(math.ceil(target - threshold)), 0),
                         int(math.ceil(max(f for f, _s in overlaps))), int(math.ceil(max(s for _f, s in overlaps))))


def compile_plan(path_or_plan: str | Path | Plan, firmware: str | None = None) -> Compiled:
    from cdf.catalogue import catalogue
    from missions.emit.lua import render_script
    from missions.emit.params import autopilot_params
    from missions.emit.setup import setup_steps
    from missions.geometry.survey import MAX_PHOTOS

    plan = path_or_plan if isinstance(path_or_plan, Plan) else load_plan(path_or_plan)
    fw = firmware or plan.vehicle.firmware
    prof = profile(fw)
    cat = catalogue()
    cameras = {p.name: cat.get(p.camera) for p in plan.payloads}
    components = {p.name: p.component_id for p in plan.payloads}
    warnings: list[str] = [f"component_id_chosen: {n}" for n in plan.notes]

    # ArduPilot drives each WIRIS as an AP_Camera instance (CAMn_TYPE 6); the RedEdge is not one (it triggers
    # itself). PX4 addresses cameras by component id instead.
    wiris = [p.name for p in plan.payloads if cameras[p.name].protocol != "rededge-serial"]
    instances = {name: i + 1 for i, name in enumerate(wiris)}
    if len(wiris) > prof.max_camera_instances:
        raise PlanError(f"{prof.title} drives at most {prof.max_camera_instances} MAVLink cameras (CAM1..CAM"
                        f"{prof.max_camera_instances}); the plan has {len(wiris)}", where=plan.where("payloads"),
                        hint="fly fewer WIRIS payloads")

    # optics, per payload; an unknown imager is an error only where a footprint is needed
    infos: dict[str, PayloadInfo] = {}
    optics_errors: dict[str, PlanError] = {}
    for p in plan.payloads:
        try:
            info, warn = optics.payload_info(p, cameras[p.name], where=plan.where("payloads", p.name))
            infos[p.name] = info
            warnings.extend(warn)
        except PlanError as e:
            optics_errors[p.name] = e

    em = Emitter(prof, plan.vehicle.frame, plan.vehicle.speed_mps, (plan.home.lat, plan.home.lon), cameras,
                 components, instances, {p.name: dict(p.values) for p in plan.payloads})
    areas: list[AreaInfo] = []
    intent: list[Any] = []
    rededge_alts: dict[str, list[float]] = {}
    rededge_overlap: dict[str, list[tuple[float, float]]] = {}
    rededge_speeds: list[tuple[str, float, float, Any]] = []   # (payload, altitude, speed, where) per survey
    altitudes: list[tuple[float, str]] = []
    speed = plan.vehicle.speed_mps
    if em.speed_is_airspeed:
        warnings.append(PlanWarning(
            "speed_is_airspeed", f"ArduPilot flies a {plan.vehicle.frame}'s vehicle.speed_mps ({speed:g} m/s) as "
            "airspeed (a ground-speed DO_CHANGE_SPEED would set its minimum ground speed instead); with wind the "
            "ground speed differs, so photo intervals and flight time vary (distance triggering keeps its spacing)"))
    if not any(isinstance(s, TakeoffStep) for s in plan.mission):
        warnings.append(PlanWarning("no_takeoff", "the mission has no takeoff step; it must be started with the "
                                                  "vehicle in the air"))

    for step in plan.mission:
        here = plan.step_where(step)
        if isinstance(step, TakeoffStep):
            em.takeoff(step.alt_m)
            altitudes.append((step.alt_m, plan.step_where(step, "alt_m")))
        elif isinstance(step, (SurveyStep, CorridorStep)):
            kind = "survey" if isinstance(step, SurveyStep) else "corridor"
            lead = step.payloads[0]
            if lead in optics_errors:
                e = optics_errors[lead]
                raise PlanError(f"{kind} lines need {lead}'s footprint: {e.message}",
                                where=plan.step_where(step, "payloads", 0), hint=e.hint)
            info = infos[lead]
            if step.altitude_m is not None:
                alt = step.altitude_m
            else:
                alt = optics.altitude_for_gsd(info, step.gsd_cm)
                if not MIN_ALTITUDE_M <= alt <= MAX_ALTITUDE_M:
                    raise PlanError(f"gsd_cm {step.gsd_cm:g} needs {alt:.1f} m above ground with {lead}'s optics, "
                                    f"outside {MIN_ALTITUDE_M:g}..{MAX_ALTITUDE_M:g} m",
                                    where=plan.step_where(step, "gsd_cm"), hint="choose another GSD")
            altitudes.append((alt, plan.step_where(step, "altitude_m" if step.altitude_m is not None else "gsd_cm")))
            fp = optics.footprint(info, alt)
            trig = optics.trigger_m(info, alt, step.front_pct)
            where_speed = plan.step_where(step, "overlap", "front")
            triggered = [n for n in step.payloads if cameras[n].protocol != "rededge-serial"]
            if step.trigger == "distance" and len(triggered) > 1 and not prof.distance_trigger_all:
                raise PlanError(f"{prof.title} distance-triggers only its primary camera: {', '.join(triggered[1:])} "
                                f"would take just the first photo of each line",
                                where=plan.step_where(step, "payloads"),
                                hint="AP_Camera::set_trigger_distance() drives the primary instance only. Use "
                                     "trigger: hover (one IMAGE_START_CAPTURE reaches every instance), one WIRIS "
                                     "per survey with that camera as CAM1, or PX4 (camera_trigger addresses "
                                     "components 100..105)")
            moving = step.trigger != "hover"
            interval = optics.check_interval(info, trig, speed, where=where_speed) if moving else None
            for other in step.payloads:
                if cameras[other].protocol == "rededge-serial":
                    # its own overlap mode: its own footprint and front overlap (checked once all surveys are
                    # known: the camera holds one overlap, the most demanding), at the same speed
                    if other in infos and other != lead:
                        rededge_speeds.append((other, alt, speed, where_speed))
                    rededge_alts.setdefault(other, []).append(alt)
                    rededge_overlap.setdefault(other, []).append((step.front_pct, step.side_pct))
                elif other == lead:
                    continue
                elif other not in infos:
                    warnings.append(PlanWarning("no_optics", f"{other} triggers alongside {lead} but its optics are "
                                                             "unknown, so its coverage cannot be measured"))
                elif moving:
                    optics.check_interval(infos[other], trig, speed, where=where_speed)
            if moving:
                if info.min_interval_s and interval < NEAR_MIN_INTERVAL * info.min_interval_s:
                    warnings.append(PlanWarning(
                        "trigger_interval_near_min", f"{lead} shoots every {interval:.2f} s at {here}, close to its "
                        f"minimum of {info.min_interval_s:g} s; a gust of tail wind loses photos"))
            turnaround = step.turnaround_m if step.turnaround_m is not None else TURNAROUND_DEFAULT_M[plan.vehicle.frame]
            start = em.s.last_pos[:2] if em.s.last_pos else (plan.home.lat, plan.home.lon)
            photos_left = max(0, MAX_PHOTOS - sum(len(g.photos) for g in intent))
            try:
                if kind == "survey":
                    from missions.geometry.area import load_area
                    from missions.geometry.survey import plan_survey

                    area = load_area(step.area, exclude=step.exclude, base_dir=plan.base_dir,
                                     where=plan.step_where(step, "area"))
                    _check_reach(plan.home, area.projection.lat0, area.projection.lon0, "area", here)
                    geo = plan_survey(area, fp, step.front_pct, step.side_pct, angle_deg=step.angle_deg,
                                      turnaround_m=turnaround, speed_mps=speed,
                                      min_interval_s=info.min_interval_s, refly_90=step.refly_90,
                                      hover=step.trigger == "hover", start_latlon=start, photos_left=photos_left)
                else:
                    from missions.geometry.corridor import plan_corridor

                    if step.trigger == "hover":
                        raise PlanError("corridors are flown with distance or interval triggering",
                                        where=plan.step_where(step, "trigger"), hint="use trigger: distance")
                    _check_reach(plan.home, *step.line[0], "corridor", here)
                    geo = plan_corridor(step.line, step.width_m, fp, step.front_pct, step.side_pct,
                                        turnaround_m=turnaround, speed_mps=speed, min_interval_s=info.min_interval_s,
                                        where=plan.step_where(step, "line"), photos_left=photos_left)
                    area = geo.area
            except PlanError as e:
                raise _relocate(e, here) from None
            hold = max(HOVER_HOLD_S, info.min_interval_s or 0.0)
            track = Track(points=tuple(TrackPoint(w.lat, w.lon, w.kind, w.yaw_deg) for w in geo.waypoints),
                          spans=tuple((s.start_index, s.stop_index) for s in geo.camera_spans),
                          altitude_m=alt, trigger=step.trigger, trigger_distance_m=geo.trigger_distance_m,
                          interval_s=(geo.trigger_distance_m / speed), hold_s=hold,
                          autopilot_triggers=any(cameras[n].protocol != "rededge-serial" for n in step.payloads))
            first = em.item_count
            em.track(track, where=plan.step_where(step, "trigger"))
            for w in geo.warnings:
                warnings.append(PlanWarning(w.code, f"{kind} at {here}: {w.message}"))
            areas.append(AreaInfo(step=step.index, kind=kind, payloads=step.payloads, area=area, altitude_m=alt,
                                  front_overlap=step.front_pct / 100.0, side_overlap=step.side_pct / 100.0,
                                  trigger=step.trigger, trigger_distance_m=geo.trigger_distance_m,
                                  items=(first, em.item_count)))
            intent.append(geo)
        elif isinstance(step, WaypointStep):
            _check_reach(plan.home, step.lat, step.lon, "waypoint", here)
            em.waypoint(step.lat, step.lon, step.alt_m, step.hold_s, step.capture,
                        where=plan.step_where(step, "capture"))
            altitudes.append((step.alt_m, plan.step_where(step, "alt_m")))
        elif isinstance(step, CameraStep):
            em.camera_change(step.payload, step.values, where=plan.step_where(step, "settings"))
        elif isinstance(step, RtlStep):
            em.rtl()
        elif isinstance(step, LandStep):
            if step.lat is not None:
                _check_reach(plan.home, step.lat, step.lon, "landing point", here)
            em.land(step.lat, step.lon, where=here)

    emitted = em.result()
    warnings.extend(emitted.warnings)
    items = emitted.items
    check_items(items, prof)
    limit = plan.vehicle.max_mission_items or prof.default_item_limit
    parts = split_parts(items, limit, prof)
    for k, part in enumerate(parts):
        check_items(part, prof, where=f"part {k + 1}")
    if len(parts) > 1:
        warnings.append(PlanWarning(
            "mission_split", f"{len(items)} items exceed {prof.title}'s limit of {limit} "
            f"({prof.item_limit_why if not plan.vehicle.max_mission_items else 'vehicle.max_mission_items'})"
            f"; split into {len(parts)} parts: each part ends holding position (NAV_LOITER_UNLIM), upload "
            "the next and switch to AUTO again; it resumes at that position with speed and camera trigger restored"))

    for alt, where in altitudes:
        if alt > MAX_AGL_M:
            warnings.append(PlanWarning("altitude_above_120m", f"{alt:g} m above home at {where}; most rules allow "
                            f"{MAX_AGL_M:g} m above ground without a permit (ground assumed flat at home's height)"))

    rededge = {name: _rededge_survey(alts, rededge_overlap[name]) for name, alts in rededge_alts.items()}
    for name, alt, step_speed, where_speed in rededge_speeds:
        own = dict(next(p.values for p in plan.payloads if p.name == name))   # the plan's setting wins
        front = own.get("overlap_along_pct", rededge[name].front_pct)
        optics.check_interval(infos[name], optics.trigger_m(infos[name], alt, front), step_speed, where=where_speed)
    try:
        setup = setup_steps(plan.payloads, cameras, rededge)
    except PlanError as e:
        raise _relocate(e, plan.where("payloads")) from None
    lua = render_script(plan.name) if emitted.needs_lua else None
    try:
        params = autopilot_params(prof, plan.payloads, cameras, infos, instances, needs_lua=emitted.needs_lua,
                                  triggers={a.trigger for a in areas})
    except PlanError as e:
        raise _relocate(e, plan.where("mission")) from None
    # PayloadInfo only for payloads whose optics are known: the report measures coverage with them
    payloads = tuple(infos[p.name] for p in plan.payloads if p.name in infos)
    for name, e in optics_errors.items():
        if not any(name in a.payloads[:1] for a in areas):
            warnings.append(PlanWarning("no_optics", f"{name}: {e.message}"))
    return Compiled(
        name=plan.name, firmware=prof.name, frame=plan.vehicle.frame,
        home=(plan.home.lat, plan.home.lon, plan.home.alt_amsl_m), speed_mps=speed, items=items, parts=parts,
        item_limit=limit, payloads=payloads, areas=tuple(areas), setup=setup, lua=lua, params=params,
        warnings=tuple(dict.fromkeys(warnings)), intent=tuple(intent), inputs=input_files(plan))
