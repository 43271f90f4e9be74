"""The WIRIS emulator's protocol logic, driven without sockets: every behaviour is checked against the
Workswell manual's section (cited per test) and the catalogue, with messages packed and parsed as on a wire."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from cdf.generate import definition_xml
from emu_wire import NAN, Wire, ack_of, only, types
from wiris_tools import paramext
from wiris_tools.camera_definition import parse_definition
from wiris_tools.emulate.wiris import WirisConfig, WirisState, new_wiris

WORKSWELL = [c.id for c in catalogue().cameras if c.protocol == "workswell-mavlink"]
ACCEPTED, DENIED, UNSUPPORTED = m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_DENIED, m.MAV_RESULT_UNSUPPORTED


@pytest.fixture
def pro():
    return new_wiris(catalogue().get("wiris-pro"), WirisConfig(definition_uri="http://127.0.0.1:1/x.xml"))


@pytest.fixture
def gcs():
    return Wire()


def test_heartbeat_is_a_camera(pro):
    hb = only(pro.tick(0.0), "HEARTBEAT")
    assert hb.type == m.MAV_TYPE_CAMERA and hb.autopilot == m.MAV_AUTOPILOT_INVALID
    assert pro.tick(0.5) == []          # once a second
    assert types(pro.tick(1.0)) == ["HEARTBEAT"]


@pytest.mark.parametrize("target,answers", [(100, True), (0, True), (101, False), (1, False), (255, False)])
def test_answers_only_its_component_or_broadcast(pro, gcs, target, answers):
    """§3.2: commands to any component but 0 or the camera id are ignored."""
    out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1, target_component=target), 1.0)
    assert bool(out) == answers


def test_other_component_id_from_the_config(gcs):
    cam = new_wiris(catalogue().get("wiris-pro"), WirisConfig(component=103))
    assert cam.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1, target_component=100), 0) == []
    assert ack_of(cam.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1, target_component=103), 0),
                  m.MAV_CMD_REQUEST_CAMERA_INFORMATION) == ACCEPTED


def test_gps_is_taken_whoever_it_is_for_and_ends_in_the_image(pro, gcs):
    """§3.2: broadcast GLOBAL_POSITION_INT/GPS_STATUS do not depend on the id; §6.4.5 position of the image."""
    pro.handle(gcs(gcs.mav.global_position_int_encode(1000, 491234567, 162345678, 350000, 120000, 0, 0, 0, 0)), 1)
    pro.handle(gcs(gcs.mav.gps_status_encode(11, [0] * 20, [0] * 20, [0] * 20, [0] * 20, [0] * 20)), 1)
    out = pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, NAN, NAN, 1), 2.0)
    assert ack_of(out, m.MAV_CMD_DO_DIGICAM_CONTROL) == ACCEPTED
    img = only(out, "CAMERA_IMAGE_CAPTURED")
    assert (img.lat, img.lon, img.alt, img.relative_alt) == (491234567, 162345678, 350000, 120000)
    assert img.capture_result == 1 and img.image_index == 0 and img.camera_id == 100
    assert pro.satellites_visible == 11


def test_unlicensed_camera_ignores_commands_but_takes_gps(gcs):
    cam = new_wiris(catalogue().get("wiris-pro"), WirisConfig(licensed=False))
    assert cam.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1), 0) == []
    cam.handle(gcs(gcs.mav.global_position_int_encode(0, 5, 6, 7, 8, 0, 0, 0, 0)), 0)
    assert cam.position.lat == 5


@pytest.mark.parametrize("model", WORKSWELL)
def test_camera_information_follows_the_table_and_common_xml(model, gcs):
    cam_t = catalogue().get(model)
    cam = new_wiris(cam_t, WirisConfig(definition_uri="http://127.0.0.1:8000/d.xml"))
    for request in (gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_INFORMATION),
                    gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1)):
        out = cam.handle(request, 2.5)
        assert types(out)[0] == "COMMAND_ACK" and out[0].result == ACCEPTED   # ACK first, then the message
        info = only(out, "CAMERA_INFORMATION")
        assert bytes(info.vendor_name).rstrip(b"\0").decode() == cam_t.vendor
        assert bytes(info.model_name).rstrip(b"\0").decode() == cam_t.model
        assert info.cam_definition_version == cam_t.definition_version
        assert info.cam_definition_uri == "http://127.0.0.1:8000/d.xml"
        assert info.sensor_size_h == 0 and info.sensor_size_v == 0          # §6.4.1 "not implemented, sends 0"
        # the standard's bits, not the manual's §7.1.1 table (0x00 for video)
        names = {e.name for v, e in m.enums["CAMERA_CAP_FLAGS"].items() if v and info.flags & v == v
                 and v < m.CAMERA_CAP_FLAGS_ENUM_END}
        assert names == set(cam_t.capabilities)
        assert info.flags & m.CAMERA_CAP_FLAGS_CAPTURE_VIDEO
        thermal = cam_t.imager("thermal")
        if thermal.resolution_px:
            assert (info.resolution_h, info.resolution_v) == thermal.resolution_px
            assert info.focal_length == thermal.lenses_mm[0]
        else:
            assert (info.resolution_h, info.resolution_v) == (0, 0) and math.isnan(info.focal_length)


def test_camera_settings_reports_main_camera_and_zoom(pro, gcs):
    """§6.4.2: mode_id carries the Main Camera enumerator, zoomLevel the zoom, focus NaN. zoomLevel is
    common.xml's percentage of the zoom range (§6.4.2 prints the factor 1-10): 4x of 1-10x is 33.3 %."""
    pro.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_MODE, NAN, NAN, NAN, NAN, NAN, 2), 0)   # main camera visible (+1)
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, 4.0), 0)
    s = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_SETTINGS, 1), 0), "CAMERA_SETTINGS")
    assert s.mode_id == 1 and s.zoomLevel == pytest.approx(100 * 3 / 9, abs=1e-3) and math.isnan(s.focusLevel)
    assert types(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_SETTINGS, 0), 0)) == ["COMMAND_ACK"]   # 0: no action
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_SETTINGS, 2), 0),
                  m.MAV_CMD_REQUEST_CAMERA_SETTINGS) == DENIED


