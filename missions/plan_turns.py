"""A plane's or VTOL's turns at plan level: its radius from the plan, the turnaround it needs, and what the
pilot should know about lines it cannot turn between (missions.geometry.turns has the geometry).

A copter turns on the spot: none of this applies to it (radius None).
"""

from __future__ import annotations

import math
from typing import Any

from missions.compiled import PlanWarning
from missions.geometry.turns import turn_radius_m


def turn_radius_of(vehicle: Any, speed_mps: float) -> float | None:
    """vehicle.turn_radius_m, or a coordinated turn at the survey speed and vehicle.max_bank_deg (default 30°)."""
    if vehicle.frame == "copter":
        return None
    if vehicle.turn_radius_m is not None:
        return vehicle.turn_radius_m
    return turn_radius_m(speed_mps, vehicle.max_bank_deg)


def default_turnaround_m(frame_default_m: float, radius_m: float | None) -> float:
    """A plane's default run-in and run-out: at least one turn radius, so that it comes out of the turn and is on
    the line (wings level) before the first photo."""
    return frame_default_m if radius_m is None else max(frame_default_m, math.ceil(radius_m))


def turn_warnings(route: Any, radius_m: float | None, turnaround_m: float | None) -> list[PlanWarning]:
    """Lines closer than two radii (flown skip-line, or looped onto), lines shorter than a turn, and a plan's own
    turnaround shorter than a radius."""
    if radius_m is None:
        return []
    out = []
    spacing = getattr(route, "spacing_m", None)
    if spacing is not None and spacing < 2.0 * radius_m:
        gap = math.ceil(2.0 * radius_m / spacing - 1e-9)
        out.append(PlanWarning("lines_closer_than_turn", f"lines {spacing:.1f} m apart are closer than two turn "
                               f"radii (2 × {radius_m:.0f} m): they are flown skipping {gap - 1} line"
                               f"{'s' if gap > 2 else ''} between turns where the area allows, and with a loop turn "
                               "onto a neighbour where it does not; the flight time counts the turns as flown"))
    legs = getattr(route, "legs", ())
    short = [leg for leg in legs if math.hypot(leg.x1 - leg.x0, leg.y1 - leg.y0) < 2.0 * radius_m]
    if short:
        out.append(PlanWarning("line_shorter_than_turn", f"{len(short)} of {len(legs)} lines are shorter than a "
                               f"turn's diameter (2 × {radius_m:.0f} m): the plane spends more time turning than "
                               "photographing there; fly the lines along the area's long side (angle_deg) or "
                               "give vehicle.turn_radius_m if it turns tighter"))
    if turnaround_m is not None and turnaround_m < radius_m:
        out.append(PlanWarning("turnaround_shorter_than_turn", f"turnaround_m {turnaround_m:g} is shorter than the "
                               f"turn radius ({radius_m:.0f} m): the plane may still be turning at a line's first "
                               f"photo; leave turnaround_m out (the default is one radius) or give at least "
                               f"{math.ceil(radius_m)}"))
    return out
