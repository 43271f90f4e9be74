"""plan_survey / plan_corridor end to end: named places, modes, errors, and 'a plan or a PlanError'."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from shapely.geometry import Point

from missions_geometry import WIRIS_60M, area_from_xy, leg_crossings
from missions.geometry.area import load_area
from missions.geometry.corridor import plan_corridor
from missions.measure.coverage import measure
from missions.errors import PlanError
from missions.geometry.geo import unwrap_lons
from missions.geometry.swaths import normalise_angle
from missions.geometry.survey import plan_survey
from missions.geometry.triggers import simulate_distance_trigger

DATA = Path(__file__).parent / "data"
FP = WIRIS_60M


def _rect(lat: float, lon: float, dlat: float = 0.004, dlon: float = 0.006) -> list[list[float]]:
    return [[lat, lon], [lat, lon + dlon], [lat + dlat, lon + dlon], [lat + dlat, lon]]


def _check(area, plan) -> None:
    c = measure(area.geometry, plan.photos, FP, plan.path_xy, plan.spacing_m, plan.trigger_distance_m)
    assert c.coverage >= 0.995
    assert c.min_front_overlap >= 0.79 and c.min_side_overlap >= 0.69
    # lat/lon of waypoints agree with their x/y through the area's projection
    for w in plan.waypoints[:: max(1, len(plan.waypoints) // 10)]:
        x, y = area.projection.point_to_xy(w.lat, w.lon)
        assert math.hypot(x - w.x, y - w.y) < 1e-4
        assert -180 <= w.lon < 180


@pytest.mark.parametrize("name,pts", [
    ("prague", _rect(50.10, 14.50)),
    ("southern hemisphere", _rect(-33.95, 151.15)),
    ("high north 75", _rect(75.0, 16.0, 0.003, 0.02)),
    ("high south -75", _rect(-75.003, -60.0, 0.003, 0.02)),
    ("greenwich", _rect(51.477, -0.003)),
    ("180 meridian", [[-16.50, 179.997], [-16.50, -179.996], [-16.495, -179.996], [-16.495, 179.997]]),
])
def test_named_places(name: str, pts) -> None:
    area = load_area(pts)
    plan = plan_survey(area, FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    _check(area, plan)
    if name == "180 meridian":
        lons = np.array([w.lon for w in plan.waypoints])
        assert (lons > 179).any() and (lons < -179).any()
        # unwrapped, the path spans about the area's 0.007° (plus turnarounds), not 360°
        u = unwrap_lons(lons, 180.0)
        assert u.max() - u.min() < 0.02


def test_angle_zero_is_north_south_on_the_globe() -> None:
    area = load_area(_rect(-33.95, 151.15))
    plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
    span = plan.camera_spans[0]
    a, b = plan.waypoints[span.start_index], plan.waypoints[span.stop_index]
    from pyproj import Geod
    az, _, dist = Geod(ellps="WGS84").inv(a.lon, a.lat, b.lon, b.lat)
    # true north within 0.01° (meridian convergence 250 m off the projection centre is ~0.002°)
    assert min(abs(az), abs(abs(az) - 180)) < 0.01 and dist > 100


def test_area_smaller_than_one_footprint_gets_one_photo_and_a_warning() -> None:
    area = load_area([[50.1, 14.5], [50.1, 14.5003], [50.1002, 14.5003]])
    plan = plan_survey(area, FP, 80, 70, turnaround_m=10, speed_mps=6)
    assert [w.code for w in plan.warnings] == ["area_smaller_than_footprint"]
    assert len(plan.photos) >= 1
    c = measure(area.geometry, plan.photos, FP)
    assert c.coverage >= 0.995


def test_holes_and_multipolygons() -> None:
    for name in ("holes.geojson", "multigeometry.kml"):
        area = load_area(DATA / name)
        plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
        c = measure(area.geometry, plan.photos, FP)
        assert c.coverage >= 0.995
    # no camera-on leg over the hole
    area = load_area(DATA / "holes.geojson")
    plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
    hole = area.geometry.interiors[0]
    from shapely.geometry import Polygon
    inner = Polygon(hole).buffer(-2.0)
    assert not any(inner.contains(Point(p.x, p.y)) for p in plan.photos)


def test_hover_mode_turns_photos_into_stops() -> None:
    area = load_area(_rect(50.10, 14.50, 0.002, 0.003))
    plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6, hover=True)
    stops = [w for w in plan.waypoints if w.kind == "photo"]
    assert plan.hover and plan.camera_spans == ()
    assert len(stops) == len(plan.photos) > 0
    # each line is entered from its turnaround stub, along the line, so the vehicle faces along it at its first
    # photo (both autopilots face the waypoint they fly to); every stop carries its line's heading as yaw
    wps = plan.waypoints
    firsts = [k for k, w in enumerate(wps) if w.kind == "photo" and wps[k - 1].kind != "photo"]
    assert len(firsts) == len(plan.legs)
    for k in firsts:
        a, b = wps[k - 1], wps[k]
        assert a.kind == "turnaround" and math.hypot(b.x - a.x, b.y - a.y) == pytest.approx(10.0)
        heading = math.degrees(math.atan2(b.x - a.x, b.y - a.y)) % 360.0
        assert (heading - b.yaw_deg + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=0.05)
    assert all(abs((w.yaw_deg - p.heading_deg + 180.0) % 360.0 - 180.0) < 0.05 for w, p in zip(stops, plan.photos))
    c = measure(area.geometry, plan.photos, FP)
    assert c.coverage >= 0.995


def test_refly_90_adds_a_crossing_pass() -> None:
    area = load_area(_rect(50.10, 14.50, 0.003, 0.004))
    one = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
    two = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6, refly_90=True)
    angles = {round(l.angle_deg) for l in two.legs}
    assert angles == {0, -90} or angles == {0, 90}
    assert len(two.photos) > 1.6 * len(one.photos)


def test_trigger_interval_faster_than_the_camera() -> None:
    area = load_area(_rect(50.10, 14.50))
    trig = FP.along_m * 0.2
    with pytest.raises(PlanError, match="faster than the camera") as e:
        plan_survey(area, FP, 80, 70, speed_mps=12, min_interval_s=1.0)
    assert f"{trig / 1.0:.1f} m/s" in e.value.hint
    plan_survey(area, FP, 80, 70, speed_mps=trig / 1.0 * 0.99, min_interval_s=1.0)   # just slow enough


@pytest.mark.parametrize("kw,match", [
    ({"front_pct": 100}, "front overlap"), ({"side_pct": -5}, "side overlap"),
    ({"speed_mps": 0}, "speed"), ({"turnaround_m": -1}, "turnaround"), ({"angle_deg": "north"}, "angle"),
])
def test_bad_parameters(kw, match) -> None:
    area = load_area(_rect(50.10, 14.50))
    args = dict(front_pct=80, side_pct=70, speed_mps=5.0)
    args.update(kw)
    with pytest.raises(PlanError, match=match):
        plan_survey(area, FP, **args)


def test_report_can_rederive_photos_from_the_waypoints() -> None:
    area = load_area(DATA / "holes.geojson")
    plan = plan_survey(area, FP, 80, 70, angle_deg=20, turnaround_m=10, speed_mps=6)
    # rebuild the path from lat/lon only (as from mission items) and simulate the trigger again
    xy = np.array([area.projection.point_to_xy(w.lat, w.lon) for w in plan.waypoints])
    again = simulate_distance_trigger(xy, plan.camera_spans)
    assert len(again) == len(plan.photos)
    assert max(math.hypot(a.x - b.x, a.y - b.y) for a, b in zip(again, plan.photos)) < 1e-3


@given(st.lists(st.tuples(st.floats(50.0, 50.004), st.floats(14.0, 14.006)), min_size=0, max_size=9))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_any_point_list_gives_a_plan_or_a_plan_error(pts) -> None:
    try:
        area = load_area([list(p) for p in pts])
        plan = plan_survey(area, FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    except PlanError as e:
        assert str(e)
        return
    assert plan.photos


# ------------------------------------------------------------------------------------------- corridor

def test_corridor_straight_and_bent() -> None:
    for line, width in ([[50.11, 14.50], [50.12, 14.52]], 60.0), \
                       ([[50.11, 14.50], [50.12, 14.50], [50.12, 14.52], [50.125, 14.51]], 120.0):
        plan = plan_corridor(line, width, FP, 80, 60, turnaround_m=10, speed_mps=6)
        c = measure(plan.area.geometry, plan.photos, FP, plan.path_xy, plan.spacing_m, plan.trigger_distance_m)
        assert c.coverage >= 0.995
        assert c.min_side_overlap is None or c.min_side_overlap >= 0.59
        n = len(plan.lines_xy)
        assert (n - 1) * plan.spacing_m + FP.across_m >= width


def test_corridor_front_overlap_on_a_straight_line() -> None:
    plan = plan_corridor([[50.11, 14.50], [50.12, 14.52]], 80.0, FP, 80, 60, turnaround_m=10, speed_mps=6)
    c = measure(plan.area.geometry, plan.photos, FP)
    assert c.min_front_overlap >= 0.79


def test_corridor_with_a_straight_middle_point_keeps_full_length_lines() -> None:
    # Three points on one meridian: in the local projection the middle one is ~1 mm off the straight line,
    # which GEOS's offset curve cuts into two halves; each line must still run the whole corridor.
    line = [[50.100, 14.500], [50.103, 14.500], [50.106, 14.500]]
    plan = plan_corridor(line, 60.0, FP, 80, 60, turnaround_m=10, speed_mps=6)
    two = plan_corridor([line[0], line[-1]], 60.0, FP, 80, 60, turnaround_m=10, speed_mps=6)
    lengths = [float(np.hypot(*np.diff(np.asarray(l), axis=0).T).sum()) for l in plan.lines_xy]
    assert len(lengths) == len(two.lines_xy) >= 2
    assert lengths == pytest.approx([float(np.hypot(*np.diff(np.asarray(l), axis=0).T).sum())
                                     for l in two.lines_xy], abs=0.01)
    c = measure(plan.area.geometry, plan.photos, FP)
    assert c.coverage >= 0.995


@pytest.mark.parametrize("line,width,match", [
    ([[50.11, 14.50]], 60, "at least 2"), ([[50.11, 14.50], [50.11, 14.50]], 60, "no length"),
    ([[50.11, 14.50], [50.12, 14.52]], 0, "width"),
    ([[50.11, 14.50], [50.12, 14.52], [50.12, 14.50], [50.11, 14.52]], 30, "crosses itself"),
])
def test_corridor_errors(line, width, match) -> None:
    with pytest.raises(PlanError, match=match):
        plan_corridor(line, width, FP, 80, 60)


def test_exclusion_zone_is_not_photographed_over_at_default_overlap() -> None:
    from shapely.geometry import LineString
    area = load_area(DATA / "square.geojson", exclude=[DATA / "substation.geojson"])
    plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
    zone = load_area(DATA / "substation.geojson")
    lat, lon = zone.projection.to_latlon(*np.asarray(zone.geometry.exterior.coords).T)
    from shapely.geometry import Polygon
    excl = Polygon(np.column_stack(area.projection.to_xy(lat, lon))).buffer(-1.0)
    xy = plan.path_xy
    on = sum(LineString(xy[s.start_index:s.stop_index + 1]).intersection(excl).length for s in plan.camera_spans)
    assert on == 0.0
    assert not any(excl.contains(Point(p.x, p.y)) for p in plan.photos)
    c = measure(area.geometry, plan.photos, FP)
    assert c.coverage >= 0.995


def test_route_starts_near_home_and_refly_starts_near_the_end_of_pass_one() -> None:
    pts = _rect(50.10, 14.50, 0.003, 0.004)
    area = load_area(pts)
    for corner in pts:
        plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6, start_latlon=tuple(corner))
        first = plan.waypoints[0]
        hx, hy = area.projection.point_to_xy(*corner)
        dists = [math.hypot(w.x - hx, w.y - hy) for w in plan.waypoints if w.kind == "entry"]
        assert math.hypot(first.x - hx, first.y - hy) <= min(dists) + 25.0     # nearest entry (+ turnaround)
    plan = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6, refly_90=True)
    k = next(i for i, l in enumerate(plan.legs) if abs(l.angle_deg) > 45)
    end1 = plan.waypoints[plan.camera_spans[k - 1].stop_index]
    start2 = plan.waypoints[plan.camera_spans[k].start_index]
    assert math.hypot(end1.x - start2.x, end1.y - start2.y) < 120.0    # a corner hop, not across the area


def _triangles(n: int, pitch_m: float = 80.0):
    """n separated triangles, 20 to 60 m across, on a grid (metres): an area of many small parts."""
    from shapely.geometry import MultiPolygon, Polygon
    cols = math.ceil(math.sqrt(n))
    polys = []
    for k in range(n):
        cx, cy = (k % cols) * pitch_m, (k // cols) * pitch_m
        r = (20.0 + (k * 7) % 41) / 2.0
        turn = math.radians((k * 37) % 120)
        corners = [turn + j * 2 * math.pi / 3 for j in range(3)]
        polys.append(Polygon([(cx + r * math.sin(a), cy + r * math.cos(a)) for a in corners]))
    return MultiPolygon(polys)


def _scan_order(legs, start_xy=None, max_starts=24):
    """order_legs' greedy as a scan over every cell entry at each step: what its grid search must reproduce."""
    from missions.geometry.route import _cell_sequence, _ends, build_cells
    cells = build_cells(legs)
    opts = [[_cell_sequence(legs, c, fs, ff) for fs in (True, False) for ff in (True, False)] for c in cells]
    entries = np.array([[_ends(legs[s[0][0]], s[0][1])[0] for s in o] for o in opts])
    exits = np.array([[_ends(legs[s[-1][0]], s[-1][1])[1] for s in o] for o in opts])
    n = len(cells)

    def greedy(c0, o0):
        used = np.zeros(n, bool)
        used[c0] = True
        seq, pos = [(c0, o0)], exits[c0, o0]
        total = 0.0 if start_xy is None else math.dist(start_xy, entries[c0, o0])
        for _ in range(n - 1):
            dd = np.hypot(entries[..., 0] - pos[0], entries[..., 1] - pos[1])
            dd[used] = np.inf
            c, o = divmod(int(np.argmin(dd)), 4)
            total += float(dd[c, o])
            used[c] = True
            seq.append((c, o))
            pos = exits[c, o]
        return total, seq

    starts = [(c, o) for c in range(n) for o in range(4)]
    if start_xy is not None:
        starts.sort(key=lambda co: math.dist(start_xy, entries[co]))
    else:
        starts.sort(key=lambda co: (min(legs[i].line for i in cells[co[0]]), co[1]))
    runs = [greedy(c, o) for c, o in starts[:max(1, min(max_starts, 2400 // n))]]
    best = min(runs, key=lambda r: r[0])      # the first of equal totals, as order_legs keeps it
    return [step for c, o in best[1] for step in opts[c][o]]


@pytest.mark.parametrize("seed", range(4))
def test_leg_order_of_many_cells_is_the_nearest_next_scans(seed: int) -> None:
    """Above a few hundred cells order_legs finds each nearest next entry on a grid of buckets; the order must be
    the one scanning every entry gives, ties (a lattice of equal distances) included."""
    from missions.geometry.route import order_legs
    from missions.geometry.swaths import Leg
    rng = np.random.default_rng(seed)
    n = int(rng.integers(250, 700))
    if seed % 2:        # a lattice: many equal distances, single-photo legs beside short ones
        xy = rng.integers(0, 25, size=(n, 2)) * 10.0
        length = rng.choice([0.0, 10.0], size=n)
    else:               # two far clusters: the search must jump between them
        xy = rng.uniform(0, 400, size=(n, 2)) + np.where(rng.random(n) < 0.5, 5000.0, 0.0)[:, None]
        length = rng.uniform(0, 40, size=n)
    legs = [Leg(k, 0, x, y, y + L, x, y, x, y + L, True, True)
            for k, ((x, y), L) in enumerate(zip(xy.tolist(), length))]
    start = None if seed < 2 else (200.0, -50.0)
    order = order_legs(legs, start)
    assert sorted(i for i, _ in order) == list(range(n))
    assert order == _scan_order(legs, start)


def test_many_part_angle_search_flies_along_strips() -> None:
    """Past EXHAUSTIVE_ANGLE_PARTS the angle is ranked on the per-part estimate; parallel strips still get lines
    along them (two lines along each 60 m wide strip, not a line every 15 m across its 300 m)."""
    from shapely import affinity
    from shapely.geometry import MultiPolygon, box

    from missions.geometry.survey import EXHAUSTIVE_ANGLE_PARTS
    strips = [affinity.rotate(box(0, k * 100.0, 300, k * 100.0 + 60), 90.0 - 30.0, origin=(0, 0))
              for k in range(EXHAUSTIVE_ANGLE_PARTS + 10)]
    plan = plan_survey(area_from_xy(MultiPolygon(strips)), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    assert abs(normalise_angle(plan.angle_deg - 30.0)) <= 1.0
    assert len(plan.legs) == 2 * len(strips)


def test_many_part_angle_search_flies_along_a_row_of_one_photo_parts() -> None:
    """Parts that each fit in one photo cost the same at every angle on their own; what differs is the hop from
    one to the next: lines along the row fly each part's turnaround stubs towards the next part."""
    from shapely.geometry import MultiPolygon, box

    from missions.geometry.survey import EXHAUSTIVE_ANGLE_PARTS
    row = MultiPolygon([box(k * 60.0, 0, k * 60.0 + 10, 10) for k in range(EXHAUSTIVE_ANGLE_PARTS + 20)])
    area = area_from_xy(row)
    plan = plan_survey(area, FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    across = plan_survey(area, FP, 80, 70, angle_deg=0, turnaround_m=10, speed_mps=6)
    assert abs(normalise_angle(plan.angle_deg - 90.0)) <= 10.0
    assert plan.stats.est_time_s < 0.9 * across.stats.est_time_s


def test_many_part_angle_search_plans_the_whole_area_a_few_times(monkeypatch) -> None:
    """1,500 small polygons: the angle search ranks angles part by part and plans the whole area at most at its
    few best angles (planning it at each of ~60 angles took minutes), and the plan covers every part."""
    import shapely

    from missions.geometry import survey
    from missions.measure.coverage import _arrays, footprint_polygons
    calls = []
    real = survey.generate_swaths

    def counted(*args, **kwargs):
        calls.append(args[1])
        return real(*args, **kwargs)

    monkeypatch.setattr(survey, "generate_swaths", counted)
    geom = _triangles(1500)
    plan = plan_survey(area_from_xy(geom), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    assert len(calls) <= 5          # the finalists and the plan itself
    xy, h, _span = _arrays(plan.photos)
    covered = shapely.union_all(footprint_polygons(xy, h, FP))
    parts = np.array(list(geom.geoms))
    assert (shapely.area(shapely.intersection(parts, covered)) / shapely.area(parts)).min() >= 0.995
    flown = list(plan.legs)
    assert len(set(flown)) == len(flown) == len(real(geom, plan.angle_deg, FP.across_m, plan.spacing_m,
                                                      plan.trigger_distance_m, FP.along_m).legs)
    assert leg_crossings(plan.legs, geom) == []


def test_area_of_more_parts_than_the_limit_is_refused_before_planning(monkeypatch) -> None:
    from missions.geometry import survey
    monkeypatch.setattr(survey, "MAX_SURVEY_PARTS", 40)
    monkeypatch.setattr(survey, "generate_swaths", lambda *a, **k: pytest.fail("planned past the limit"))
    with pytest.raises(PlanError, match="41 separate polygons, more than the 40 one survey can plan") as ei:
        plan_survey(area_from_xy(_triangles(41)), FP, 80, 70, angle_deg="auto", turnaround_m=10, speed_mps=6)
    assert "merge or simplify the polygons" in ei.value.hint