def test_storage_information_three_storages(pro, gcs):
    out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_STORAGE_INFORMATION), 0)
    infos = [x for x in out if x.get_type() == "STORAGE_INFORMATION"]
    assert [i.storage_id for i in infos] == [0, 1, 2] and {i.storage_count for i in infos} == {3}
    names = [o.name for o in catalogue().get("wiris-pro").enum("storage").options]
    assert [i.name for i in infos] == names
    one = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_STORAGE_INFORMATION, 2), 0)
    assert only(one, "STORAGE_INFORMATION").storage_id == 2
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_STORAGE_INFORMATION, 3), 0),
                  m.MAV_CMD_REQUEST_MESSAGE) == DENIED


def test_request_message_unknown_id_is_unsupported_and_nan_denied(pro, gcs):
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS), 0),
                  m.MAV_CMD_REQUEST_MESSAGE) == UNSUPPORTED
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, NAN), 0), m.MAV_CMD_REQUEST_MESSAGE) == DENIED


def test_commands_the_manual_does_not_list_are_unsupported(pro, gcs):
    listed = {name for name, _ in catalogue().get("wiris-pro").commands}
    for cmd in (m.MAV_CMD_SET_CAMERA_FOCUS, m.MAV_CMD_COMPONENT_ARM_DISARM, m.MAV_CMD_USER_4):
        assert m.enums["MAV_CMD"][cmd].name not in listed
        assert ack_of(pro.handle(gcs.cmd(cmd, 1), 0), cmd) == UNSUPPORTED
    ci = gcs(gcs.mav.command_int_encode(1, 100, 0, m.MAV_CMD_SET_CAMERA_FOCUS, 0, 0, 1, 0, 0, 0, 0, 0, 0))
    assert ack_of(pro.handle(ci, 0), m.MAV_CMD_SET_CAMERA_FOCUS) == UNSUPPORTED


def test_command_int_for_a_listed_command_says_command_long_only(pro, gcs):
    # §6.3 lists COMMAND_LONGs; common.xml's MAV_RESULT_COMMAND_LONG_ONLY tells the sender how to resend
    ci = gcs(gcs.mav.command_int_encode(1, 100, 0, m.MAV_CMD_REQUEST_CAMERA_INFORMATION, 0, 0, 1, 0, 0, 0, 0, 0, 0))
    assert ack_of(pro.handle(ci, 0), m.MAV_CMD_REQUEST_CAMERA_INFORMATION) == m.MAV_RESULT_COMMAND_LONG_ONLY
    assert not [x for x in pro.handle(ci, 0) if x.get_type() == "CAMERA_INFORMATION"]


def test_set_camera_mode_offsets_and_keep(pro, gcs):
    """§6.3.2.5: layout and main camera are sent +1; 0 and NaN keep; opacity 10–100."""
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_MODE, NAN, 1, NAN, NAN, 4, 2, 70), 0),
                  m.MAV_CMD_SET_CAMERA_MODE) == ACCEPTED
    assert (pro.value("layout"), pro.value("main_camera"), pro.value("blend_opacity")) == (3, 1, 70)
    assert pro.camera_mode == m.CAMERA_MODE_VIDEO
    pro.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_MODE, NAN, NAN, NAN, NAN, 0, 0, NAN), 0)    # 0 and NaN keep
    assert (pro.value("layout"), pro.value("main_camera"), pro.value("blend_opacity")) == (3, 1, 70)
    for bad in ([NAN, NAN, NAN, NAN, 5], [NAN, NAN, NAN, NAN, NAN, 3], [NAN] * 6 + [9], [NAN, 2]):
        assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_MODE, *bad), 0), m.MAV_CMD_SET_CAMERA_MODE) == DENIED
    assert (pro.value("layout"), pro.value("main_camera"), pro.value("blend_opacity")) == (3, 1, 70)


