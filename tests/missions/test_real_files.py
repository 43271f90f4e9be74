"""Real public mission files (tests/data, sources in its README) read as their own tools read them:
QGroundControl's loader for .plan (3.x sections skipped with a note), pymavlink's MAVWPLoader for WPL 110
(rows numbered by position), fence and rally WPL files recognised; what is ambiguous is refused at its line."""

from __future__ import annotations

from pathlib import Path

import pytest

from missions.emit.items import MISSION_TYPE_FENCE, MISSION_TYPE_MISSION
from missions.errors import PlanError
from missions.formats.planfile import load_plan_file, read_plan_file
from missions.formats.wpl import load_wpl_file, read_wpl_file

DATA = Path(__file__).resolve().parents[1] / "data"


def mavwploader_rows(path: Path) -> list[tuple[int, int, float, float]]:
    """(seq, command, lat, lon) of each row as pymavlink's MAVWPLoader numbers them."""
    from pymavlink import mavwp

    loader = mavwp.MAVWPLoader()
    n = loader.load(str(path))
    return [(w.seq, w.command, w.x, w.y) for w in (loader.wp(i) for i in range(n))]


def test_autotest_inf_loop_with_a_gap_is_renumbered_like_mavwploader():
    path = DATA / "ardupilot_inf_loop.txt"      # rows 0, 1, 2, 4
    read = load_wpl_file(path)
    assert read.mission_type == MISSION_TYPE_MISSION
    assert read.home == pytest.approx((-35.363262, 149.165237, 584.089966))
    assert [it.command for it in read.items] == [19, 177, 16]
    assert [str(n) for n in read.notes] == [
        f"{path}:5: row index 4 read as 3 (the rows before it end at 2), as pymavlink's MAVWPLoader renumbers"]
    # MAVWPLoader: the same rows at seq 0..3, home first
    loader = mavwploader_rows(path)
    assert [seq for seq, *_ in loader] == [0, 1, 2, 3]
    assert [cmd for _, cmd, *_ in loader] == [16] + [it.command for it in read.items]
    assert read.items[2].x == round(loader[3][2] * 1e7) and read.items[2].y == round(loader[3][3] * 1e7)
    assert read.items[1].param1 == 1.0          # the DO_JUMP before the gap keeps its target


def test_a_jump_past_a_gap_follows_the_row_it_names():
    text = (DATA / "ardupilot_inf_loop.txt").read_text() + \
        "5\t0\t0\t177\t4.000000\t2.000000\t0\t0\t0\t0\t0\t1\n"         # jump to the row numbered 4
    read = read_wpl_file(text, "j.txt")
    assert read.items[-1].param1 == 3.0          # row 4 is read as 3
    assert [n.where for n in read.notes] == ["j.txt:5", "j.txt:6", "j.txt:6"]
    assert "DO_JUMP to row 4 follows it to its new number 3" in read.notes[-1].message
    with pytest.raises(PlanError) as err:        # a jump to a row that is not there: nothing to follow
        read_wpl_file(text.replace("177\t4.000000", "177\t3.000000"), "j.txt")
    assert err.value.where == "j.txt:6" and "does not have" in err.value.message and err.value.hint


def test_dronekit_save_mission_without_home_reads_from_item_1():
    path = DATA / "dronekit_save_mission_no_home.txt"     # rows 1..6, no home row
    read = load_wpl_file(path)
    assert read.home is None and len(read.items) == 6
    assert [it.command for it in read.items] == [22, 16, 16, 16, 16, 16]
    assert len(read.notes) == 1 and read.notes[0].where == f"{path}:2" and "no home row" in read.notes[0].message
    assert [cmd for _, cmd, *_ in mavwploader_rows(path)] == [22, 16, 16, 16, 16, 16]


@pytest.mark.parametrize("name,count,home", [
    ("dronekit_mpmission.txt", 6, True),
    ("ardupilot_copter_mission_CHIAI.txt", 4, True),
    ("mavsdk_mission_planner_sample.txt", 4, False),     # row 0 is a takeoff in frame 5: no home row
])
def test_ordinary_wpl_files_read_without_notes(name, count, home):
    read = load_wpl_file(DATA / name)
    assert len(read.items) == count and (read.home is not None) == home and read.notes == ()
    assert len(mavwploader_rows(DATA / name)) == count + home


