"""After the steps, what goes up beside the mission items: the cameras' pre-flight setup sequence (each
RedEdge's overlap mode covering what it flies), the ArduPilot Lua bridge and the autopilot parameters.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink

from missions.compiled import SetupStep
from missions.emit.emitter import Emitted
from missions.emit.lua import render_script
from missions.emit.params import Param, autopilot_params
from missions.emit.setup import RedEdgeSurvey, setup_steps
from missions.errors import PlanError
from missions.geometry import optics
from missions.compiler.context import Compilation, RedEdgeFlight, relocate


def rededge_survey(flights: list[RedEdgeFlight]) -> RedEdgeSurvey:
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


def setup_sequence(c: Compilation) -> tuple[SetupStep, ...]:
    """The pre-flight sequence, with each RedEdge's overlap mode covering what it flies."""
    rededge = {name: rededge_survey(flights) for name, flights in c.state.rededge_flights.items()}
    for check in c.state.rededge_checks:
        info = c.payloads.optics[check.payload]
        own = dict(c.plan.payload(check.payload).values)   # the plan's setting wins
        front = own.get("overlap_along_pct", rededge[check.payload].front_pct)
        optics.check_interval(info, optics.trigger_m(info, check.altitude_m, front), c.speed_mps, where=check.where)
    try:
        return setup_steps(c.plan.payloads, c.payloads.cameras, rededge)
    except PlanError as e:
        raise relocate(e, c.plan.where("payloads")) from None


def lua_bridge(c: Compilation, emitted: Emitted) -> str | None:
    return render_script(c.plan.name) if emitted.needs_lua else None


def _fixed_wing_without_landing(c: Compilation, emitted: Emitted) -> bool:
    """A plane or VTOL mission that ends without a landing item (an RTL, a loiter)."""
    landings = (mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_NAV_VTOL_LAND, mavlink.MAV_CMD_DO_LAND_START)
    return c.plan.vehicle.frame != "copter" and not any(it.command in landings for it in emitted.items)


def mission_params(c: Compilation, emitted: Emitted) -> tuple[Param, ...]:
    try:
        return autopilot_params(c.profile, c.plan.payloads, c.payloads.cameras, c.payloads.optics,
                                c.payloads.instances, needs_lua=emitted.needs_lua,
                                triggers={a.trigger for a in c.state.areas},
                                version=c.plan.vehicle.firmware_version,
                                fixed_wing_without_landing=_fixed_wing_without_landing(c, emitted),
                                speed_mps=c.speed_mps)
    except PlanError as e:
        raise relocate(e, c.plan.where("mission")) from None