def test_digicam_configure_nan_keeps(pro, gcs):
    """§6.3: NaN, NaN, NaN, 6, NaN, NaN, NaN only sets the gain to 6."""
    before = dict(pro.values)
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONFIGURE, NAN, NAN, NAN, 6, NAN, NAN, NAN), 0)
    changed = {k for k in pro.values if pro.values[k] != before[k]}
    assert changed == {"VIS_GAIN"} and pro.value("gain_db") == 6
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONFIGURE, NAN, 22), 0),
                  m.MAV_CMD_DO_DIGICAM_CONFIGURE) == DENIED            # shutter 0–21
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONFIGURE, 4), 0),
                  m.MAV_CMD_DO_DIGICAM_CONFIGURE) == DENIED            # visible modes 0–3


def test_zoom_goes_to_the_closest_possible_value(pro, gcs):
    """§6.3.2.2: absolute zoom is set to the closest possible value; relative only when absolute is NaN."""
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, 55.0), 0)
    assert pro.value("zoom") == catalogue().get("wiris-pro").setting("zoom").max
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, 2.0, 3), 0)      # relative ignored: absolute given
    assert pro.value("zoom") == 2.0
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, -3), 0)
    assert pro.value("zoom") == pytest.approx(1.7)
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, -100), 0)
    assert pro.value("zoom") == 1.0
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, NAN, NAN, 2), 0),
                  m.MAV_CMD_DO_DIGICAM_CONTROL) == DENIED               # shoot is 0 or 1


def test_user_1_pro_range_limits_depend_on_the_mode(pro, gcs):
    """§6.3.2.13: p3/p4 are max/min in manual mode and half width/centre in span mode."""
    out = pro.handle(gcs.cmd(m.MAV_CMD_USER_1, 1, NAN, 80, 5, 0.9, 25, 22), 0)
    assert ack_of(out, m.MAV_CMD_USER_1) == ACCEPTED
    v = pro.values
    assert (v["RANGE_MODE"], v["RANGE_MAX_C"], v["RANGE_MIN_C"]) == (1, 80, 5)
    assert (v["EMISSIVITY"], v["REFLECTED_C"], v["ATMOSPHERIC_C"]) == pytest.approx((0.9, 25, 22))
    pro.handle(gcs.cmd(m.MAV_CMD_USER_1, 2, NAN, 10, 40), 0)
    assert (v["RANGE_MODE"], v["SPAN_HALF_C"], v["SPAN_CENTER_C"], v["RANGE_MAX_C"]) == (2, 10, 40, 80)
    pro.handle(gcs.cmd(m.MAV_CMD_USER_1, NAN, NAN, 12), 0)                 # still span: p3 is the half width
    assert v["SPAN_HALF_C"] == 12 and v["RANGE_MAX_C"] == 80
    for bad in ([3], [NAN, NAN, NAN, NAN, 0.4], [NAN] * 5 + [101], [NAN] * 6 + [-41], [NAN, NAN, 0.0]):
        assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_USER_1, *bad), 0), m.MAV_CMD_USER_1) == DENIED
    assert v["RANGE_MODE"] == 2 and v["SPAN_HALF_C"] == 12


def test_user_1_security_is_range_stabilisation(gcs):
    sec = new_wiris(catalogue().get("wiris-security"))
    assert ack_of(sec.handle(gcs.cmd(m.MAV_CMD_USER_1, 2.5, 10, 20), 0), m.MAV_CMD_USER_1) == ACCEPTED
    assert (sec.value("stabilization_s"), sec.value("hot_rejection_pct"), sec.value("cold_rejection_pct")) \
        == (2.5, 10, 20)
    assert sec.value("range_mode") is None
    assert ack_of(sec.handle(gcs.cmd(m.MAV_CMD_USER_1, 6), 0), m.MAV_CMD_USER_1) == DENIED
    assert ack_of(sec.handle(gcs.cmd(m.MAV_CMD_USER_1, NAN, 31), 0), m.MAV_CMD_USER_1) == DENIED


