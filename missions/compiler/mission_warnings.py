"""The warnings about the mission as a whole: how it starts, how high it flies, payloads it cannot measure.
"""

from __future__ import annotations

from missions.plan.load import TakeoffStep
from missions.plan.schema import MAX_AGL_M
from missions.compiler.context import Compilation


def warn_about_the_start(c: Compilation) -> None:
    if c.emitter.speed_is_airspeed:
        c.warn("speed_is_airspeed", f"ArduPilot flies a {c.plan.vehicle.frame}'s vehicle.speed_mps "
               f"({c.speed_mps:g} m/s) as airspeed (a ground-speed DO_CHANGE_SPEED would set its minimum ground "
               "speed instead); with wind the ground speed differs, so photo intervals and flight time vary "
               "(distance triggering keeps its spacing)")
    if not any(isinstance(s, TakeoffStep) for s in c.plan.mission):
        c.warn("no_takeoff", "the mission has no takeoff step; it must be started with the vehicle in the air")


def warn_about_altitudes(c: Compilation) -> None:
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


def warn_about_unknown_optics(c: Compilation) -> None:
    """A payload of unknown optics that sets no lines is only unmeasured (one that does is an error)."""
    for name, e in c.payloads.optics_errors.items():
        if not any(name in a.payloads[:1] for a in c.state.areas):
            c.warn("no_optics", f"{name}: {e.message}")
