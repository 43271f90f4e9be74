"""A survey or corridor step: its lead payload's optics set the altitude, footprint and trigger distance, every
payload is checked against the trigger, the planners (missions.geometry.survey, missions.geometry.corridor) lay
the lines, the DEM re-plans and follows them, and the lines become the emitter's track.
"""

from __future__ import annotations

from typing import Any, Callable

from missions.compiled import AreaInfo, PayloadInfo
from missions.emit.emitter import Track, TrackPoint, HOVER_HOLD_S
from missions.errors import PlanError
from missions.geometry import optics, survey
from missions.geometry.corridor import CorridorPlan, plan_corridor
from missions.geometry.footprint import Footprint
from missions.geometry.survey import SurveyPlan, plan_survey
from missions.geometry.zones import area_clear_of
from missions.plan.load import CorridorStep, SurveyStep
from missions.plan_turns import default_turnaround_m, line_end, turn_warnings
from missions.thermal.speed import check_sharp
from missions.compiler.context import (Altitude, Compilation, LineInputs, Lines, NEAR_MIN_INTERVAL, RedEdgeCheck,
                                       RedEdgeFlight, TURNAROUND_DEFAULT_M, check_reach, relocate)
from missions.compiler.payloads import lead_optics, line_altitude
from missions.compiler.speed import step_limits
from missions.compiler.facts import facts_of_step, pattern
from missions.compiler.zones import check_path_clear_of_zones, step_zones, track_clear_of_zones, transit_to


def lines_step(c: Compilation, step: SurveyStep | CorridorStep, kind: str,
               plan_lines: Callable[[Compilation, Any, LineInputs], Lines]) -> None:
    """A survey or corridor: its first payload's optics set the altitude, footprint and trigger distance, every
    payload must keep up with the trigger, and the planned lines become the emitter's track."""
    here = c.plan.step_where(step)
    lead = lead_optics(c.plan, c.payloads, step, kind)
    alt = line_altitude(c.plan, step, lead)
    c.state.altitudes.append(Altitude(alt, c.plan.step_where(
        step, "altitude_m" if step.altitude_m is not None else "gsd_cm")))
    footprint = optics.footprint(lead, alt)
    trig = optics.trigger_m(lead, alt, step.front_pct)
    _check_triggering(c, step, lead, trig)
    check_sharp(step_limits(c.plan, c.payloads, step, lead, alt), c.speed_mps, c.plan.where("vehicle", "speed_mps"))
    _record_rededges(c, step, lead, alt)
    try:
        lines = plan_lines(c, step, _line_inputs(c, step, lead, footprint))
        if c.terrain is not None:
            lines = _lines_for_the_ground(c, step, lead, alt, footprint, lines, plan_lines)
    except PlanError as e:
        raise relocate(e, here) from None
    first = c.emitter.item_count
    track = track_clear_of_zones(c, step, lines, _track(c, step, lines.route, alt, lead), alt, kind)
    if c.terrain is not None:
        track = _terrain_track(c, step, kind, track)
    check_path_clear_of_zones(c, step, lines, track, kind)
    transit_to(c, track.points[0].lat, track.points[0].lon, alt, f"flight to the {kind}'s first line", here)
    c.emitter.track(track, where=c.plan.step_where(step, "trigger"))
    for w in lines.route.warnings:
        c.warn(w.code, f"{kind} at {here}: {w.message}")
    for w in turn_warnings(lines.route, c.turn_radius_m, _line_inputs_turnaround(c, step)):
        c.warn(w.code, f"{kind} at {here}: {w.message}")
    c.state.areas.append(AreaInfo(
        step=step.index, kind=kind, payloads=step.payloads, area=lines.area, altitude_m=alt,
        front_overlap=step.front_pct / 100.0, side_overlap=step.side_pct / 100.0, trigger=step.trigger,
        trigger_distance_m=lines.route.trigger_distance_m, items=(first, c.emitter.item_count),
        zones=step_zones(c, step, lines, alt),
        line_items=_line_items(c.emitter.s.track_navs, lines.route)))
    c.state.intent.append(lines.route)
    c.state.step_facts.append(facts_of_step(c, step, kind, lead, footprint, lines.route))
    c.state.patterns.append(pattern(c, step, kind, lines, lead, alt, first))


def _line_items(navs: tuple[int, ...], route: SurveyPlan | CorridorPlan) -> tuple[int, ...]:
    """The items of the points after each camera span's entry up to its exit: flying towards them is flying a line."""
    return tuple(navs[k] for s in route.camera_spans for k in range(s.start_index + 1, s.stop_index + 1)
                 if k < len(navs))


def _check_triggering(c: Compilation, step: SurveyStep | CorridorStep, lead: PayloadInfo, trig: float) -> None:
    """Every payload the autopilot triggers must be reached by the trigger and keep up with its interval; a
    payload of unknown optics flies along unmeasured (warned). RedEdges are checked in `setup_sequence`."""
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


def _check_distance_trigger_reach(c: Compilation, step: SurveyStep | CorridorStep) -> None:
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