def test_user_2_and_user_3(pro, gcs):
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_USER_2, 3, 10, 90, 6, 4, 1, 0), 0), m.MAV_CMD_USER_2) == ACCEPTED
    assert (pro.value("alarm_mode"), pro.value("sights"), pro.value("palette"), pro.value("alarm_above_color"),
            pro.value("alarm_below_color")) == (3, 6, 4, 1, 0)
    pro.handle(gcs.cmd(m.MAV_CMD_USER_2, NAN, NAN, NAN, 0), 0)                 # sights 0 keeps (§7.2.10)
    assert pro.value("sights") == 6
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_USER_2, NAN, NAN, NAN, 0x20), 0), m.MAV_CMD_USER_2) == DENIED  # CWSI: Agro
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_USER_3, 3), 0), m.MAV_CMD_USER_3) == ACCEPTED
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_USER_3, 5), 0), m.MAV_CMD_USER_3) == DENIED
    assert pro.menu_actions == [3]


def test_one_state_behind_commands_and_param_ext(pro, gcs):
    """A USER_1 change reads back through PARAM_EXT; a PARAM_EXT set shows in CAMERA_SETTINGS."""
    pro.handle(gcs.cmd(m.MAV_CMD_USER_1, 1), 0)
    val = only(pro.handle(gcs(gcs.mav.param_ext_request_read_encode(1, 100, b"RANGE_MODE", -1)), 0), "PARAM_EXT_VALUE")
    assert paramext.decode(paramext.raw_value(val), "uint32") == 1
    ack = only(pro.handle(gcs(gcs.mav.param_ext_set_encode(1, 100, b"CAM_ZOOM", paramext.encode(3.5, "float"),
                                                           m.MAV_PARAM_EXT_TYPE_REAL32)), 0), "PARAM_EXT_ACK")
    assert ack.param_result == m.PARAM_ACK_ACCEPTED
    s = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_SETTINGS), 0), "CAMERA_SETTINGS")
    assert s.zoomLevel == pytest.approx(100 * 2.5 / 9, abs=1e-3)                    # 3.5x of 1-10x, in %


def test_param_ext_list_covers_the_definition_with_declared_types(pro, gcs):
    d = parse_definition(definition_xml(catalogue().get("wiris-pro")))
    out = pro.handle(gcs(gcs.mav.param_ext_request_list_encode(1, 100)), 0)
    assert [x.param_id for x in out] == [p.name for p in d.params]
    for x, p in zip(out, d.params):
        assert x.param_type == paramext.wire_type(p.type).ext_type and x.param_count == len(d.params)
        assert paramext.decode(paramext.raw_value(x), p.type) == pytest.approx(p.default)
    by_index = only(pro.handle(gcs(gcs.mav.param_ext_request_read_encode(1, 100, b"", 3)), 0), "PARAM_EXT_VALUE")
    assert by_index.param_id == d.params[3].name and by_index.param_index == 3
    assert pro.handle(gcs(gcs.mav.param_ext_request_read_encode(1, 100, b"NOPE", -1)), 0) == []
    assert pro.handle(gcs(gcs.mav.param_ext_request_read_encode(1, 100, b"", 999)), 0) == []


def test_param_ext_value_with_zero_bytes_survives(pro, gcs):
    """A uint32 256 is 00 01 00 00: the leading NUL must not cut the value (pymavlink strips char arrays)."""
    ack = only(pro.handle(gcs(gcs.mav.param_ext_set_encode(1, 100, b"PALETTE", paramext.encode(256 - 1, "uint32"),
                                                           m.MAV_PARAM_EXT_TYPE_UINT32)), 0), "PARAM_EXT_ACK")
    assert ack.param_result == m.PARAM_ACK_ACCEPTED and pro.value("palette") == 255
    ack = only(pro.handle(gcs(gcs.mav.param_ext_set_encode(1, 100, b"LAYOUT", paramext.encode(0, "uint32"),
                                                           m.MAV_PARAM_EXT_TYPE_UINT32)), 0), "PARAM_EXT_ACK")
    assert ack.param_result == m.PARAM_ACK_ACCEPTED and pro.value("layout") == 0


@pytest.mark.parametrize("name,value,ptype,result", [
    ("LAYOUT", 4, "uint32", m.PARAM_ACK_VALUE_UNSUPPORTED),       # not an option
    ("EMISSIVITY", 1.2, "float", m.PARAM_ACK_VALUE_UNSUPPORTED),  # above max
    ("CAPTURE_FMT", 0, "uint32", m.PARAM_ACK_VALUE_UNSUPPORTED),  # 0 is not a flag combination
    ("NO_SUCH", 1, "uint32", m.PARAM_ACK_FAILED),                 # unknown
    ("LAYOUT", 1.0, "float", m.PARAM_ACK_FAILED),                 # wrong type
])
def test_param_ext_set_refusals_change_nothing(pro, gcs, name, value, ptype, result):
    before = dict(pro.values)
    out = pro.handle(gcs(gcs.mav.param_ext_set_encode(1, 100, name.encode(), paramext.encode(value, ptype),
                                                      paramext.wire_type(ptype).ext_type)), 0)
    assert only(out, "PARAM_EXT_ACK").param_result == result
    assert pro.values == before


