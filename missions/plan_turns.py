"""A plane's or VTOL's turns at plan level: its radius from the plan, the turnaround it needs, and what the
pilot should know about lines it cannot turn between (missions.geometry.turns has the geometry).

A copter turns on the spot: none of this applies to it (radius None).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from missions.compiled import PlanWarning
from missions.geometry.turns import turn_radius_m


def turn_radius_of(vehicle: Any, speed_mps: float) -> float | None:
    """vehicle.turn_radius_m, or a coordinated turn at the survey speed and vehicle.max_bank_deg (default 30°)."""
    if vehicle.frame == "copter":
        return None
    if vehicle.turn_radius_m is not None:
        return vehicle.turn_radius_m
    return turn_radius_m(speed_mps, vehicle.max_bank_deg)


# ArduPlane's NAVL1_PERIOD default (AP_L1_Control's "PERIOD", seconds): the period of its L1 controller's
# convergence onto a new line; ArduPilot's SITL plane flies 15.
ARDUPLANE_L1_PERIOD_S = 17.0


def default_turnaround_m(frame_default_m: float, radius_m: float | None, firmware: str = "",
                         speed_mps: float | None = None) -> float:
    """A plane's default run-in and run-out: at least one turn radius, so that it comes out of the turn and is on
    the line (wings level) before the first photo. ArduPlane flies a turnaround as straight legs between its
    waypoints, cutting each corner (it accepts a waypoint up to WP_RADIUS before it) and converging on the next
    leg at its L1 controller's pace: flown in SITL with one radius of run-in, it crossed each line's first photo
    11-51 m off the line and took 150-250 m to settle. So on ArduPilot the run-in adds one L1 period of flight."""
    if radius_m is None:
        return frame_default_m
    settle = ARDUPLANE_L1_PERIOD_S * speed_mps if firmware == "ardupilot" and speed_mps else 0.0
    return max(frame_default_m, math.ceil(radius_m + settle))


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
                               f"photo; leave turnaround_m out (the default is one radius, on ArduPilot plus one L1 period "
                               f"of flight for its run onto the line) or give at least "
                               f"{math.ceil(radius_m)}"))
    return out


class LineEnd(NamedTuple):
    """Where a line's camera-off waypoint goes past its last photo: margin_m plus stretch × the line's length."""

    margin_m: float
    stretch: float


def line_end(firmware: str, frame: str, speed_mps: float, trigger_m: float,
             default_margin_m: float) -> LineEnd:
    """ArduPlane's trigger fires each photo half a 50 Hz check late on average (the line's last photo comes
    stretch × its length later), and its 10 Hz navigate task switches the camera on and off up to a tick after
    the waypoints: the exit goes that much further, so the last photo is taken (flown in SITL with 2 m: 4 lines
    of 7 lost it). Copters and PX4 keep the plain margin."""
    if firmware != "ardupilot" or frame == "copter" or trigger_m <= 0:
        return LineEnd(default_margin_m, 0.0)
    from missions.measure.flight import ARDUPLANE_NAV_HZ, arduplane_trigger_spacing_m
    return LineEnd(default_margin_m + speed_mps / ARDUPLANE_NAV_HZ,
                   arduplane_trigger_spacing_m(trigger_m, speed_mps) / trigger_m - 1.0)
