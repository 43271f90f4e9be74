"""A plane's turns (missions.geometry.turns, missions.plan_turns): its radius, skip-line order for lines closer
than two radii, the flight model's turn paths, and the warnings."""

from __future__ import annotations

import math
import random

import pytest

from missions.compile import compile_plan
from missions.geometry.route import skip_line_order
from missions.geometry.turns import dubins_length_m, turn_radius_m
from missions.measure.flight import simulate, turn_lengths
from missions.plan import parse_plan

R = 40.0


def test_dubins_lengths_of_known_paths():
    assert dubins_length_m((0, 0), 0.0, (0, 100), 0.0, R) == pytest.approx(100.0)           # straight on
    assert dubins_length_m((0, 0), 0.0, (2 * R, 0), 180.0, R) == pytest.approx(math.pi * R)  # a half circle
    assert dubins_length_m((0, 0), 0.0, (2 * R + 30, 0), 180.0, R) == pytest.approx(math.pi * R + 30)
    # onto a line d beside, closer than 2R: the loop (omega) turn, R·(π + 4·acos((2R + d) / 4R))
    d = 20.0
    omega = R * (math.pi + 4 * math.acos((2 * R + d) / (4 * R)))
    assert dubins_length_m((0, 0), 0.0, (d, 0), 180.0, R) == pytest.approx(omega)
    assert turn_radius_m(16.0, 30.0) == pytest.approx(16.0 ** 2 / (9.80665 * math.tan(math.radians(30))))


def test_a_dubins_path_is_never_shorter_than_the_straight_line():
    rnd = random.Random(7)
    for _ in range(2000):
        p1 = (rnd.uniform(-300, 300), rnd.uniform(-300, 300))
        h0, h1 = rnd.uniform(0, 360), rnd.uniform(0, 360)
        assert dubins_length_m((0, 0), h0, p1, h1, R) >= math.hypot(*p1) - 1e-6


@pytest.mark.parametrize("n,gap", [(12, 3), (9, 2), (5, 5), (30, 4)])
def test_skip_line_order_flies_every_line_once_and_far_enough_apart_but_at_the_end(n, gap):
    order = skip_line_order(n, gap)
    assert sorted(order) == list(range(n))
    close = [k for k in range(1, n) if abs(order[k] - order[k - 1]) < gap]
    # only among the lines left over after the last full block of 2·(gap + 1): the last few, with a loop turn
    assert all(k >= n - 2 * (gap + 1) for k in close)


PLANE = """\
version: 1
vehicle: {{firmware: ardupilot, frame: plane, speed_mps: 14{extra}}}
home: {{lat: 50.0, lon: 14.5, alt_amsl_m: 300}}
payloads:
  thermal: {{camera: wiris-pro, imager: thermal, lens_mm: 13}}
mission:
  - takeoff: {{alt_m: 100}}
  - survey:
      area: [[50.0010, 14.5010], [50.0010, 14.5066], [50.0037, 14.5066], [50.0037, 14.5010]]
      payloads: [thermal]
      altitude_m: 100
      overlap: {{front: 70, side: 70}}
      angle_deg: 0
      blur_px: 1.5{survey}
  - rtl: {{}}
"""


def _plane(tmp_path, extra="", survey=""):
    text = PLANE.format(extra=extra, survey=survey)
    return compile_plan(parse_plan(text, str(tmp_path / "plane.yaml"), tmp_path))


def test_a_plane_flies_lines_closer_than_two_radii_skipping_lines(tmp_path):
    c = _plane(tmp_path)
    r = c.turn_radius_m
    assert r == pytest.approx(turn_radius_m(14.0, 30.0))
    route = c.intent[0]
    assert route.spacing_m < 2 * r
    us = [leg.u for leg in route.legs]          # across-track position of each line, in flying order
    assert len(us) >= 8
    gaps = [abs(b - a) for a, b in zip(us, us[1:])]
    # consecutive lines at least two radii apart, but for the last few (loop turns)
    assert sum(g < 2 * r - 1e-6 for g in gaps) <= math.ceil(2 * r / route.spacing_m)
    assert any(w.code == "lines_closer_than_turn" for w in c.warnings)
    assert sorted(us) == sorted(set(us))        # every line once