def test_single_capture_and_counter_reset(pro, gcs):
    out = pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 1), 0)     # MAVSDK's take_photo
    assert ack_of(out, m.MAV_CMD_IMAGE_START_CAPTURE) == ACCEPTED
    assert only(out, "CAMERA_IMAGE_CAPTURED").image_index == 0
    st = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS), 0), "CAMERA_CAPTURE_STATUS")
    assert st.image_count == 1 and st.image_status == 0
    again = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_IMAGE_CAPTURED, 0), 0),
                 "CAMERA_IMAGE_CAPTURED")
    assert again.image_index == 0 and again.file_url
    pro.handle(gcs.cmd(m.MAV_CMD_STORAGE_FORMAT, 0, 0, 1), 0)                  # reset the counter only
    assert pro.image_count == 0


def test_periodic_capture_follows_interval_and_count(pro, gcs):
    """§6.3.2.6: interval (min 1 s) and count; CAMERA_CAPTURE_STATUS reports it while it runs (§6.4.4)."""
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0.5, 3), 0), m.MAV_CMD_IMAGE_START_CAPTURE) \
        == DENIED
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 2, 3, 0, 0x1 | 0x8, 2), 10.0),
                  m.MAV_CMD_IMAGE_START_CAPTURE) == ACCEPTED
    assert pro.value("capture") == 9 and pro.value("storage") == 1               # p5 flags, p6 storage + 1
    times = []
    t = 10.0
    while t < 20.0:
        for msg in pro.tick(t):
            if msg.get_type() == "CAMERA_IMAGE_CAPTURED":
                times.append(round(t, 2))
                if len(times) == 1:
                    st = pro._capture_status(t)
                    assert st.image_status == 3 and st.image_interval == 2
        t += 0.05
    assert times == [10.0, 12.0, 14.0]
    assert pro._capture_status(t).image_status == 0
    assert pro.used_mib[1] > 0 and pro.used_mib[0] == 0


def test_stop_capture_and_until_stopped(pro, gcs):
    pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 1, 0), 0)
    n = sum(1 for t in range(0, 50) for x in pro.tick(t / 10) if x.get_type() == "CAMERA_IMAGE_CAPTURED")
    assert n == 5
    pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_STOP_CAPTURE), 5.0)
    assert not any(x.get_type() == "CAMERA_IMAGE_CAPTURED" for t in range(50, 80) for x in pro.tick(t / 10))


def test_full_storage_fails_the_capture():
    g = Wire()
    cam = new_wiris(catalogue().get("wiris-pro"), WirisConfig(storage_capacity_mib=(10.0, 10.0, 10.0),
                                                              image_size_mib=4.0))
    results = []
    cam.handle(g.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 1, 0), 0)
    for t in range(0, 60):
        results += [x for x in cam.tick(t / 10) if x.get_type() == "CAMERA_IMAGE_CAPTURED"]
    assert [r.capture_result for r in results] == [1, 1, 0]
    assert [r.image_index for r in results] == [0, 1, 2] and cam.image_count == 2
    assert not cam.capture.running                                       # periodic capture stopped
    st = only(cam.handle(g.cmd(m.MAV_CMD_REQUEST_STORAGE_INFORMATION, 0), 7), "STORAGE_INFORMATION")
    assert st.available_capacity == pytest.approx(2.0)
    cam.handle(g.cmd(m.MAV_CMD_STORAGE_FORMAT, 0, 1, 0), 7)              # format the SSD
    out = cam.handle(g.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1), 7)
    assert only(out, "CAMERA_IMAGE_CAPTURED").capture_result == 1


def test_video_recording_and_status_rate(pro, gcs):
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_CAPTURE, 3, 2), 0), m.MAV_CMD_VIDEO_START_CAPTURE) \
        == DENIED                                                          # sequence + encoded: not possible
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_CAPTURE, 5, 2), 0), m.MAV_CMD_VIDEO_START_CAPTURE) \
        == ACCEPTED
    statuses = [x for t in range(0, 20) for x in pro.tick(t / 10) if x.get_type() == "CAMERA_CAPTURE_STATUS"]
    assert len(statuses) == 4 and all(s.video_status == 1 for s in statuses)
    pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_STOP_CAPTURE), 2.0)
    assert not [x for t in range(20, 40) for x in pro.tick(t / 10) if x.get_type() == "CAMERA_CAPTURE_STATUS"]


