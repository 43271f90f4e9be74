"""QGC WPL 110: the Mission Planner sample from the corpus, the home row, 7-decimal coordinates,
exact round trips, bad rows with file:line, and pymavlink's own loader (MAVWPLoader) reading
what we write."""

from __future__ import annotations

import math
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from missions.errors import PlanError
from missions.formats.itemcheck import item_problem
from missions.emit.items import MissionItem
from missions.formats.wpl import load_wpl, read_wpl, write_wpl
import corpus

CORPUS = corpus.PLANS


def items():
    return [MissionItem(command=22, param1=15, param4=math.nan, x=473977507, y=85456075, z=50),
            MissionItem(command=16, x=-335000001, y=-700000009, z=42.125, frame=0),
            MissionItem(command=206, frame=2, param1=25.5, param3=1),
            MissionItem(command=20, frame=2, autocontinue=0)]


def same(a, b):
    return len(a) == len(b) and all(x.same_on_wire(y) for x, y in zip(a, b))


def test_mission_planner_sample():
    got, home = load_wpl(CORPUS / "mission_planner_sample.txt")
    # Its row 0 is a takeoff in frame 5, not a home row: every row is a mission item.
    assert home is None and [it.command for it in got] == [22, 16, 16, 20]
    assert (got[0].frame, got[0].x, got[0].y, got[0].z, got[0].current) == (5, 473978101, 85455380, 15.0, 1)
    forced, home = load_wpl(CORPUS / "mission_planner_sample.txt", home_row=True)
    assert len(forced) == 3 and home == pytest.approx((47.3978101, 8.545538, 15.0))


def test_layout_home_row_tabs_and_seven_decimals():
    text = write_wpl(items(), (47.1, 8.2, 488.5))
    lines = text.splitlines()
    assert lines[0] == "QGC WPL 110"
    assert lines[1].split("\t") == ["0", "1", "0", "16", "0", "0", "0", "0", "47.1000000", "8.2000000", "488.5", "1"]
    row = lines[3].split("\t")
    assert row[0] == "2" and row[8:10] == ["-33.5000001", "-70.0000009"]
    assert all(len(line.split("\t")) == 12 for line in lines[1:])


def test_round_trip_with_home():
    got, home = read_wpl(write_wpl(items(), (47.1, 8.2, 488.5)))
    assert same(got, items()) and home == (47.1, 8.2, 488.5)


def test_without_home_writes_a_placeholder_row():
    text = write_wpl(items())
    assert text.splitlines()[1].split("\t")[8:11] == ["0.0000000", "0.0000000", "0"]
    got, home = read_wpl(text)
    assert same(got, items()) and home == (0.0, 0.0, 0.0)


def test_file_form(tmp_path):
    target = tmp_path / "m.waypoints"
    text = write_wpl(target, items(), home=(1.0, 2.0, 3.0), firmware="ardupilot")
    assert target.read_text() == text and [p.name for p in tmp_path.iterdir()] == ["m.waypoints"]


def test_pymavlink_loader_reads_what_we_write(tmp_path):
    from pymavlink import mavwp

    f = tmp_path / "m.waypoints"
    f.write_text(write_wpl(items(), (47.1, 8.2, 488.5)))
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(f)) == 5
    wps = [loader.wp(i) for i in range(5)]
    assert [w.command for w in wps] == [16, 22, 16, 206, 20]
    assert wps[2].x == pytest.approx(-33.5000001, abs=1e-9) and wps[2].y == pytest.approx(-70.0000009, abs=1e-9)
    assert math.isnan(wps[1].param4)


@pytest.mark.parametrize("text,where,msg", [
    ("", "w:1", "not 'QGC WPL 110'"),
    ("QGC WPL 100\n", "w:1", "not 'QGC WPL 110'"),
    ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\n", "w:2", "12 fields"),
    ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\tabc\t2\t3\t1\n", "w:2", "not a number"),
    ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n", "w:3",
     "row index 0 appears twice (first at w:2)"),
    ("QGC WPL 110\n\n# c\n0\t2\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n", "w:4", "current"),
    ("QGC WPL 110\n0\t0\t0\t16.5\t0\t0\t0\t0\t1\t2\t3\t1\n", "w:2", "command"),
    ("QGC WPL 110\n0\t0\t0\t16\t0\t0\t0\t0\t300\t2\t3\t1\n", "w:2", "does not fit"),
    ("QGC WPL 110\n0\t0\t0\t16\t1e300\t0\t0\t0\t1\t2\t3\t1\n", "w:2", "float32"),
])
def test_bad_rows_name_their_line(text, where, msg):
    with pytest.raises(PlanError) as err:
        read_wpl(text, "w")
    assert err.value.where == where and msg in err.value.message


