"""Objectives of the line-angle search: what a candidate angle is scored by, lower is better.

The search (`survey.best_angle`) measures what the survey would fly at each candidate angle as a `PassEstimate`
and scores it with an objective, a plain function `objective(estimate, speed_mps) -> float`; it never looks
inside the objective, so a caller can rank angles by anything the estimate carries:

    flight_time_s   seconds: the path at `speed_mps` plus braking and re-accelerating at every turn
                    (`estimated_time_s`, as in `SurveyStats.est_time_s`). The default: what a pilot pays for.
    path_length_m   metres of path (legs, turnaround stubs, connections), whatever the turns cost.
    turn_count      leg ends where the vehicle stops and turns (two per leg): fewest turns, whatever the path.

An objective that needs a setting of its own takes it as a keyword with a default, bound with
`functools.partial` (e.g. `partial(flight_time_s, accel_mps2=3.0)` for a vehicle that brakes harder).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

# A multirotor brakes and re-accelerates at each leg end; at ~2 m/s² (ArduCopter WPNAV_ACCEL default
# 250 cm/s²) that costs about 2·v/a seconds beyond the straight-line time.
DEFAULT_ACCEL_MPS2 = 2.0
HOVER_HOLD_S = 4.0        # QGC's _hoverAndCaptureDelaySeconds


class PassEstimate(NamedTuple):
    """What a survey would fly at one line angle, as the angle search estimates it (no turnaround repairs, no
    detours): the inputs every objective chooses from."""

    path_length_m: float     # legs, with their turnaround stubs, and the hops between them
    turns: int               # leg ends, where the vehicle brakes and turns
    legs: int


# objective(estimate, speed_mps) -> score; lower is better
Objective = Callable[[PassEstimate, float], float]


def estimated_time_s(path_length_m: float, turns: int, speed_mps: float, accel_mps2: float = DEFAULT_ACCEL_MPS2,
                     hover_stops: int = 0, hover_s: float = HOVER_HOLD_S) -> float:
    """Flight time: cruise over the path, plus braking/accelerating at each turn, plus hover holds."""
    per_stop = 2.0 * speed_mps / accel_mps2
    return path_length_m / speed_mps + turns * per_stop + hover_stops * (hover_s + per_stop)


def flight_time_s(estimate: PassEstimate, speed_mps: float, accel_mps2: float = DEFAULT_ACCEL_MPS2) -> float:
    """Seconds to fly the pass: the default objective."""
    return estimated_time_s(estimate.path_length_m, estimate.turns, speed_mps, accel_mps2)


def path_length_m(estimate: PassEstimate, speed_mps: float) -> float:
    """Metres of path; the speed does not matter."""
    return estimate.path_length_m


def turn_count(estimate: PassEstimate, speed_mps: float) -> float:
    """Turns at the leg ends; the speed does not matter."""
    return float(estimate.turns)
