"""The report's ArduPilot distance-trigger model against what ArduPilot 4.7 SITL flew. AP_Camera checks the
distance from the last photo at 50 Hz and fires at the first check at or past CAMn_TRIGG_DIST, so it flies the
distance rounded up to whole checks of travel; and it measures that distance in its own metres (Location's
sphere of 6378100 m), which at 50° N are 0.2 % longer than true metres east-west and 0.08 % shorter north-south.
field-multispectral, lines heading 278° at 50.16° N, DO_SET_CAM_TRIGG_DIST 10.043 m at 5 m/s, flown in SITL with
the WIRIS emulator (DataFlash CAM messages): 577 photos, 10.117 m median between photos (101 checks of 0.1 m
are 10.1 m of ArduPilot's, 10.1195 m true), and 10 of its 17 lines one photo short of the 36 that 10.1 m
spacing fits exactly on them (353.5 m lines)."""

from __future__ import annotations

import collections
import dataclasses
import math
from pathlib import Path

import pytest

from missions.compile import compile_plan
from missions.emit.items import mavlink
from missions.emit.trigger_distance import AP_CAMERA_UPDATE_HZ, ardupilot_commanded_distance, ardupilot_metre
from missions.measure.flight import ardupilot_trigger_spacing_m, simulate
from missions.measure.report import report

ROOT = Path(__file__).resolve().parents[2]

# photos per line in ArduPilot SITL (4.7, speed-up 40), field-multispectral with the 10.043 m trigger distance
SITL_PER_LINE = (30, 35, 35, 35, 35, 35, 36, 36, 36, 36, 35, 35, 35, 34, 32, 30, 27)


def test_ardupilots_metre_is_longer_east_west_and_shorter_north_south_at_50_degrees():
    m = ardupilot_metre(50.1557)
    assert m.east == pytest.approx(1.00198, abs=1e-5) and m.north == pytest.approx(0.99922, abs=1e-5)
    assert 10.1 * m.along(278.0) == pytest.approx(10.117, abs=0.005)       # the median SITL spacing
    assert ardupilot_metre(0.0).east == pytest.approx(6378137 / 6378100)   # the equator: WGS84's a over AP's R


def _with_commanded_distance(compiled, distance_m: float):
    items = tuple(dataclasses.replace(it, param1=distance_m)
                  if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST and it.param1 > 0 else it
                  for it in compiled.items)
    return dataclasses.replace(compiled, items=items, parts=(items,))


def test_field_multispectral_is_predicted_as_ardupilot_sitl_flew_it():
    compiled = _with_commanded_distance(compile_plan(ROOT / "examples" / "field-multispectral.yaml"), 10.043076923)
    photos = [p for p in simulate(compiled).photos if "thermal" in p.payloads]
    per_line = collections.Counter(p.span for p in photos)
    predicted = tuple(per_line[s] for s in sorted(per_line))
    # the first and the last-but-one line are 293.25 m long: the 30th photo falls 0.02 m past the end as SITL
    # flew it, 0.2 m past as modelled; every other line as flown
    assert predicted[1:15] + predicted[16:] == SITL_PER_LINE[1:15] + SITL_PER_LINE[16:]
    assert abs(len(photos) - sum(SITL_PER_LINE)) <= 2


@pytest.mark.parametrize("speed", [2.0, 4.5, 5.0, 6.3, 12.0])
@pytest.mark.parametrize("lat", [-35.26, 0.0, 50.16, 69.0])
@pytest.mark.parametrize("spacing", [3.1, 5.356307692, 10.043076923, 10.0, 25.0])
def test_the_commanded_distance_flies_half_a_check_short_of_the_spacing_and_is_never_a_tie(speed, lat, spacing):
    step = speed / AP_CAMERA_UPDATE_HZ
    cmd = ardupilot_commanded_distance(spacing, speed, lat)
    flown_true = ardupilot_trigger_spacing_m(cmd, speed) * max(ardupilot_metre(lat))
    assert flown_true <= spacing - step / 2 * (1 - 1e-9)
    assert flown_true > spacing - 2 * step * max(ardupilot_metre(lat))        # and no shorter than it must be
    assert (cmd / step) % 1.0 == pytest.approx(0.5)                           # half way between two checks


def _straight_gaps(photos) -> list[float]:
    return [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(photos, photos[1:])
            if a.span == b.span and abs(a.heading_deg - b.heading_deg) < 1e-6]


@pytest.mark.parametrize("example", ["field-multispectral", "solar-park", "pv-inspection", "powerline-corridor"])
def test_the_examples_hold_the_requested_front_overlap_on_ardupilot(example):
    """Before: solar-park 79.8 % for 80 % asked, field-multispectral 74.9 % for 75 % (the 50 Hz rounding)."""
    compiled = compile_plan(ROOT / "examples" / f"{example}.yaml", firmware="ardupilot")
    rep = report(compiled)
    for area in compiled.areas:
        if area.trigger != "distance":
            continue
        lead = area.payloads[0]
        along = compiled.payload(lead).footprint_m(area.altitude_m)[1]
        photos = [p for p in simulate(compiled).photos if lead in p.payloads]
        # photo to photo on a straight line, every pair of the example
        assert max(_straight_gaps(photos)) <= along * (1 - area.front_overlap)
        if area.kind == "survey":      # a corridor's bends turn the footprints, and lose overlap, by geometry
            assert rep.overlap[lead].front_min >= area.front_overlap