def test_streaming_needs_the_ethernet_sdk(pro, gcs):
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_STREAMING), 0), m.MAV_CMD_VIDEO_START_STREAMING) == DENIED
    info = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION), 0), "VIDEO_STREAM_INFORMATION")
    assert info.count == 0
    sdk = new_wiris(catalogue().get("wiris-pro"), WirisConfig(ethernet_sdk=True))
    assert ack_of(sdk.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_STREAMING), 0), m.MAV_CMD_VIDEO_START_STREAMING) == ACCEPTED
    streams = [x for x in sdk.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 0), 0)
               if x.get_type() == "VIDEO_STREAM_INFORMATION"]
    assert [s.stream_id for s in streams] == [1, 2] and {s.count for s in streams} == {2}
    assert streams[0].flags & m.VIDEO_STREAM_STATUS_FLAGS_THERMAL and streams[0].flags & m.VIDEO_STREAM_STATUS_FLAGS_RUNNING
    assert streams[0].uri.startswith("rtsp://")


def test_reset_and_format_and_trigger(pro, gcs):
    pro.handle(gcs.cmd(m.MAV_CMD_USER_1, 1, NAN, 99), 0)
    pro.handle(gcs.cmd(m.MAV_CMD_RESET_CAMERA_SETTINGS, 0), 0)
    assert pro.value("range_max_c") == 99
    pro.handle(gcs.cmd(m.MAV_CMD_RESET_CAMERA_SETTINGS, 1), 0)
    assert pro.values == {s.param: s.default for s in catalogue().get("wiris-pro").settings}
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_STORAGE_FORMAT, 5, 1), 0), m.MAV_CMD_STORAGE_FORMAT) == DENIED
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_DO_TRIGGER_CONTROL, 0), 0), m.MAV_CMD_DO_TRIGGER_CONTROL) == ACCEPTED
    assert pro.trigger_enabled is False
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_DO_TRIGGER_CONTROL, 2), 0), m.MAV_CMD_DO_TRIGGER_CONTROL) == DENIED


def test_wiris_state_refuses_a_rededge():
    with pytest.raises(ValueError):
        WirisState(catalogue().get("rededge-mx"), parse_definition(definition_xml(catalogue().get("wiris-pro"))))


@pytest.mark.parametrize("data,where,message,hint", [
    (b" " * (4 * 1024 * 1024 + 1), "d.xml", "the limit is 4194304", "at most 4 MiB"),
    (b"\xfd7zXZ\x00" + b"\0" * 20, "d.xml", "broken xz stream", ".xml.xz"),
    (b"<parameters/>", "d.xml", "root element is <parameters>, not <mavlinkcamera>", "not a camera definition"),
    (b"<mavlinkcamera>\n<definition>", "d.xml:2", "", "broken definition"),
], ids=["too-large", "broken-xz", "other-root", "unclosed"])
def test_a_definition_that_cannot_be_read_says_where_and_what_to_do(data, where, message, hint):
    from cdf.errors import CdfError

    with pytest.raises(CdfError) as err:
        parse_definition(data, "d.xml")
    assert message in err.value.message and err.value.where == where and hint in err.value.hint


def test_the_emulator_refuses_a_definition_that_is_not_one_before_it_opens_anything():
    from cdf.errors import CdfError
    from wiris_tools.emulate.runner import start_emulator

    with pytest.raises(CdfError, match="root element is <camera>") as err:
        start_emulator("wiris-pro", "udpin:127.0.0.1:0", definition=b"<camera/>")
    assert err.value.where == "wiris-pro" and "check which file" in err.value.hint


def test_infinite_storage_id_is_denied_not_a_crash(pro, gcs):
    """Found by the fuzzer: REQUEST_MESSAGE(STORAGE_INFORMATION, inf) raised OverflowError."""
    out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_STORAGE_INFORMATION, math.inf), 0)
    assert ack_of(out, m.MAV_CMD_REQUEST_MESSAGE) == DENIED


@pytest.mark.parametrize("bad", [NAN, math.inf, -math.inf])
def test_param_ext_set_refuses_non_finite_floats_and_every_command_is_still_answered(pro, gcs, bad):
    """A REAL32 PARAM_EXT_SET of NaN or an infinity was ACCEPTED and stored; the next relative zoom
    (DO_DIGICAM_CONTROL param 3) then raised ValueError and the sender got no COMMAND_ACK at all."""
    floats = [p for p in pro.definition.params if p.type == "float"]
    assert {"CAM_ZOOM", "EMISSIVITY", "RANGE_MAX_C"} <= {p.name for p in floats}
    before = dict(pro.values)
    for p in floats:
        out = pro.handle(gcs(gcs.mav.param_ext_set_encode(1, 100, p.name.encode(), paramext.encode(bad, "float"),
                                                          m.MAV_PARAM_EXT_TYPE_REAL32)), 0)
        ack = only(out, "PARAM_EXT_ACK")
        assert ack.param_result == m.PARAM_ACK_VALUE_UNSUPPORTED, p.name
        # the ACK carries the value the camera keeps
        assert paramext.decode(paramext.raw_value(ack), "float") == pytest.approx(before[p.name]), p.name
    assert pro.values == before
    out = pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, 2), 0)
    assert ack_of(out, m.MAV_CMD_DO_DIGICAM_CONTROL) == ACCEPTED and pro.value("zoom") == pytest.approx(1.2)
    settings = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_CAMERA_SETTINGS, 1), 0), "CAMERA_SETTINGS")
    assert math.isfinite(settings.zoomLevel)
    assert pro.faults == 0


