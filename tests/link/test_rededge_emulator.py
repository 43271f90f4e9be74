"""The RedEdge emulator against the MicaSense serial API's rules (shared/seeds/micasense-rededge-serial-api.txt)."""

from __future__ import annotations

import math
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from emu_wire import Wire, only, types
from wiris_tools.emulate.rededge import RedEdgeState
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.link import Link

MX = catalogue().get("rededge-mx")


@pytest.fixture
def cam():
    return RedEdgeState(MX, now=0.0, utc_offset_s=1.7e9)


@pytest.fixture
def ap():
    return Wire(system=7, component=1, mavlink1=True)


def test_heartbeat_fixed_values_and_system_id_adoption(cam, ap):
    hb = only(cam.tick(0.0), "HEARTBEAT")
    fixed = dict(MX.extra)["heartbeat"]
    assert (hb.type, hb.autopilot, hb.base_mode, hb.custom_mode, hb.system_status) == (
        fixed["type"], fixed["autopilot"], fixed["base_mode"], fixed["custom_mode"], fixed["system_status"])
    assert hb.type != m.MAV_TYPE_CAMERA
    assert cam.system_id == 255                         # "defaults to 255 otherwise"
    cam.handle(ap(ap.mav.attitude_encode(0, 0, 0, 0, 0, 0, 0)), 0.1)
    assert cam.system_id == 7 and cam.mav.srcSystem == 7


def test_ping_answered_with_same_seq_to_the_sender(cam, ap):
    out = cam.handle(ap(ap.mav.ping_encode(123456, 42, 0, 0)), 0)
    p = only(out, "PING")
    assert (p.seq, p.target_system, p.target_component, p.time_usec) == (42, 7, 1, 123456)
    assert cam.handle(ap(ap.mav.ping_encode(1, 43, 9, 9)), 0) == []     # a response, not a request


def test_capture_feedback_carries_state(cam, ap):
    cam.handle(ap(ap.mav.gps_raw_int_encode(1_700_000_000_000_000, 3, 491000000, 160000000, 400000, 0, 0, 0, 0, 12)), 1.0)
    cam.handle(ap(ap.mav.attitude_encode(0, math.radians(5), math.radians(-3), math.radians(90), 0, 0, 0)), 1.0)
    cam.handle(ap(ap.mav.mount_status_encode(7, 100, 1000, 0, 0)), 1.0)
    out = cam.handle(ap(ap.mav.digicam_control_encode(7, 100, 1, 1, 0, 0, 1, 0, 0, 0)), 2.0)
    assert types(out) == ["CAMERA_STATUS", "CAMERA_FEEDBACK"]
    status, fb = out
    assert status.event_id == m.CAMERA_STATUS_TYPE_TRIGGER and status.img_idx == 1 and status.target_system == 7
    assert fb.flags == m.CAMERA_FEEDBACK_CLOSEDLOOP and fb.img_idx == 1
    assert (fb.lat, fb.lng) == (491000000, 160000000) and fb.alt_msl == pytest.approx(400.0)
    assert fb.roll == pytest.approx(5) and fb.pitch == pytest.approx(-3 + 10) and fb.yaw == pytest.approx(90)
    assert fb.foc_len == pytest.approx(MX.imagers[0].lenses_mm[0])
    assert fb.time_usec == 1_700_000_000_000_000 + 1_000_000     # GPS time + 1 s on the camera clock


def test_state_older_than_5_s_is_not_used(cam, ap):
    cam.handle(ap(ap.mav.global_position_int_encode(0, 10, 20, 30000, 0, 0, 0, 0, 0)), 0.0)
    fb = cam.handle(ap(ap.mav.digicam_control_encode(0, 0, 1, 1, 0, 0, 1, 0, 0, 0)), 6.0)[1]
    assert (fb.lat, fb.lng) == (0, 0)


def test_no_fix_gives_no_position(cam, ap):
    cam.handle(ap(ap.mav.gps_raw_int_encode(0, 2, 491000000, 160000000, 400000, 0, 0, 0, 0, 3)), 0.0)
    fb = cam.handle(ap(ap.mav.digicam_control_encode(0, 0, 1, 1, 0, 0, 1, 0, 0, 0)), 0.5)[1]
    assert (fb.lat, fb.lng) == (0, 0)


@pytest.mark.parametrize("shot,captures", [(0, False), (1, True), (2, True), (3, False)])
def test_shot_values(cam, ap, shot, captures):
    out = cam.handle(ap(ap.mav.digicam_control_encode(0, 100, 1, 1, 0, 0, shot, 0, 0, 0)), 0)
    assert bool(out) == captures
    if shot == 2:
        assert cam.feedback[-1].panel


def test_ignores_other_components_and_command_long(cam, ap):
    assert cam.handle(ap(ap.mav.digicam_control_encode(7, 101, 1, 1, 0, 0, 1, 0, 0, 0)), 0) == []
    assert cam.handle(ap(ap.mav.param_request_list_encode(7, 1)), 0) == []
    cmd = ap(ap.mav.command_long_encode(7, 100, m.MAV_CMD_DO_DIGICAM_CONTROL, 0, 0, 0, 0, 0, 1, 0, 0))
    assert cam.handle(cmd, 0) == []          # not part of the serial API: no ACK, no capture
    assert cam.capture_count == 0


