"""Emitter units: item shapes per firmware, script-queue pacing across steps, landing, PX4 capture caveat."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from missions.emit import lua
from missions.emit.emitter import Emitter, Track, TrackPoint
from missions.errors import PlanError
from missions.emit.firmware import ARDUPILOT, PX4, check_items


def emitter(prof, payloads=("thermal",)):
    cat = catalogue()
    cams = {n: cat.get("wiris-pro") for n in payloads}
    comps = {n: 101 + i for i, n in enumerate(payloads)}
    inst = {n: i + 1 for i, n in enumerate(payloads)}
    return Emitter(prof, "copter", 5.0, (50.0, 14.0), cams, comps, inst)


def track(trigger="distance"):
    pts = (TrackPoint(50.0, 14.0, "turnaround"), TrackPoint(50.0001, 14.0, "entry"),
           TrackPoint(50.001, 14.0, "exit"), TrackPoint(50.0011, 14.0, "turnaround"))
    return Track(points=pts, spans=((1, 2),), altitude_m=30.0, trigger=trigger, trigger_distance_m=7.5,
                 interval_s=1.5)


@pytest.mark.parametrize("prof", [ARDUPILOT, PX4])
def test_items_shapes(prof):
    e = emitter(prof)
    e.takeoff(20)
    e.track(track())
    e.land(None, None)
    items = e.result().items
    check_items(items, prof)
    for it in items:
        if it.frame == m.MAV_FRAME_MISSION:
            assert it.x == 0 and it.y == 0          # int32 params 5/6: never NaN
        else:
            assert it.frame == m.MAV_FRAME_GLOBAL_RELATIVE_ALT and it.x and it.y
    land = items[-1]
    assert land.command == m.MAV_CMD_NAV_LAND and land.z == 0 and (land.x, land.y) == (items[-2].x, items[-2].y)
    assert math.isnan(items[0].param4)              # takeoff yaw unchanged, as QGC writes it


def test_bridge_paced_across_consecutive_camera_steps():
    e = emitter(ARDUPILOT)
    e.takeoff(20)
    for k in range(4):   # four steps, no NAV item between them
        e.camera_change("thermal", [("layout", 3), ("blend_opacity", 20 + k), ("palette", k), ("emissivity", 0.9)])
    items = e.result().items
    run = 0
    pauses = 0
    for it in items:
        if it.command == m.MAV_CMD_NAV_LOITER_TIME:
            pauses += 1
            assert it.param1 > 0 and (it.x, it.y, it.z) == (items[0].x, items[0].y, items[0].z)
        if it.frame != m.MAV_FRAME_MISSION:
            run = 0
        elif it.command == m.MAV_CMD_DO_SEND_SCRIPT_MESSAGE:
            run += 1
            assert run <= lua.QUEUE_SIZE
    assert pauses >= 2
    assert len(lua.decode(items)) == 4 * 3   # SET_CAMERA_MODE, USER_1, USER_2 per step
    check_items(items, ARDUPILOT)


def test_change_before_any_position_refused():
    with pytest.raises(PlanError, match="before the vehicle has a position") as ei:
        emitter(ARDUPILOT).camera_change("thermal", [("palette", 1)])
    assert "payload's settings" in ei.value.hint


def test_px4_single_capture_warns_other_cameras_shoot():
    e = emitter(PX4, ("a", "b"))
    e.takeoff(20)
    e.waypoint(50.0, 14.0, 20, 2, "a")
    assert any(w.code == "px4_single_capture_all" for w in e.result().warnings)


def test_zoom_in_flight_on_px4_is_digicam_control_without_a_shot():
    e = emitter(PX4)
    e.takeoff(20)
    e.camera_change("thermal", [("zoom", 4.0)])
    (it,) = [i for i in e.result().items if i.command == m.MAV_CMD_DO_DIGICAM_CONTROL]
    assert it.param2 == 4.0 and it.x == 0 and math.isnan(it.param1)     # p5 shoot = 0: no photo


def test_visible_settings_in_flight_refused_on_px4():
    e = emitter(PX4)
    e.takeoff(20)
    with pytest.raises(PlanError) as ei:
        e.camera_change("thermal", [("gain_db", 6)])
    assert "202" in ei.value.hint


def test_altitudes_are_whole_centimetres_as_ardupilot_stores_them():
    """ArduPilot keeps mission altitudes in cm; a finer value would read back different under --verify."""
    from missions.emit import emitter as emit

    item = emit._nav(16, 50.0, 14.0, 40.123456)
    assert item.z == 40.12


def test_land_before_any_position_needs_lat_lon():
    with pytest.raises(PlanError, match="land needs lat/lon") as ei:
        emitter(ARDUPILOT).land(None, None, where="plan.yaml:9:5")
    assert ei.value.where == "plan.yaml:9:5"
    assert "lat" in ei.value.hint and "takeoff" in ei.value.hint


@pytest.mark.parametrize("prof", [ARDUPILOT, PX4])
def test_setting_whose_condition_is_not_set_in_flight_names_the_condition(prof):
    e = emitter(prof)
    e.takeoff(20)
    with pytest.raises(PlanError, match="none of these settings") as ei:
        e.camera_change("thermal", [("range_max_c", 90.0), ("span_half_c", 5.0)], where="plan.yaml:12:7")
    assert ei.value.where == "plan.yaml:12:7"
    assert "range_mode: manual" in ei.value.hint and "range_mode: span" in ei.value.hint
