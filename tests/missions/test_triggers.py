"""Distance-trigger simulation as ArduPilot/PX4 execute DO_SET_CAM_TRIGG_DIST."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings, strategies as st

from missions.geometry.triggers import TriggerSpan, photos_along, simulate_distance_trigger


def test_straight_leg_start_photo_then_every_distance() -> None:
    ph = simulate_distance_trigger([(0, 0), (0, 100)], [TriggerSpan(0, 1, 10.0)])
    assert [round(p.y, 9) for p in ph] == [10.0 * k for k in range(11)]      # the end lands exactly on k·d
    assert all(p.heading_deg == 0.0 for p in ph)


def test_param3_zero_means_no_photo_at_start_and_stop_photo_when_asked() -> None:
    ph = simulate_distance_trigger([(0, 0), (25, 0)], [TriggerSpan(0, 1, 10.0, shoot_at_start=False, shoot_at_stop=True)])
    assert [(round(p.x, 9), p.heading_deg) for p in ph] == [(10.0, 90.0), (20.0, 90.0), (25.0, 90.0)]


def test_distance_is_measured_from_the_last_photo_not_along_the_path() -> None:
    # both firmwares compare the current position with the last photo's: after a 90° bend the next
    # photo comes when the straight-line distance reaches d (x = √(6² − 5²)), not after 6 m of path
    ph = simulate_distance_trigger([(0, 0), (0, 5), (10, 5)], [TriggerSpan(0, 2, 6.0)])
    assert ph[1].x == pytest.approx(math.sqrt(11.0)) and ph[1].y == pytest.approx(5.0)
    assert ph[1].heading_deg == pytest.approx(90.0)


def test_camera_off_between_spans() -> None:
    path = [(0, 0), (0, 30), (20, 30), (20, 0)]
    ph = simulate_distance_trigger(path, [TriggerSpan(0, 1, 10.0), TriggerSpan(2, 3, 10.0)])
    assert {p.span for p in ph} == {0, 1}
    assert not [p for p in ph if 0 < p.x < 20]        # nothing on the connection
    assert [round(p.y, 6) for p in ph if p.span == 1] == [30.0, 20.0, 10.0, 0.0]


def test_bad_span_indices() -> None:
    with pytest.raises(ValueError):
        simulate_distance_trigger([(0, 0), (0, 1)], [TriggerSpan(0, 5, 1.0)])


@given(st.lists(st.tuples(st.floats(-500, 500), st.floats(-500, 500)), min_size=2, max_size=8),
       st.floats(0.5, 50))
@settings(max_examples=80, deadline=None)
def test_consecutive_photos_are_exactly_the_distance_apart(path, d) -> None:
    ph = simulate_distance_trigger(path, [TriggerSpan(0, len(path) - 1, d)])
    for a, b in zip(ph, ph[1:]):
        assert math.hypot(b.x - a.x, b.y - a.y) == pytest.approx(d, rel=1e-6, abs=1e-6)
    # and no photo is missed: the path never gets d away from the last photo without one
    last = ph[-1]
    end = path[-1]
    # the remaining path after the last photo stays within d of it (checked at the vertices)
    assert math.hypot(end[0] - last.x, end[1] - last.y) < d * (1 + 1e-6) or len(path) > 2


def test_photos_along_measures_path_length() -> None:
    ph = photos_along([(0, 0), (0, 5), (10, 5)], 5.0)
    assert [(round(p.x, 9), round(p.y, 9)) for p in ph] == [(0, 0), (0, 5), (5, 5), (10, 5)]