def test_digicam_configure_manual_per_sensor(cam, ap):
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 2, 500, 0, 3, 0, 0, 0, 2, 0)), 0)
    assert cam.exposure_mode == 2 and cam.exposures[2].shutter_divisor == 500 and cam.exposures[2].iso == 3
    assert cam.exposures[0].shutter_divisor != 500
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 2, 250, 0, 9, 0, 0, 0, 255, 0)), 0)   # ISO 9: ignored
    assert all(e.shutter_divisor == 250 for e in cam.exposures) and cam.exposures[2].iso == 3
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 7, 1, 0, 1, 0, 0, 0, 255, 0)), 0)    # mode 7: no effect
    assert cam.exposure_mode == 2
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 1, 1, 0, 1, 0, 0, 0, 255, 0)), 0)
    assert cam.exposure_mode == 1


def test_classic_parameters(cam, ap):
    params = [s.param for s in MX.settings if s.command and s.command.message == "PARAM_SET"]
    out = cam.handle(ap(ap.mav.param_request_list_encode(7, 100)), 0)
    assert [p.param_id for p in out] == params and {p.param_type for p in out} == {m.MAV_PARAM_TYPE_REAL32}
    v = only(cam.handle(ap(ap.mav.param_set_encode(7, 100, b"autoCapMode", 2, m.MAV_PARAM_TYPE_REAL32)), 0),
             "PARAM_VALUE")
    assert v.param_value == 2
    v = only(cam.handle(ap(ap.mav.param_set_encode(7, 100, b"autoCapMode", 7, m.MAV_PARAM_TYPE_REAL32)), 0),
             "PARAM_VALUE")
    assert v.param_value == 2                # refused: the unchanged value comes back
    v = only(cam.handle(ap(ap.mav.param_request_read_encode(7, 100, b"", params.index("wifi"))), 0), "PARAM_VALUE")
    assert v.param_id == "wifi"
    assert cam.handle(ap(ap.mav.param_set_encode(7, 100, b"nope", 1, m.MAV_PARAM_TYPE_REAL32)), 0) == []


def test_timer_auto_capture(cam, ap):
    cam.handle(ap(ap.mav.param_set_encode(7, 100, b"timerPeriod", 2.0, m.MAV_PARAM_TYPE_REAL32)), 0)
    cam.handle(ap(ap.mav.param_set_encode(7, 100, b"autoCapMode", 1, m.MAV_PARAM_TYPE_REAL32)), 0)
    for t in range(0, 100):
        cam.tick(t / 10)
    assert len(cam.auto_captures) == 5


def test_overlap_auto_capture_from_positions(cam, ap):
    for name, value in (("autoCapMode", 2), ("operatingAlt", 100.0), ("opAltTolerance", 10.0),
                        ("overlapAlongTrk", 80.0)):
        cam.handle(ap(ap.mav.param_set_encode(7, 100, name.encode(), value, m.MAV_PARAM_TYPE_REAL32)), 0)
    lat0 = 490000000
    cam.handle(ap(ap.mav.global_position_int_encode(0, lat0, 160000000, 200000, 0, 0, 0, 0, 0)), 0)   # ground
    # climb to 100 m above it, then fly north 1 km; along-track footprint 100*3.6/5.4 = 66.7 m, spacing 13.3 m
    north_m = 0.0
    t = 1.0
    while north_m <= 1000.0:
        lat = lat0 + int(north_m / 111195.0 * 1e7)
        cam.handle(ap(ap.mav.global_position_int_encode(0, lat, 160000000, 300000, 0, 0, 0, 0, 0)), t)
        north_m += 1.0
        t += 0.1
    sensor_h = MX.imagers[0].sensor_size_mm[1]
    spacing = 100.0 * sensor_h / MX.imagers[0].lenses_mm[0] * 0.2
    gaps = [(b[1] - a[1]) / 1e7 * 111195.0 for a, b in zip(cam.auto_captures, cam.auto_captures[1:])]
    assert len(gaps) > 50
    assert all(spacing <= g <= spacing + 1.05 for g in gaps)      # positions arrive every 1 m


def test_udp_mavlink1_end_to_end():
    """Over a real socket: MAVLink 1 frames from component 100, sysid adopted, capture answered."""
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", system=9, component=1, heartbeat_s=0.2) as ap_link:
        hb = ap_link.wait_heartbeat(timeout=5, component=100)
        assert hb.get_msgbuf()[0] == 0xFE
        deadline = time.monotonic() + 5
        while ap_link.heartbeats().get((9, 100)) is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert (9, 100) in ap_link.heartbeats()            # it adopted our system id
        with ap_link.inbox(["CAMERA_STATUS", "CAMERA_FEEDBACK"], src_component=100) as box:
            ap_link.send(ap_link.mav.digicam_control_encode(9, 100, 1, 1, 0, 0, 1, 0, 0, 0))
            got = {box.get(3).get_type(), box.get(3).get_type()}
        assert got == {"CAMERA_STATUS", "CAMERA_FEEDBACK"}
        assert emu.errors == 0