def test_a_command_that_trips_over_a_stored_value_is_still_acknowledged(pro, gcs):
    """Whatever ends up stored (here forced past the PARAM_EXT check), every command gets its COMMAND_ACK."""
    pro.values["CAM_ZOOM"] = NAN
    out = pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, NAN, 2), 0)
    assert ack_of(out, m.MAV_CMD_DO_DIGICAM_CONTROL) == ACCEPTED and pro.value("zoom") == pytest.approx(1.2)
    pro.values["STORAGE"] = "ssd"          # a value of the wrong kind: the capture raises inside the emulator
    out = pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1), 0)
    assert ack_of(out, m.MAV_CMD_IMAGE_START_CAPTURE) == m.MAV_RESULT_FAILED and pro.faults == 1


def _captured(out):
    return [x.image_index for x in out if x.get_type() == "CAMERA_IMAGE_CAPTURED"]


def test_image_captured_is_requested_by_image_index_even_after_the_history_is_trimmed(pro, gcs):
    """REQUEST_MESSAGE(CAMERA_IMAGE_CAPTURED) param2 is the image_index (common.xml); it was read as a place in
    the history, which keeps the last 1000 images: after 1005 images, index 0 answered with image 5."""
    for i in range(1005):
        pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1), i)

    def ask(*params):
        out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_IMAGE_CAPTURED, *params), 2000)
        return ack_of(out, m.MAV_CMD_REQUEST_MESSAGE), _captured(out)

    assert ask(5) == (ACCEPTED, [5])
    assert ask(1004) == (ACCEPTED, [1004])
    assert ask(1004, NAN) == (ACCEPTED, [1004])                    # param3 unused (a WIRIS-style sender's NaN)
    assert ask(0) == (m.MAV_RESULT_FAILED, [])                     # given out, no longer held
    assert ask(1005) == (DENIED, []) and ask(-2) == (DENIED, []) and ask(2.5) == (DENIED, [])
    result, every = ask(-1)                                        # -1: all it still holds
    assert result == ACCEPTED and every == list(range(5, 1005))
    assert ask(1000, -1) == (ACCEPTED, [1000, 1001, 1002, 1003, 1004])   # param3 -1: that one and all after
    assert ask(3, 6) == (ACCEPTED, [5, 6])                               # param3: the last of a range
    assert ask(6, 3)[0] == DENIED


def test_image_captured_after_a_counter_reset(pro, gcs):
    for i in range(3):
        pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1), i)
    pro.handle(gcs.cmd(m.MAV_CMD_STORAGE_FORMAT, 0, 0, 1), 3)           # reset the image counter
    assert ack_of(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_IMAGE_CAPTURED, 0), 4),
                  m.MAV_CMD_REQUEST_MESSAGE) == DENIED                  # index 0 is not given out again yet
    out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_IMAGE_CAPTURED, -1), 4)
    assert ack_of(out, m.MAV_CMD_REQUEST_MESSAGE) == ACCEPTED and _captured(out) == []


@pytest.mark.parametrize("zoom_x,level", [(1.0, 0.0), (5.5, 50.0), (10.0, 100.0)])
def test_zoom_level_is_a_percentage_of_the_range(pro, gcs, zoom_x, level):
    """common.xml CAMERA_SETTINGS.zoomLevel: "percentage of the full range (0.0 to 100.0)"; §6.4.2 prints the
    zoom factor 1-10, which a standard reader (QGC's, MAVSDK's slider) would take for 1-10 %."""
    pro.handle(gcs.cmd(m.MAV_CMD_DO_DIGICAM_CONTROL, NAN, zoom_x), 0)
    s = only(pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_MESSAGE, m.MAVLINK_MSG_ID_CAMERA_SETTINGS), 0), "CAMERA_SETTINGS")
    assert s.zoomLevel == pytest.approx(level)


