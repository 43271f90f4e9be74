"""What the report and QGC's editors read of a compiled survey or corridor: the step's numbers and their
assumptions (StepFacts), the files each photo writes, and the step as QGC's survey or corridor pattern.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from missions.compiled import CaptureSize, PayloadInfo, StepFacts, TransectPattern
from missions.geometry.area import Area
from missions.geometry.corridor import CorridorPlan
from missions.geometry.footprint import Footprint
from missions.geometry.survey import SurveyPlan
from missions.plan.load import CorridorStep, SurveyStep
from missions.compiler.context import Compilation, Lines, TURNAROUND_DEFAULT_M


def pattern(c: Compilation, step: SurveyStep | CorridorStep, kind: str, lines: Lines, lead: PayloadInfo, alt: float,
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


def _turnaround_m(c: Compilation, step: SurveyStep | CorridorStep) -> float:
    return step.turnaround_m if step.turnaround_m is not None else TURNAROUND_DEFAULT_M[c.plan.vehicle.frame]


def facts_of_step(c: Compilation, step: SurveyStep | CorridorStep, kind: str, lead: PayloadInfo, footprint: Footprint,
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


def _capture_size(c: Compilation, name: str) -> CaptureSize:
    """The files each photo of payload `name` writes with the settings it holds now, and their size."""
    cam = c.payloads.cameras[name]
    held = c.state.settings_now.setdefault(name, dict(c.plan.payload(name).values))
    formats, mb = cam.capture_formats(held)
    if mb is not None:
        source = cam.capture_sizes.source
    else:
        source = f"{cam.model}: no published image sizes in the catalogue (cdf/tables/{cam.table})"
    return CaptureSize(name, formats, mb, source)


def _assumptions(c: Compilation, step: SurveyStep | CorridorStep) -> list[str]:
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
