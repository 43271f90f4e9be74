"""The plan's DEM (missions.terrain): loading it, home's elevation from it, and the clearance of the re-flown
path above it.
"""

from __future__ import annotations

from typing import Any

from missions.compiled import Compiled, PlanWarning
from missions.emit.firmware import FirmwareProfile
from missions.errors import PlanError
from missions.plan.load import Plan
from missions.compiler.context import CompileState


def load_terrain(plan: Plan, prof: FirmwareProfile) -> Any:
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


def home_elevation(plan: Plan, terrain: Any, state: CompileState) -> float:
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


def check_clearance(compiled: Compiled, terrain: Any, plan: Plan) -> None:
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