def test_limits(tmp_path):
    with pytest.raises(PlanError, match="UTF-8"):
        read_wpl(b"QGC WPL 110\n\xff\n", "w")
    with pytest.raises(PlanError, match="cannot read"):
        load_wpl(tmp_path / "nope")
    with pytest.raises(PlanError, match=r"mission item 2 \(command 16\) has param4 = -inf, which a waypoint file"):
        write_wpl([MissionItem(command=16), MissionItem(command=16, param4=-math.inf)])
    with pytest.raises(PlanError, match=r"home position \(inf, 8.0, 0.0\) holds an infinite value"):
        write_wpl([MissionItem(command=16)], (math.inf, 8.0, 0.0))


finite = st.floats(allow_nan=True, allow_infinity=False, width=32)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.builds(MissionItem, command=st.integers(1, 65535), frame=st.sampled_from([2, 3, 5, 6, 10]),
                          param1=finite, param2=finite, param3=finite, param4=finite,
                          x=st.integers(-900000000, 900000000), y=st.integers(-1800000000, 1800000000),
                          z=finite, autocontinue=st.integers(0, 1)), max_size=8))
def test_property_round_trip(xs):
    # what the writer writes reads back the same; what the reader would refuse the writer refuses
    if any(item_problem(x) for x in xs):
        with pytest.raises(PlanError, match=r"mission item \d+ \(.*\): .*, which a waypoint file should not hold"):
            write_wpl(xs, (1.0, 2.0, 3.0))
        return
    got, _ = read_wpl(write_wpl(xs, (1.0, 2.0, 3.0)))
    assert same(got, xs)


def _one_row(row: str) -> str:
    return "QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t47.1\t8.2\t488.5\t1\n" + row + "\n"


@pytest.mark.parametrize("row,message,hint", [
    ("1\t0\t3\t16\t0\t0\t0\t0\tnan\t8.5\t50\t1", "MAV_CMD_NAV_WAYPOINT: latitude is not set (null or NaN)",
     "needs a position"),
    ("1\t0\t3\t16\t0\t0\t0\t0\t95\t8.5\t50\t1", "latitude 95.0000000 is outside -90..90", "latitude -90..90"),
    ("1\t0\t3\t16\t0\t0\t0\t0\t47\t8.5\tNaN\t1", "altitude nan is not a real altitude", "altitude in metres"),
    ("1\t0\t255\t16\t0\t0\t0\t0\t47\t8.5\t50\t1", "frame 255 is not a MAV_FRAME", "MAV_FRAME number"),
    # the whole number 255 is not "not a whole number": it is out of the flag's range
    ("1\t0\t3\t16\t0\t0\t0\t0\t47\t8.5\t50\t255", "autocontinue 255 is outside 0..1", "0 or 1"),
])
def test_rows_must_hold_real_positions_and_values(row, message, hint):
    with pytest.raises(PlanError) as err:
        read_wpl(_one_row(row), "w")
    assert err.value.where == "w:3" and message in err.value.message and hint in err.value.hint, str(err.value)


def test_rows_without_a_position_and_a_home_without_altitude_are_read():
    # NaN lat/lon where a command takes no position is QGC's and Mission Planner's 0; a home altitude NaN is
    # ArduPilot's home before a fix (write_wpl writes it so)
    items, home = read_wpl(write_wpl([MissionItem(command=178, frame=2, param2=5)], (47.1, 8.2, math.nan)), "w")
    assert items[0].command == 178 and home[:2] == (47.1, 8.2) and math.isnan(home[2])
    items, _ = read_wpl(_one_row("1\t0\t3\t22\t0\t0\t0\t0\tnan\tnan\t30\t1"), "w")   # takeoff: 0, 0 = here
    assert (items[0].x, items[0].y) == (0, 0)
    with pytest.raises(PlanError, match="home latitude nan"):
        read_wpl("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\tnan\t8.2\t488.5\t1\n", "w")
