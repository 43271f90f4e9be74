"""Swaths and routes: legs split at concavities, edges covered, angle search, inside connections."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from shapely.geometry import LineString, Polygon, box
from shapely import affinity

from missions_geometry import WIRIS_60M, area_from_xy, convex_polygons, leg_crossings, star_polygons
from missions.geometry.route import build_cells, order_legs
from missions.geometry.survey import plan_survey
from missions.geometry.swaths import generate_swaths, line_offsets, normalise_angle

FP = WIRIS_60M
SPACING = FP.across_m * 0.3
TRIG = FP.along_m * 0.2


def test_angle_zero_gives_north_south_lines() -> None:
    sw = generate_swaths(box(0, 0, 300, 200), 0.0, FP.across_m, SPACING, TRIG, FP.along_m)
    for l in sw.legs:
        assert abs(l.x1 - l.x0) < 1e-9 and l.y1 > l.y0
    sw = generate_swaths(box(0, 0, 300, 200), 90.0, FP.across_m, SPACING, TRIG, FP.along_m)
    for l in sw.legs:
        assert abs(l.y1 - l.y0) < 1e-9


def test_lines_are_the_fewest_that_cover_the_width_and_are_centred() -> None:
    w = 300.0
    offs = line_offsets(w, FP.across_m, SPACING, 0.5)
    n = len(offs)
    assert (n - 1) * SPACING + FP.across_m >= w + 1.0
    assert (n - 2) * SPACING + FP.across_m < w + 1.0          # one fewer would not reach both edges
    assert offs[0] - FP.across_m / 2 == pytest.approx(w - (offs[-1] + FP.across_m / 2))


def test_concave_u_shape_splits_lines_and_never_flies_the_gap() -> None:
    u = Polygon([(0, 0), (400, 0), (400, 400), (300, 400), (300, 100), (100, 100), (100, 400), (0, 400)])
    sw = generate_swaths(u, 90.0, FP.across_m, SPACING, TRIG, FP.along_m)     # east-west lines
    # lines through both arms have two legs
    per_line: dict[int, int] = {}
    for l in sw.legs:
        per_line[l.line] = per_line.get(l.line, 0) + 1
    assert max(per_line.values()) == 2
    assert leg_crossings(sw.legs, u) == []
    gap = box(100 + 1, 100 + 1, 300 - 1, 400)
    assert sum(LineString([(l.x0, l.y0), (l.x1, l.y1)]).intersection(gap).length for l in sw.legs) < 1e-6
    # the route's connections between the arms stay inside too (via the base of the U)
    plan = plan_survey(area_from_xy(u), FP, 80, 70, angle_deg=90.0, turnaround_m=10, speed_mps=6)
    path = LineString(plan.path_xy)
    assert path.intersection(box(100 + 15, 100 + 15, 300 - 15, 400 - 15)).length == 0.0


@given(star_polygons())
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
def test_legs_never_leave_and_reenter_random_concave_areas(poly: Polygon) -> None:
    for angle in (0.0, 37.0):
        sw = generate_swaths(poly, angle, FP.across_m, SPACING, TRIG, FP.along_m)
        assert sw.legs
        assert leg_crossings(sw.legs, poly) == []


@given(star_polygons(max_radius=250))
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
def test_any_star_polygon_plans(poly: Polygon) -> None:
    plan = plan_survey(area_from_xy(poly), FP, 80, 70, angle_deg=15.0, turnaround_m=10, speed_mps=6)
    assert plan.photos and plan.camera_spans
    # every planned photo is where the trigger simulation on the flown path puts it
    assert len(plan.photos) == plan.stats.photo_count


def test_hole_is_not_flown_over_by_legs() -> None:
    outer = box(0, 0, 600, 400)
    hole = box(200, 120, 400, 280)
    geom = outer.difference(hole)
    sw = generate_swaths(geom, 0.0, FP.across_m, SPACING, TRIG, FP.along_m)
    inner = hole.buffer(-1.0)
    assert sum(LineString([(l.x0, l.y0), (l.x1, l.y1)]).intersection(inner).length for l in sw.legs) == 0.0
    plan = plan_survey(area_from_xy(geom), FP, 80, 70, angle_deg=0.0, turnaround_m=10, speed_mps=6)
    # connections may use the turnaround zone next to the hole, but never cross it
    assert LineString(plan.path_xy).intersection(hole.buffer(-15.0)).length == 0.0


def test_cells_of_a_u_shape() -> None:
    u = Polygon([(0, 0), (400, 0), (400, 400), (300, 400), (300, 100), (100, 100), (100, 400), (0, 400)])
    sw = generate_swaths(u, 90.0, FP.across_m, SPACING, TRIG, FP.along_m)
    cells = build_cells(sw.legs)
    assert len(cells) >= 3          # base, left arm, right arm
    order = order_legs(sw.legs)
    assert sorted(i for i, _ in order) == list(range(len(sw.legs)))


@pytest.mark.parametrize("azimuth", [0.0, 30.0, 65.0, -40.0])
def test_auto_angle_flies_along_a_long_strip(azimuth: float) -> None:
    strip = affinity.rotate(box(-600, -60, 600, 60), 90.0 - azimuth, origin=(0, 0))   # long axis at `azimuth`
    plan = plan_survey(area_from_xy(strip), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    diff = abs(normalise_angle(plan.angle_deg - azimuth))
    assert diff <= 1.0


def test_auto_angle_is_never_worse_than_fixed_angles_by_the_objective() -> None:
    from missions.geometry.survey import angle_objective
    poly = Polygon([(0, 0), (500, 80), (620, 400), (100, 330)])
    plan = plan_survey(area_from_xy(poly), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)

    def cost(a):
        return angle_objective(generate_swaths(poly, a, FP.across_m, SPACING, TRIG, FP.along_m), 10, 6)
    best = cost(plan.angle_deg)
    assert all(best <= cost(a) + 1e-6 for a in range(-90, 90, 15))


def test_photo_positions_line_up_across_lines() -> None:
    poly = Polygon([(0, 0), (500, 60), (450, 420), (30, 380)])
    plan = plan_survey(area_from_xy(poly), FP, 80, 70, angle_deg=0.0, turnaround_m=10, speed_mps=6)
    ys = np.array([p.y for p in plan.photos])
    phase = np.mod(ys, plan.trigger_distance_m)
    phase = np.minimum(phase, plan.trigger_distance_m - phase)
    assert phase.max() < 1e-6          # every photo on the common grid v = k·trigger


def test_first_photo_at_each_leg_start() -> None:
    plan = plan_survey(area_from_xy(box(0, 0, 300, 300)), FP, 80, 70, angle_deg=0.0, turnaround_m=10, speed_mps=6)
    firsts = {}
    for p in plan.photos:
        firsts.setdefault(p.span, p)
    for k, span in enumerate(plan.camera_spans):
        w = plan.waypoints[span.start_index]
        assert w.kind == "entry"
        assert math.hypot(firsts[k].x - w.x, firsts[k].y - w.y) < 1e-9


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(polys=st.lists(st.one_of(star_polygons(), convex_polygons()), min_size=1, max_size=3),
       angle=st.floats(-90, 90), flip=st.booleans())
def test_bare_lines_from_the_edges_measure_the_estimate_swaths(polys, angle, flip) -> None:
    """The many-parts angle search measures the bare inside segments from the edges alone (swaths.bare_lines);
    they must be generate_swaths(estimate=True)'s, whichever way the rings are drawn."""
    from shapely.geometry import MultiPolygon
    from shapely.geometry.polygon import orient

    from missions.geometry.swaths import PartEdges, bare_lines
    parts = [orient(affinity.translate(p, 2000.0 * k, 0.0), -1.0 if flip else 1.0) for k, p in enumerate(polys)]
    geom = parts[0] if len(parts) == 1 else MultiPolygon(parts)
    sw = generate_swaths(geom, angle, FP.across_m, SPACING, TRIG, FP.along_m, estimate=True)
    bare = bare_lines(PartEdges.of(geom), angle, FP.across_m, SPACING, FP.along_m)
    assert bare.legs == len(sw.legs)
    assert bare.length_m == pytest.approx(sum(l.length_m for l in sw.legs), rel=1e-9, abs=1e-6)
