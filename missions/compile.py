"""compile_plan: capture plan -> Compiled (mission items, parts, setup sequence, Lua bridge, params, warnings).

    compiled = compile_plan("plan.yaml")                 # the plan's firmware
    compiled = compile_plan(plan, firmware="px4")        # a loaded Plan, another firmware

Pipeline, as `compile_plan` reads: load (schema, locations) -> the payloads' cameras and optics
(missions.compiler.payloads) and the speed (missions.compiler.speed) -> per step, the function
`missions.compiler.steps.STEPS` names for its type: a survey or corridor (missions.compiler.lines) goes area ->
geometry (missions.geometry.survey, missions.geometry.corridor) -> items (missions.emit.emitter, firmware ×
camera), kept clear of the plan's zones (missions.compiler.zones) -> firmware check (missions.emit.firmware) ->
item limit / parts (missions.sorties) -> setup sequence, Lua bridge, autopilot params (missions.compiler.preflight)
-> warnings (missions.compiler.mission_warnings) -> fence (missions.compiler.fence) -> clearance over a DEM
(missions.compiler.terrain) -> the sun. What the steps add up as they go (warnings, areas, altitudes, what the
RedEdges fly) is one `CompileState`, local to the compile (missions.compiler.context). Pure: no sockets, no
files written; errors are PlanError with the plan's file:line:col.

Warnings are `PlanWarning(code, message)` values. Codes: altitude_above_120m, assumed_optics, trigger_interval_near_min,
area_smaller_than_footprint (and the survey planner's own codes), no_takeoff, component_id_chosen,
no_optics, mission_split, px4_single_capture_all; with a DEM (missions.terrain) terrain_rate_limited,
home_elevation_differs, rededge_over_terrain.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from missions.compiled import Compiled
from missions.emit.firmware import check_items, profile
from missions.errors import PlanError, Problem
from missions.geometry.geo import LocalProjection
from missions.geometry.zones import TransitRouter, plan_zones
from missions.plan.load import Plan, input_files, load_plan_partly, raise_problems
from missions.sorties import in_sorties
from missions.plan_turns import turn_radius_of
from missions.thermal.assess import assess
from missions.compiler.context import Compilation, CompileState
from missions.compiler.payloads import emitter_for, resolve_payloads
from missions.compiler.speed import mission_speed
from missions.compiler.steps import STEPS
from missions.compiler.zones import check_rededge_and_zones
from missions.compiler.preflight import lua_bridge, mission_params, setup_sequence
from missions.compiler.fence import mission_fence
from missions.compiler.mission_warnings import warn_about_altitudes, warn_about_the_start, warn_about_unknown_optics
from missions.compiler.terrain import check_clearance, home_elevation, load_terrain


def _problems_of(err: PlanError) -> list[Problem]:
    return list(err.problems) or [Problem(err.where or "", err.message, err.hint)]


def _compile_steps(c: Compilation) -> list[Problem]:
    """Every step compiled in order; a step that fails is left out and the next ones still checked, so that
    one run reports every step's problem."""
    problems: list[Problem] = []
    for step in c.plan.mission:
        try:
            STEPS[type(step)](c, step)
        except PlanError as e:
            problems.extend(_problems_of(e))
    return problems


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
    state = CompileState(warnings=[f"component_id_chosen: {n}" for n in plan.notes])
    try:
        terrain = load_terrain(plan, prof)
        home_amsl = home_elevation(plan, terrain, state)
        payloads = resolve_payloads(plan, prof, state)
        speed = mission_speed(plan, payloads, state)
        zones = plan_zones(plan)
        check_rededge_and_zones(plan, payloads, zones)
    except PlanError as e:
        raise_problems(problems + _problems_of(e), plan.path)
    radius = turn_radius_of(plan.vehicle, speed)
    router = TransitRouter(zones, LocalProjection(plan.home.lat, plan.home.lon)) if zones else None
    c = Compilation(plan, prof, payloads, emitter_for(plan, prof, payloads, speed), state, speed, radius, zones, router,
                    terrain)
    c.emitter.home_amsl_m = home_amsl
    if terrain is not None and any(c.payloads.is_rededge(p.name) for p in plan.payloads):
        c.warn("rededge_over_terrain", "a RedEdge in overlap mode spaces its photos by its own height above the "
               "take-off point, not above the DEM: over rising or falling ground its front overlap and its "
               "capture threshold (operatingAlt) differ from the plan's; the report measures what it does")
    warn_about_the_start(c)
    problems += _compile_steps(c)
    if problems:
        # the mission misses the failed steps: what follows (items, parts, setup) would judge a mission nobody
        # asked for; the pre-flight setup depends on the payloads alone and is still checked
        try:
            setup_sequence(c)
        except PlanError as e:
            problems += _problems_of(e)
        raise_problems(problems, plan.path)
    emitted = c.emitter.result()
    state.warnings.extend(emitted.warnings)
    check_items(emitted.items, prof)
    warn_about_altitudes(c)
    setup = setup_sequence(c)
    lua = lua_bridge(c, emitted)
    params = mission_params(c, emitted)
    if terrain is not None and terrain.frame == "terrain":
        params = (*params, ("TERRAIN_ENABLE", 1.0, "the survey lines fly in the terrain frame "
                            "(MAV_FRAME_GLOBAL_TERRAIN_ALT): ArduPilot needs terrain data, from the ground station "
                            "or its SD card, before it accepts them"))
    warn_about_unknown_optics(c)
    fence = mission_fence(c, emitted.items)
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
        check_clearance(compiled, terrain, plan)
    return _with_the_sun(plan, in_sorties(plan, compiled))


def _with_the_sun(plan: Plan, compiled: Compiled) -> Compiled:
    """The sun over each timed step and the PV profile's findings: its violations are the plan's errors."""
    found = assess(plan, compiled)
    raise_problems(list(found.problems), plan.path)
    if not found.steps and not found.warnings:
        return compiled
    return replace(compiled, sun=found.steps, warnings=tuple(dict.fromkeys(compiled.warnings + found.warnings)))
