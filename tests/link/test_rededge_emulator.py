"""The RedEdge emulator against the MicaSense serial API's rules (shared/seeds/micasense-rededge-serial-api.txt)."""

from __future__ import annotations

import math
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from emu_wire import Wire, only, types
from wiris_tools import paramext
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
    """The API page's values (<li value="4">Manual</li>; gain 1, 2, 4, 8), not the seed's renumbered lists."""
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 4, 500, 0, 4, 0, 0, 0, 2, 0)), 0)
    assert cam.exposure_mode == 4 and cam.exposures[2].shutter_divisor == 500 and cam.exposures[2].iso == 4
    assert cam.exposures[0].shutter_divisor != 500
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 4, 250, 0, 3, 0, 0, 0, 255, 0)), 0)   # gain 3: none
    assert all(e.shutter_divisor == 250 for e in cam.exposures) and cam.exposures[2].iso == 4
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 4, 250, 0, 8, 0, 0, 0, 255, 0)), 0)   # ISO 800
    assert all(e.iso == 8 for e in cam.exposures)
    for mode in (2, 3, 7):                                                               # "no effect"
        cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, mode, 1, 0, 1, 0, 0, 0, 255, 0)), 0)
        assert cam.exposure_mode == 4 and cam.exposures[0].shutter_divisor == 250
    cam.handle(ap(ap.mav.digicam_configure_encode(7, 100, 1, 1, 0, 1, 0, 0, 0, 255, 0)), 0)
    assert cam.exposure_mode == 1


def _set(ap, name: str, value, cdf_type: str):
    """PARAM_SET as the API wants it: the value's bytes as the parameter's type."""
    return ap(ap.mav.param_set_encode(7, 100, name.encode(), paramext.encode_classic(value, cdf_type),
                                      paramext.classic_type(cdf_type)))


def test_classic_parameters(cam, ap):
    """Each parameter has the API table's MAV_PARAM_TYPE, and its 4 bytes are read as that type."""
    params = [s.param for s in MX.settings if s.command and s.command.message == "PARAM_SET"]
    out = cam.handle(ap(ap.mav.param_request_list_encode(7, 100)), 0)
    assert [p.param_id for p in out] == params
    assert {p.param_id: p.param_type for p in out} == {
        "wifi": m.MAV_PARAM_TYPE_REAL32, "autoCapMode": m.MAV_PARAM_TYPE_UINT32,
        "timerPeriod": m.MAV_PARAM_TYPE_REAL32, "overlapAlongTrk": m.MAV_PARAM_TYPE_UINT32,
        "overlapCrossTrk": m.MAV_PARAM_TYPE_UINT32, "operatingAlt": m.MAV_PARAM_TYPE_INT32,
        "opAltTolerance": m.MAV_PARAM_TYPE_UINT32, "rawFormat": m.MAV_PARAM_TYPE_UINT32}
    v = only(cam.handle(_set(ap, "autoCapMode", 2, "uint32"), 0), "PARAM_VALUE")
    assert paramext.decode_classic(v.param_value, v.param_type) == 2 and v.param_value < 1e-40
    v = only(cam.handle(_set(ap, "autoCapMode", 7, "uint32"), 0), "PARAM_VALUE")
    assert paramext.decode_classic(v.param_value, v.param_type) == 2          # refused: unchanged value back
    # an integer sent as a float: 1.0 is 0x3F800000 = 1065353216 to the camera, not timer mode
    v = only(cam.handle(ap(ap.mav.param_set_encode(7, 100, b"autoCapMode", 1.0, m.MAV_PARAM_TYPE_REAL32)), 0),
             "PARAM_VALUE")
    assert cam.values["autoCapMode"] == 2
    v = only(cam.handle(_set(ap, "timerPeriod", 1.5, "float"), 0), "PARAM_VALUE")
    assert v.param_value == 1.5 and v.param_type == m.MAV_PARAM_TYPE_REAL32
    v = only(cam.handle(ap(ap.mav.param_request_read_encode(7, 100, b"", params.index("wifi"))), 0), "PARAM_VALUE")
    assert v.param_id == "wifi"
    assert cam.handle(_set(ap, "nope", 1, "float"), 0) == []


def _at_height(cam, ap, height_m: float, t: float, north_m: float = 0.0) -> None:
    lat = 490000000 + int(north_m / 111195.0 * 1e7)
    cam.handle(ap(ap.mav.global_position_int_encode(0, lat, 160000000, int(200000 + height_m * 1000), 0, 0, 0, 0,
                                                    0)), t)


