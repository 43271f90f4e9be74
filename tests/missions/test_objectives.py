"""The angle search minimises the objective it is given (missions.geometry.objectives), on both of its paths."""

from __future__ import annotations

import functools

from shapely import affinity
from shapely.geometry import MultiPolygon, box

from missions_geometry import WIRIS_60M, area_from_xy
from missions.geometry.objectives import (PassEstimate, estimated_time_s, flight_time_s, path_length_m,
                                          turn_count)
from missions.geometry.survey import EXHAUSTIVE_ANGLE_PARTS, angle_objective, plan_survey
from missions.geometry.swaths import generate_swaths, normalise_angle

FP = WIRIS_60M


def _plan(geom, **kw):
    return plan_survey(area_from_xy(geom), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6, **kw)


def most_turns(estimate: PassEstimate, speed_mps: float) -> float:
    """The opposite of what a pilot wants: the search must still follow it."""
    return -float(estimate.turns)


def test_objectives_measure_what_their_docstring_says() -> None:
    est = PassEstimate(path_length_m=1200.0, turns=8, legs=4)
    assert flight_time_s(est, 6.0) == estimated_time_s(1200.0, 8, 6.0) == 1200.0 / 6.0 + 8 * 2 * 6.0 / 2.0
    assert flight_time_s(est, 6.0, accel_mps2=3.0) == 1200.0 / 6.0 + 8 * 2 * 6.0 / 3.0
    assert path_length_m(est, 6.0) == 1200.0
    assert turn_count(est, 6.0) == 8.0


def test_the_default_objective_is_the_flight_time() -> None:
    field = affinity.rotate(box(0, 0, 500, 200), 20.0, origin=(0, 0))
    default, explicit = _plan(field), _plan(field, objective=flight_time_s)
    assert explicit.angle_deg == default.angle_deg
    assert explicit.waypoints == default.waypoints


def _score(plan, geom, objective) -> float:
    """`objective` of the full swaths at the plan's angle, as the search's last ranking measures it."""
    sw = generate_swaths(geom, plan.angle_deg, FP.across_m, plan.spacing_m, plan.trigger_distance_m, FP.along_m)
    return angle_objective(sw, 10, 6, objective)


def test_the_search_follows_the_objective_on_one_part() -> None:
    """A 600 × 100 m strip along azimuth 90: fewest turns flies along it; most turns lines it across."""
    strip = box(0, 0, 600, 100)
    default, along, across = _plan(strip), _plan(strip, objective=turn_count), _plan(strip, objective=most_turns)
    assert abs(normalise_angle(along.angle_deg - 90.0)) <= 1.0
    assert abs(normalise_angle(across.angle_deg - 90.0)) >= 45.0
    assert len(across.legs) > 4 * len(along.legs)
    assert _score(across, strip, most_turns) < _score(default, strip, most_turns)
    assert _score(along, strip, turn_count) <= _score(across, strip, turn_count)
    # an objective with a setting of its own, bound with functools.partial
    hard_brakes = _plan(strip, objective=functools.partial(flight_time_s, accel_mps2=4.0))
    assert abs(normalise_angle(hard_brakes.angle_deg - 90.0)) <= 1.0


def test_the_search_follows_the_objective_on_many_parts() -> None:
    """Past EXHAUSTIVE_ANGLE_PARTS (the per-part estimate): along 60 m wide strips by default, lined across them
    when the objective wants turns."""
    strips = MultiPolygon([affinity.rotate(box(0, k * 100.0, 300, k * 100.0 + 60), 90.0 - 30.0, origin=(0, 0))
                           for k in range(EXHAUSTIVE_ANGLE_PARTS + 10)])
    default = _plan(strips)
    across = _plan(strips, objective=most_turns)
    assert abs(normalise_angle(default.angle_deg - 30.0)) <= 1.0
    assert abs(normalise_angle(across.angle_deg - 30.0)) >= 45.0
    assert len(across.legs) > 4 * len(default.legs)
    assert _score(across, strips, most_turns) < _score(default, strips, most_turns)