@pytest.mark.parametrize("model", WORKSWELL)
def test_basic_zoom_flag_means_set_camera_zoom_works(model, gcs):
    """CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM is "basic zoom control (MAV_CMD_SET_CAMERA_ZOOM)" (common.xml), and the
    camera advertised it while answering that command UNSUPPORTED (ArduPilot sends it when the flag is set).
    ZOOM_TYPE_RANGE and ZOOM_TYPE_STEP map onto §6.3.2.2's zoom; success is answered with CAMERA_SETTINGS."""
    cam_t = catalogue().get(model)
    assert "CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM" in cam_t.capabilities
    cam = new_wiris(cam_t)
    zoom = cam_t.setting("zoom")
    out = cam.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_ZOOM, m.ZOOM_TYPE_RANGE, 50), 0)
    assert ack_of(out, m.MAV_CMD_SET_CAMERA_ZOOM) == ACCEPTED
    assert types(out) == ["COMMAND_ACK", "CAMERA_SETTINGS"] and out[1].zoomLevel == pytest.approx(50.0)
    assert cam.value("zoom") == pytest.approx((zoom.min + zoom.max) / 2)
    cam.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_ZOOM, m.ZOOM_TYPE_RANGE, 33), 0)      # the closest zoom step
    assert cam.value("zoom") == pytest.approx(round(zoom.min + 0.33 * (zoom.max - zoom.min), 1))
    before = cam.value("zoom")
    assert ack_of(cam.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_ZOOM, m.ZOOM_TYPE_STEP, 1), 0),
                  m.MAV_CMD_SET_CAMERA_ZOOM) == ACCEPTED
    assert cam.value("zoom") == pytest.approx(before + zoom.step)
    cam.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_ZOOM, m.ZOOM_TYPE_STEP, -1000), 0)    # goes no wider than the widest
    assert cam.value("zoom") == zoom.min
    for bad in ([m.ZOOM_TYPE_RANGE, 101], [m.ZOOM_TYPE_RANGE, -1], [m.ZOOM_TYPE_RANGE, NAN], [m.ZOOM_TYPE_STEP, 0.5],
                [m.ZOOM_TYPE_CONTINUOUS, 1], [m.ZOOM_TYPE_FOCAL_LENGTH, 20], [NAN, 50]):
        out = cam.handle(gcs.cmd(m.MAV_CMD_SET_CAMERA_ZOOM, *bad), 0)
        assert types(out) == ["COMMAND_ACK"] and out[0].result == DENIED, bad
    assert cam.value("zoom") == zoom.min


def test_video_start_with_stream_id_0_keeps_the_video_id(pro, gcs):
    """common.xml VIDEO_START_CAPTURE param1: "Video Stream ID (0 for all streams)", which ArduPilot's
    MAVLinkCamV2 always sends; §6.3.2.9 reads param1 as Video ID flags and gives 0 no meaning. It was DENIED,
    so no standard sender could record; 0 now keeps the current Video ID, like NaN."""
    pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_CAPTURE, 4), 0)                  # visible encoded
    pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_STOP_CAPTURE), 1)
    out = pro.handle(gcs.cmd(m.MAV_CMD_VIDEO_START_CAPTURE, 0, 0, 0, NAN, 0, 0, NAN), 2)   # common.xml defaults
    assert ack_of(out, m.MAV_CMD_VIDEO_START_CAPTURE) == ACCEPTED
    assert pro.video_recording and pro.value("video") == 4


def test_storage_format_reports_the_formatted_storage(pro, gcs):
    """common.xml STORAGE_FORMAT: "Once format is complete, a STORAGE_INFORMATION message is sent"."""
    pro.handle(gcs.cmd(m.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 0, NAN, 2), 0)     # one image on the USB drive
    assert pro.used_mib[1] > 0
    out = pro.handle(gcs.cmd(m.MAV_CMD_STORAGE_FORMAT, 1, 1, 0), 1)
    assert types(out) == ["COMMAND_ACK", "STORAGE_INFORMATION"] and out[0].result == ACCEPTED
    info = out[1]
    assert info.storage_id == 1 and info.used_capacity == 0 and info.available_capacity == info.total_capacity
    # resetting the image counter alone formats nothing, so nothing is reported
    assert types(pro.handle(gcs.cmd(m.MAV_CMD_STORAGE_FORMAT, 1, 0, 1), 2)) == ["COMMAND_ACK"]


def test_storage_information_type_is_common_xml_storage_type(pro, gcs):
    """§6.4.3 fills `type` with the Storage ID (0 SSD, 1 USB, 2 microSD); read as common.xml's STORAGE_TYPE those
    say unknown, USB stick and SD card. The standard's types are sent; storage_id keeps the manual's 0-based
    Storage ID, which its requests use too."""
    out = pro.handle(gcs.cmd(m.MAV_CMD_REQUEST_STORAGE_INFORMATION), 0)
    infos = [x for x in out if x.get_type() == "STORAGE_INFORMATION"]
    assert [(i.storage_id, i.type) for i in infos] == [
        (0, m.STORAGE_TYPE_HD), (1, m.STORAGE_TYPE_USB_STICK), (2, m.STORAGE_TYPE_MICROSD)]
