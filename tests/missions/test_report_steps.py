"""Per-step figures of the report belong to the step: two neighbouring surveys do not blur each other's overlaps,
photo counts or metres outside the area, while coverage still counts whatever photo covers the ground."""

from __future__ import annotations

from dataclasses import replace

import pytest
import yaml
from shapely.geometry import LineString

from missions.compile import compile_plan
from missions.emit.items import FRAME_MISSION, mavlink
from missions.plan import parse_plan
from missions.measure.report import area_geometry, report

# Two fields side by side, touching along 14.502 E; the east one is flown higher and with lower overlaps, so its
# photos reaching over the shared edge (and its path) differ from the west one's.
WEST = [[50.1, 14.5], [50.1, 14.502], [50.101, 14.502], [50.101, 14.5]]
EAST = [[50.1, 14.502], [50.1, 14.504], [50.101, 14.504], [50.101, 14.502]]


def _survey(area, altitude, front, side, **extra):
    return {"survey": {"area": area, "payloads": ["thermal"], "altitude_m": altitude,
                       "overlap": {"front": front, "side": side}, "angle_deg": 0, **extra}}


WEST_STEP = _survey(WEST, 40, 80, 70)
EAST_STEP = _survey(EAST, 50, 60, 40)


def _compile(tmp_path, steps, name="plan"):
    doc = {"version": 1, "name": name, "vehicle": {"firmware": "ardupilot", "frame": "copter", "speed_mps": 4.5},
           "home": {"lat": 50.0995, "lon": 14.5, "alt_amsl_m": 250},
           "payloads": {"thermal": {"camera": "wiris-pro", "imager": "thermal", "lens_mm": 13, "component_id": 100}},
           "mission": [{"takeoff": {"alt_m": 40}}, *steps, {"rtl": {}}]}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return compile_plan(parse_plan(path.read_text(), str(path), tmp_path))


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("steps")
    c = _compile(tmp, [WEST_STEP, EAST_STEP], "both")
    return c, report(c)


def test_each_step_emits_its_own_item_range(both):
    c, _ = both
    (a0, e0), (a1, e1) = (a.items for a in c.areas)
    assert 0 < a0 < e0 <= a1 < e1 <= len(c.items)
    # every trigger item of the mission lies in one of the two ranges
    trig = [i for i, it in enumerate(c.items) if it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
    assert trig and all(a0 <= i < e0 or a1 <= i < e1 for i in trig)


@pytest.mark.parametrize("k,alone", [(0, WEST_STEP), (1, EAST_STEP)])
def test_a_step_measures_its_own_overlaps_and_photos(tmp_path, both, k, alone):
    # flown alone, a field's minimum overlaps and photo count are its own; next to the other field they must stay
    # so (they were the minimum over both fields' photos near it: the west field read 60 % front and 40 % side,
    # the east field's request, and counted the east field's photos along the shared edge)
    _, rep = both
    solo = report(_compile(tmp_path, [alone], "solo")).areas[0]
    row = rep.areas[k]
    assert row.overlap["thermal"].front_min == pytest.approx(solo.overlap["thermal"].front_min, abs=2e-4)
    assert row.overlap["thermal"].side_min == pytest.approx(solo.overlap["thermal"].side_min, abs=2e-4)
    assert row.photos["thermal"] == solo.photos["thermal"]
    assert row.coverage["thermal"] >= 0.995


def test_the_mission_overlap_is_the_lowest_of_the_steps(both):
    _, rep = both
    rows = rep.areas
    assert rows[0].overlap["thermal"].front_min != rows[1].overlap["thermal"].front_min
    for key in ("front_min", "side_min"):
        assert getattr(rep.overlap["thermal"], key) == min(getattr(r.overlap["thermal"], key) for r in rows)


def _expected_outside_m(c, a) -> float:
    """Metres outside the area of the step's own flight, straight from its items: from the position before its
    first item through the positions of its NAV items (none of them hold a "here" position)."""
    first, end = a.items
    nav = [it for it in c.items if it.frame != FRAME_MISSION and (it.x or it.y)]
    before = [it for it in c.items[:first] if it in nav]
    pts = [before[-1]] + [it for it in c.items[first:end] if it.frame != FRAME_MISSION and (it.x or it.y)]
    x, y = a.area.projection.to_xy([p.lat for p in pts], [p.lon for p in pts])
    return LineString(list(zip(x, y))).difference(a.area.geometry).length


def test_outside_metres_are_the_steps_own_flight(both):
    # they were the whole mission's: the other field's lines, the take-off leg and the return, for either field
    c, rep = both
    for a, row in zip(c.areas, rep.areas):
        assert row.path.outside_m == pytest.approx(_expected_outside_m(c, a), abs=0.2)
    assert rep.areas[0].path.outside_m + rep.areas[1].path.outside_m < rep.path_length_m


def test_coverage_counts_a_neighbours_photos_but_the_photo_count_does_not(tmp_path):
    # the east field now overlaps the west one by half; with its own camera items silenced (indices kept), it takes
    # no photo: none is its own, no overlap is measured, yet the west field's photos still cover the shared half
    east = [[50.1, 14.501], [50.1, 14.503], [50.101, 14.503], [50.101, 14.501]]
    c = _compile(tmp_path, [WEST_STEP, _survey(east, 50, 60, 40)])
    first, end = c.areas[1].items
    quiet = tuple(it.with_(param1=0.0, param3=0.0) if first <= i < end
                  and it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST else it for i, it in enumerate(c.items))
    rep = report(replace(c, items=quiet, parts=(quiet,)))
    row = rep.areas[1]
    assert row.photos["thermal"] == 0
    assert row.overlap["thermal"].to_json() == {"front_min": None, "side_min": None}
    west, east_area = c.areas[0].area, c.areas[1].area
    shared = area_geometry(west, east_area.projection).intersection(east_area.geometry).area / east_area.geometry.area
    assert 0.45 < shared < 0.55
    assert row.coverage["thermal"] >= shared - 1e-3
    assert rep.areas[0].coverage["thermal"] >= 0.995


def test_a_neighbour_keeps_out_of_an_exclusion_another_step_declares(tmp_path):
    # An exclusion is ground not to fly over or photograph for the whole flight: the west field's route keeps out
    # of the substation across its east edge, and so does the east field drawn over it without declaring it (before
    # zones held for the whole flight, it flew and shot across it: 10+ m with the camera on, photos centred inside)
    sub = [[50.1004, 14.5017], [50.1004, 14.5023], [50.1006, 14.5023], [50.1006, 14.5017]]
    over = [[50.1, 14.5012], [50.1, 14.5026], [50.101, 14.5026], [50.101, 14.5012]]
    west = _survey(WEST, 40, 80, 70, exclude=[sub])
    alone = report(_compile(tmp_path, [west], "alone"))
    assert alone.areas[0].path.over_gaps_m < 0.1
    rep = report(_compile(tmp_path, [west, _survey(over, 50, 60, 40)], "over"))
    for row in rep.areas:
        assert [(z.kind, z.flown_inside_m, z.photographed_m2) for z in row.zones] == [("exclude", 0.0, 0.0)]
    assert rep.areas[0].path.over_gaps_m < 0.1 and rep.areas[0].photos_in_zones["thermal"] == 0
    assert not any(w.code in ("path_over_exclusion", "zone_photographed") for w in rep.warnings)