def test_a_plane_plan_defaults_its_turnaround_to_a_radius_and_warns_about_a_shorter_one(tmp_path):
    slow_bank = _plane(tmp_path, extra=", max_bank_deg: 15")       # a radius of ~75 m
    r = slow_bank.turn_radius_m
    assert r > 30
    # the run-in before each line's entry is one radius long
    wps = slow_bank.intent[0].route.points
    runs = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(wps, wps[1:])
            if a.kind == "turnaround" and b.kind == "entry"]
    assert runs and min(runs) >= math.ceil(r) - 0.5
    short = _plane(tmp_path, survey="\n      turnaround_m: 10")
    (w,) = [w for w in short.warnings if w.code == "turnaround_shorter_than_turn"]
    assert "turnaround_m 10" in w.message
    assert not [w for w in slow_bank.warnings if w.code == "turnaround_shorter_than_turn"]


def test_the_flight_model_flies_a_planes_turns_and_a_copters_corners(tmp_path):
    c = _plane(tmp_path)
    sim = simulate(c)
    straight = sim.path_length_m
    turned = float(turn_lengths(sim.vertices, c.turn_radius_m).sum())
    assert turned > straight                              # loops and arcs: longer than the polyline
    tight = _plane(tmp_path, extra=", turn_radius_m: 5")
    assert simulate(tight).flight_time_s < sim.flight_time_s
    assert float(turn_lengths(sim.vertices, None).sum()) == pytest.approx(straight)


def _runs_in(c):
    wps = c.intent[0].route.points
    return [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(wps, wps[1:])
            if a.kind == "turnaround" and b.kind == "entry"]


def test_an_arduplane_runs_in_a_radius_and_an_l1_period_and_a_px4_plane_a_radius(tmp_path):
    from missions.plan_turns import ARDUPLANE_L1_PERIOD_S
    ap = _plane(tmp_path)
    r = ap.turn_radius_m
    # ArduPlane converges on a line at its L1 controller's pace: one radius of run-in left it 11-51 m off (SITL)
    assert min(_runs_in(ap)) >= r + ARDUPLANE_L1_PERIOD_S * 14.0 - 0.5
    px4 = compile_plan(parse_plan(PLANE.format(extra="", survey="").replace("firmware: ardupilot", "firmware: px4"),
                                  str(tmp_path / "px4.yaml"), tmp_path))
    assert math.ceil(r) - 0.5 <= min(_runs_in(px4)) and max(_runs_in(px4)) < r + ARDUPLANE_L1_PERIOD_S * 14.0 - 0.5


def _exits_past_last_photo(c):
    """Per line: how far its camera-off waypoint lies past the report's last photo of the line."""
    sim = simulate(c)
    pts = c.intent[0].route.points
    exits = [(p.x, p.y) for p in pts if p.kind == "exit"]
    by_span = {}
    for ph in sim.photos:
        by_span.setdefault(ph.span, []).append(ph)
    out = []
    for photos in by_span.values():
        last = photos[-1]
        ex = min(exits, key=lambda e: math.hypot(e[0] - last.x, e[1] - last.y))
        h = math.radians(last.heading_deg)
        out.append((ex[0] - last.x) * math.sin(h) + (ex[1] - last.y) * math.cos(h))
    return out


def _exits_past_last_planned_photo(c):
    """Per line: how far its camera-off waypoint lies past the line's last planned photo (the compiler's own)."""
    exits = [(p.x, p.y) for p in c.intent[0].route.points if p.kind == "exit"]
    last_of_span = {}
    for ph in c.intent[0].photos:
        last_of_span[ph.span] = ph
    return [min(math.hypot(e[0] - ph.x, e[1] - ph.y) for e in exits) for ph in last_of_span.values()]


