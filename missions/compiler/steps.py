"""One function per plan step type (`STEPS`), each adding the step's items to the emitter; surveys and corridors
go through `missions.compiler.lines`.
"""

from __future__ import annotations

from typing import Any, Callable

from missions.plan.load import CameraStep, CorridorStep, LandStep, RtlStep, SurveyStep, TakeoffStep, WaypointStep
from missions.compiler.context import Altitude, Compilation, check_reach
from missions.compiler.lines import lines_step, plan_corridor_lines, plan_survey_lines
from missions.compiler.zones import capture_clear_of_zones, transit_to


def _takeoff(c: Compilation, step: TakeoffStep) -> None:
    c.emitter.takeoff(step.alt_m)
    c.state.altitudes.append(Altitude(step.alt_m, c.plan.step_where(step, "alt_m")))


def _waypoint(c: Compilation, step: WaypointStep) -> None:
    check_reach(c.plan.home, step.lat, step.lon, "waypoint", c.plan.step_where(step))
    transit_to(c, step.lat, step.lon, step.alt_m, "flight to this waypoint", c.plan.step_where(step))
    c.emitter.waypoint(step.lat, step.lon, step.alt_m, step.hold_s, capture_clear_of_zones(c, step),
                       where=c.plan.step_where(step, "capture"))
    c.state.altitudes.append(Altitude(step.alt_m, c.plan.step_where(step, "alt_m")))


def _camera(c: Compilation, step: CameraStep) -> None:
    c.emitter.camera_change(step.payload, step.values, where=c.plan.step_where(step, "settings"))
    c.state.settings_now.setdefault(step.payload, {}).update(step.values)


def _rtl(c: Compilation, step: RtlStep) -> None:
    last = c.emitter.s.last_pos
    if last is not None:
        # the vehicle flies home straight from where it is: from the last way round the zones, that is clear
        transit_to(c, c.plan.home.lat, c.plan.home.lon, last[2], "return home", c.plan.step_where(step))
    c.emitter.rtl()


def _land(c: Compilation, step: LandStep) -> None:
    here = c.plan.step_where(step)
    if step.lat is not None:
        check_reach(c.plan.home, step.lat, step.lon, "landing point", here)
        last = c.emitter.s.last_pos
        if last is not None:
            transit_to(c, step.lat, step.lon, last[2], "flight to the landing point", here)
    c.emitter.land(step.lat, step.lon, where=here)


def _survey(c: Compilation, step: SurveyStep) -> None:
    lines_step(c, step, "survey", plan_survey_lines)


def _corridor(c: Compilation, step: CorridorStep) -> None:
    lines_step(c, step, "corridor", plan_corridor_lines)


STEPS: dict[type, Callable[[Compilation, Any], None]] = {
    TakeoffStep: _takeoff, SurveyStep: _survey, CorridorStep: _corridor, WaypointStep: _waypoint,
    CameraStep: _camera, RtlStep: _rtl, LandStep: _land}
