"""The plan's zones as the steps meet them: tracks kept out of no-fly and exclude zones and their camera off
near no-photo ones, transits routed round them, waypoint photos dropped, and the zones each step's report
measures against.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from missions.emit.emitter import Track, TrackPoint
from missions.errors import PlanError
from missions.geometry.footprint import Footprint
from missions.geometry.survey import DEFAULT_EXIT_MARGIN_M
from missions.geometry.zones import (CameraPoint, StepZones, Zone, ZoneRouter, capture_reaches, grown_union,
                                     keep_path_out, keep_photos_out, path_inside, place_zones, zones_near)
from missions.plan.load import CorridorStep, Plan, SurveyStep, WaypointStep
from missions.compiler.context import Compilation, Lines, Payloads


def _step_footprint(c: Compilation, step: SurveyStep | CorridorStep, alt: float) -> Footprint | None:
    """The footprint holding every photo the autopilot triggers on the step (the largest across and along of its
    payloads of known optics), None when it triggers none."""
    sizes = [c.payloads.optics[n].footprint_m(alt) for n in step.payloads
             if n in c.payloads.optics and not c.payloads.is_rededge(n)]
    return Footprint(max(s[0] for s in sizes), max(s[1] for s in sizes)) if sizes else None


def track_clear_of_zones(c: Compilation, step: SurveyStep | CorridorStep, lines: Lines, track: Track, alt: float,
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


def check_path_clear_of_zones(c: Compilation, step: SurveyStep | CorridorStep, lines: Lines, track: Track,
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


def transit_to(c: Compilation, lat: float, lon: float, alt: float, what: str, where: str) -> None:
    """Waypoints round the no-fly and exclude zones between where the vehicle is and (lat, lon), at `alt`."""
    if c.transits is None:
        return
    last = c.emitter.s.last_pos
    start = last[:2] if last else (c.plan.home.lat, c.plan.home.lon)
    for la, lo in c.transits.route(start, (lat, lon), what, where):
        c.emitter.via(la, lo, alt)


def capture_clear_of_zones(c: Compilation, step: WaypointStep) -> str | None:
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


def step_zones(c: Compilation, step: SurveyStep | CorridorStep, lines: Lines, alt: float) -> StepZones | None:
    """The zones the report measures against this step: its own, and any other a footprint from its area could
    reach."""
    fp = _step_footprint(c, step, alt)
    if not c.zones:
        return None
    reach = max(fp.across_m, fp.along_m) if fp is not None else 0.0
    near = set(zones_near(c.zones, lines.area, reach))
    mine = tuple(z for z in c.zones if z.step == step.index or z in near)
    return StepZones(mine, reach) if mine else None


def check_rededge_and_zones(plan: Plan, payloads: Payloads, zones: tuple[Zone, ...]) -> None:
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