def test_an_arduplane_line_ends_a_navigate_tick_past_its_last_photo_and_a_copters_as_before(tmp_path):
    from missions.measure.flight import ARDUPLANE_NAV_HZ
    from missions.geometry.survey import DEFAULT_EXIT_MARGIN_M
    ap = _plane(tmp_path)
    # its 10 Hz navigate task switches the camera on up to a tick after the entry (the report: half a tick late)
    # and off up to a tick after the exit: the last photo must not be lost to a late start (SITL with 2 m past
    # it: 4 lines of 7 lost it)
    margins = _exits_past_last_photo(ap)
    assert len(margins) >= 8 and min(margins) >= DEFAULT_EXIT_MARGIN_M + 0.5 * 14.0 / ARDUPLANE_NAV_HZ - 1e-3
    copter = compile_plan(parse_plan(PLANE.format(extra="", survey="").replace("frame: plane", "frame: copter")
                                     .replace("speed_mps: 14", "speed_mps: 5"),
                                     str(tmp_path / "copter.yaml"), tmp_path))
    # a copter's camera-off waypoint stays the default margin past the line's planned last photo (its flown
    # photos come a little earlier: on ArduPilot the commanded distance is half a 50 Hz check short)
    assert max(_exits_past_last_planned_photo(copter)) <= DEFAULT_EXIT_MARGIN_M + 0.01
    assert max(_exits_past_last_photo(copter)) >= DEFAULT_EXIT_MARGIN_M


def test_arduplane_photos_come_half_a_trigger_check_further_apart_than_asked(tmp_path):
    from missions.emit.trigger_distance import ardupilot_metre
    from missions.measure.flight import AP_CAMERA_UPDATE_HZ, arduplane_trigger_spacing_m
    # measured in arduplane SITL (CAMERA_FEEDBACK): 26.96 m mean for 26.78 m at 20 m/s; whole 50 Hz steps give 26.80
    assert arduplane_trigger_spacing_m(26.78, 20.0) == pytest.approx(26.98)
    c = _plane(tmp_path)
    sim = simulate(c)
    trig = c.intent[0].trigger_distance_m
    line = [p for p in sim.photos if p.span == sim.photos[0].span]
    steps = [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(line, line[1:])]
    # in ArduPilot's metres (its Location arithmetic's sphere), which the report brings back to true metres
    true_per_ap = ardupilot_metre(c.home[0]).along(line[0].heading_deg)
    assert steps and all(s == pytest.approx((trig + 14.0 / AP_CAMERA_UPDATE_HZ / 2) * true_per_ap, abs=2e-3)
                         for s in steps)


def test_a_fast_planes_wiris_hears_its_position_often_enough_to_geotag_within_2_m(tmp_path):
    from missions.emit.params import GEOTAG_LAG_M
    # the WIRIS tags a photo with the last GLOBAL_POSITION_INT it heard: at 5 Hz and 20 m/s up to 4 m behind
    # (arduplane SITL: captured photos 1-3 m behind the report's, alternating with the 5 Hz stream)
    fast = compile_plan(parse_plan(PLANE.format(extra="", survey="").replace("speed_mps: 14", "speed_mps: 20")
                                   .replace("blur_px: 1.5", "blur_px: 2"),
                                   str(tmp_path / "fast.yaml"), tmp_path))
    rates = {n: v for n, v, _ in fast.params if n.endswith("_POSITION")}
    assert rates and all(20.0 / v <= GEOTAG_LAG_M for v in rates.values()), rates
    why = [w for n, v, w in fast.params if n == "MAV3_POSITION"][0]
    assert "10 Hz" in why and "2 m" in why
    slow = compile_plan(parse_plan(PLANE.format(extra="", survey="").replace("frame: plane", "frame: copter")
                                   .replace("speed_mps: 14", "speed_mps: 5"), str(tmp_path / "slow.yaml"), tmp_path))
    assert {v for n, v, _ in slow.params if n.endswith("_POSITION")} == {5}