def test_a_fence_saved_as_wpl_is_a_fence():
    read = load_wpl_file(DATA / "ardupilot_rover_bendyruler_fence.txt")
    assert read.mission_type == MISSION_TYPE_FENCE and read.home is None
    assert [it.command for it in read.items] == [5001] * 8 + [5004] * 2
    assert all(it.mission_type == MISSION_TYPE_FENCE for it in read.items)


@pytest.mark.parametrize("edit,where,text", [
    (lambda t: t.replace("\n3\t0\t0\t5001", "\n2\t0\t0\t5001"), ":5", "row index 2 appears twice (first at"),
    (lambda t: t.replace("\n3\t0\t0\t5001", "\n1\t0\t0\t5001"), ":5", "row index 1 appears twice"),
    (lambda t: t.replace("\n9\t0\t0\t5004", "\n9\t0\t3\t16"), ":11", "MAV_CMD_NAV_WAYPOINT in a file of fence rows"),
    (lambda t: t.replace("5001\t8.000000", "5001\t9.000000", 1), ":2", "a fence polygon of 9 vertices"),
])
def test_ambiguous_or_mixed_fence_rows_are_refused_at_their_line(edit, where, text):
    src = (DATA / "ardupilot_rover_bendyruler_fence.txt").read_text()
    with pytest.raises(PlanError) as err:
        read_wpl_file(edit(src), "f.txt")
    assert err.value.where == "f.txt" + where and text in err.value.message and err.value.hint


def test_decreasing_index_is_refused():
    src = (DATA / "dronekit_mpmission.txt").read_text().replace("\n3\t", "\n1\t", 1)
    with pytest.raises(PlanError) as err:
        read_wpl_file(src.replace("\n1\t", "\n7\t", 1), "m.txt")     # 0, 7, 2, 1, ...
    assert err.value.where == "m.txt:4" and "comes after 7" in err.value.message


def test_crlf_line_endings_read_alike():
    src = (DATA / "dronekit_mpmission.txt").read_text()
    assert read_wpl_file(src.replace("\n", "\r\n").encode(), "m").items == read_wpl_file(src, "m").items


def test_qgc3_save_skips_its_version_1_fence_and_rally_as_qgc_does():
    path = DATA / "qgc3_devguide_mission.plan"
    read = load_plan_file(path)
    assert [it.command for it in read.items] == [22, 16]
    # QGC 3.x "coordinate" items: params 5-7 from the coordinate (MissionItem::_convertJsonV2ToV3)
    assert (read.items[0].x, read.items[0].y, read.items[0].z) == (473859139, 85520675, 15.0)
    assert read.fence == [] and read.rally == [] and read.firmware == 12
    assert [n.where for n in read.notes] == [f"{path}: geoFence", f"{path}: rallyPoints"]
    assert all("skipped as QGroundControl skips it" in n.message for n in read.notes)


def test_qgc_fence_plan_with_a_version_1_rally_section():
    path = DATA / "qgc_ce_geofence_rd_2.plan"
    read = load_plan_file(path)
    assert read.items == [] and len(read.fence) == 8 and read.rally == []
    assert [n.where for n in read.notes] == [f"{path}: rallyPoints"]


@pytest.mark.parametrize("edit,where", [
    (lambda t: t.replace('"version": 1\n    },\n    "groundStation"', '"version": 3\n    },\n    "groundStation"'),
     "geoFence.version"),
    (lambda t: t.replace('"points": [\n        ],\n        "version": 1', '"points": [\n        ]'), "rallyPoints"),
    (lambda t: t.replace('8.5520674900000007,\n                    15\n', '8.5520674900000007\n', 1),
     "mission.items[0].coordinate"),
    (lambda t: t.replace('"coordinate": [', '"extra": [', 1), "mission.items[0].params"),
])
def test_what_qgc_refuses_in_a_3x_save_is_refused(edit, where):
    src = (DATA / "qgc3_devguide_mission.plan").read_text()
    changed = edit(src)
    assert changed != src
    with pytest.raises(PlanError) as err:
        read_plan_file(changed, "q.plan")
    assert err.value.where == f"q.plan: {where}" and err.value.hint