def _record_rededges(c: Compilation, step: SurveyStep | CorridorStep, lead: PayloadInfo, alt: float) -> None:
    """What each RedEdge of the step flies: its overlap mode (set once, in `setup_sequence`) must cover it."""
    where = c.plan.step_where(step, "overlap", "front")
    for name in step.payloads:
        if not c.payloads.is_rededge(name):
            continue
        if name in c.payloads.optics and name != lead.name:
            c.state.rededge_checks.append(RedEdgeCheck(name, alt, where))
        c.state.rededge_flights.setdefault(name, []).append(RedEdgeFlight(alt, step.front_pct, step.side_pct))


def _line_inputs(c: Compilation, step: SurveyStep | CorridorStep, lead: PayloadInfo,
                 footprint: Footprint) -> LineInputs:
    last = c.emitter.s.last_pos
    return LineInputs(
        footprint=footprint,
        turnaround_m=step.turnaround_m if step.turnaround_m is not None
        else default_turnaround_m(TURNAROUND_DEFAULT_M[c.plan.vehicle.frame], c.turn_radius_m, c.profile.name,
                                  c.speed_mps),
        start_latlon=last[:2] if last else (c.plan.home.lat, c.plan.home.lon),
        photos_left=max(0, survey.MAX_PHOTOS - sum(len(g.photos) for g in c.state.intent)),
        min_interval_s=lead.min_interval_s)


def _line_inputs_turnaround(c: Compilation, step: SurveyStep | CorridorStep) -> float | None:
    """The step's own turnaround_m (None: the default, which a plane's turn already sizes)."""
    return step.turnaround_m


def plan_survey_lines(c: Compilation, step: SurveyStep, inputs: LineInputs) -> Lines:
    area = area_clear_of(step.area, c.zones, c.plan.base_dir, c.plan.step_where(step, "area"))
    check_reach(c.plan.home, area.projection.lat0, area.projection.lon0, "area", c.plan.step_where(step))
    end = line_end(c.profile.name, c.plan.vehicle.frame, c.speed_mps,
                   survey.trigger_distance_m(inputs.footprint, step.front_pct), survey.DEFAULT_EXIT_MARGIN_M)
    route = plan_survey(area, inputs.footprint, step.front_pct, step.side_pct, angle_deg=step.angle_deg,
                        turnaround_m=inputs.turnaround_m, speed_mps=c.speed_mps,
                        min_interval_s=inputs.min_interval_s, refly_90=step.refly_90,
                        hover=step.trigger == "hover", start_latlon=inputs.start_latlon,
                        photos_left=inputs.photos_left, turn_radius_m=c.turn_radius_m,
                        exit_margin_m=end.margin_m, exit_stretch=end.stretch)
    return Lines(route, area)


def plan_corridor_lines(c: Compilation, step: CorridorStep, inputs: LineInputs) -> Lines:
    if step.trigger == "hover":
        raise PlanError("corridors are flown with distance or interval triggering",
                        where=c.plan.step_where(step, "trigger"), hint="use trigger: distance")
    check_reach(c.plan.home, *step.line[0], "corridor", c.plan.step_where(step))
    route = plan_corridor(step.line, step.width_m, inputs.footprint, step.front_pct, step.side_pct,
                          turnaround_m=inputs.turnaround_m, speed_mps=c.speed_mps,
                          min_interval_s=inputs.min_interval_s, where=c.plan.step_where(step, "line"),
                          photos_left=inputs.photos_left)
    return Lines(route, route.area)


def _track(c: Compilation, step: SurveyStep | CorridorStep, route: SurveyPlan | CorridorPlan, alt: float,
           lead: PayloadInfo) -> Track:
    """The planned lines as the emitter flies them; a hover photo holds at least the camera's interval."""
    return Track(points=tuple(TrackPoint(w.lat, w.lon, w.kind, w.yaw_deg) for w in route.waypoints),
                 spans=tuple((s.start_index, s.stop_index) for s in route.camera_spans),
                 altitude_m=alt, trigger=step.trigger, trigger_distance_m=route.trigger_distance_m,
                 interval_s=(route.trigger_distance_m / c.speed_mps),
                 hold_s=hover_hold_s(lead),
                 autopilot_triggers=any(not c.payloads.is_rededge(n) for n in step.payloads))


def hover_hold_s(lead: PayloadInfo) -> float:
    """A hover photo waits until the vehicle has settled: QGC's hover delay at least, and long enough for a
    microbolometer to settle on the still scene (five time constants: 99 % of a first-order step response) and
    then take the photo (the camera's minimum capture interval)."""
    settle = 5.0 * (lead.time_constant_ms or 0.0) / 1000.0
    return max(HOVER_HOLD_S, settle + (lead.min_interval_s or 0.0))


def _lines_for_the_ground(c: Compilation, step: SurveyStep | CorridorStep, lead: PayloadInfo, alt: float,
                          footprint: Footprint, lines: Lines,
                          plan_lines: Callable[[Compilation, Any, LineInputs], Lines]) -> Lines:
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


def _terrain_track(c: Compilation, step: SurveyStep | CorridorStep, kind: str, track: Track) -> Track:
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