def test_timer_auto_capture_only_from_the_tolerance_below_the_target_up(cam, ap):
    """opAltTolerance: "Distance, in meters, below the operating altitude (operatingAlt) to enable automatic
    capture modes" — on the ground it does not shoot, above the target it does."""
    for name, value, t in (("timerPeriod", 2.0, "float"), ("operatingAlt", 100, "int32"),
                           ("opAltTolerance", 10, "uint32"), ("autoCapMode", 1, "uint32")):
        cam.handle(_set(ap, name, value, t), 0)
    _at_height(cam, ap, 0.0, 0.0)                       # the ground estimate
    for k in range(0, 100):
        _at_height(cam, ap, 85.0, k / 10)
        cam.tick(k / 10)
    assert cam.auto_captures == []                      # 15 m below the target: more than the tolerance
    for k in range(100, 200):
        _at_height(cam, ap, 150.0, k / 10)
        cam.tick(k / 10)
    assert len(cam.auto_captures) == 5                  # far above it: every 2 s


def test_overlap_auto_capture_from_positions(cam, ap):
    for name, value, t in (("autoCapMode", 2, "uint32"), ("operatingAlt", 100, "int32"),
                           ("opAltTolerance", 10, "uint32"), ("overlapAlongTrk", 80, "uint32")):
        cam.handle(_set(ap, name, value, t), 0)
    _at_height(cam, ap, 0.0, 0.0)                       # ground
    # climb to 100 m above it, then fly north 1 km; along-track footprint 100*3.6/5.4 = 66.7 m, spacing 13.3 m
    north_m = 0.0
    t = 1.0
    while north_m <= 1000.0:
        _at_height(cam, ap, 100.0, t, north_m)
        north_m += 1.0
        t += 0.1
    sensor_h = MX.imagers[0].sensor_size_mm[1]
    spacing = 100.0 * sensor_h / MX.imagers[0].lenses_mm[0] * 0.2
    gaps = [(b[1] - a[1]) / 1e7 * 111195.0 for a, b in zip(cam.auto_captures, cam.auto_captures[1:])]
    assert len(gaps) > 50
    assert all(spacing <= g <= spacing + 1.05 for g in gaps)      # positions arrive every 1 m
    before = len(cam.auto_captures)
    while north_m <= 1500.0:                            # 200 m above the target: still shooting
        _at_height(cam, ap, 300.0, t, north_m)
        north_m += 1.0
        t += 0.1
    assert len(cam.auto_captures) > before
    before = len(cam.auto_captures)
    while north_m <= 2000.0:                            # 11 m below it: stopped
        _at_height(cam, ap, 89.0, t, north_m)
        north_m += 1.0
        t += 0.1
    assert len(cam.auto_captures) == before


def test_mavlink2_frames_are_not_read(cam):
    """"RedEdge uses Mavlink v1.0 messages": a MAVLink 2 DIGICAM_CONTROL takes no picture and gets no answer."""
    ap2 = Wire(system=7, component=1, mavlink1=False)
    assert cam.handle(ap2(ap2.mav.digicam_control_encode(7, 100, 1, 1, 0, 0, 1, 0, 0, 0)), 0) == []
    assert cam.capture_count == 0


def test_image_index_wraps_and_angles_stay_within_180(cam, ap):
    cam.capture_count = 65535
    status, fb = cam.handle(ap(ap.mav.digicam_control_encode(7, 100, 1, 1, 0, 0, 1, 0, 0, 0)), 0)
    assert status.img_idx == 0 and fb.img_idx == 0             # uint16 "Image Index"
    cam.handle(ap(ap.mav.attitude_encode(0, math.radians(170), math.radians(-170), 0, 0, 0, 0)), 1.0)
    cam.handle(ap(ap.mav.mount_status_encode(7, 100, -3000, 3000, 0, 0)), 1.0)
    fb = cam.handle(ap(ap.mav.digicam_control_encode(7, 100, 1, 1, 0, 0, 1, 0, 0, 0)), 1.5)[1]
    assert fb.roll == pytest.approx(-160) and fb.pitch == pytest.approx(160)   # "earth frame, degrees, +-180"
    cam.handle(ap(ap.mav.gps_raw_int_encode(2**64 - 1, 3, 491000000, 160000000, 400000, 0, 0, 0, 0, 12)), 2.0)
    status, fb = cam.handle(ap(ap.mav.digicam_control_encode(7, 100, 1, 1, 0, 0, 1, 0, 0, 0)), 3.0)
    assert fb.time_usec == 2**64 - 1                   # clamped: the answer is still sent


def test_udp_mavlink1_end_to_end():
    """Over a real socket: MAVLink 1 frames from component 100, sysid adopted, capture answered."""
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu, \
            Link(f"udpout:127.0.0.1:{emu.link.local_port}", system=9, component=1, heartbeat_s=0.2,
                 mavlink1=True) as ap_link:
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
