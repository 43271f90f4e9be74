"""The emulators never crash on garbage: random bytes, truncated frames, wrong CRCs, messages to other
components, NaN/inf/out-of-range params, floods — through the pure handlers (hypothesis), and once over UDP."""

from __future__ import annotations

import math
import random
import socket
import struct
import time

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from pymavlink.dialects.v20 import ardupilotmega as m

from cdf.catalogue import catalogue
from emu_wire import Wire
from wiris_tools import paramext
from wiris_tools.emulate.rededge import RedEdgeState
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.emulate.wiris import new_wiris
from wiris_tools.link import Link

PRO = new_wiris(catalogue().get("wiris-pro"))          # parsed once; each example copies its config
MX = catalogue().get("rededge-mx")
COMMANDS = sorted({getattr(m, name) for name, _ in catalogue().get("wiris-pro").commands}
                  | {m.MAV_CMD_DO_SET_MODE, m.MAV_CMD_USER_4, 0, 65535})
floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=32), st.sampled_from(
    [math.nan, 0.0, -1.0, 1.0, 2.0, 259.0, 261.0, 263.0, 269.0, 1e9, -1e9]))


def _fresh_wiris():
    return new_wiris(catalogue().get("wiris-pro"), PRO.config, definition_bytes=None)


def _parse(data: bytes):
    parser = m.MAVLink(None)
    parser.robust_parsing = True
    try:
        return parser.parse_buffer(data) or []
    except Exception:
        return []


def _feed(state, msgs, now=0.0):
    out = []
    for msg in msgs:
        out += state.handle(msg, now)
        now += 0.01
        out += state.tick(now)
    for o in out:                       # everything the camera says must pack onto the wire
        o.pack(m.MAVLink(None, 1, 100))
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cmd=st.sampled_from(COMMANDS), params=st.lists(floats, min_size=7, max_size=7),
       target=st.sampled_from([0, 100, 101, 1, 255]))
def test_wiris_commands_with_any_params(cmd, params, target):
    state = _fresh_wiris()
    g = Wire()
    out = _feed(state, [g.cmd(cmd, *params, target_component=target)])
    acks = [o for o in out if o.get_type() == "COMMAND_ACK"]
    if target in (0, 100):
        assert len(acks) == 1 and acks[0].command == cmd     # always exactly one answer
        assert acks[0].result in (m.MAV_RESULT_ACCEPTED, m.MAV_RESULT_DENIED, m.MAV_RESULT_UNSUPPORTED)
    else:
        assert acks == []                                    # §3.2: not for us, ignored
    for name, value in state.values.items():                 # nothing outside the catalogue's ranges
        s = state._by_param.get(name)
        if s is not None and value is not None and s.min is not None:
            assert s.min <= value <= s.max, name


@settings(max_examples=100, deadline=None)
@given(name=st.sampled_from(["LAYOUT", "EMISSIVITY", "CAM_ZOOM", "CAPTURE_FMT", "CAM_EV", "", "X" * 16]),
       raw=st.one_of(st.binary(max_size=128),   # and NaN / infinities as REAL32 and REAL64 bytes
                     st.sampled_from([struct.pack(f, v) for f in ("<f", "<d")
                                      for v in (math.nan, math.inf, -math.inf)])),
       ptype=st.one_of(st.integers(0, 12), st.just(m.MAV_PARAM_EXT_TYPE_REAL32)))
@example(name="CAM_ZOOM", raw=struct.pack("<f", math.nan), ptype=m.MAV_PARAM_EXT_TYPE_REAL32)
@example(name="EMISSIVITY", raw=struct.pack("<f", -math.inf), ptype=m.MAV_PARAM_EXT_TYPE_REAL32)
def test_wiris_param_ext_set_with_any_bytes(name, raw, ptype):
    state = _fresh_wiris()
    g = Wire()
    out = _feed(state, [g(g.mav.param_ext_set_encode(1, 100, name.encode(), raw.ljust(128, b"\0"), ptype))])
    assert [o.get_type() for o in out if o.get_type() != "HEARTBEAT"] == ["PARAM_EXT_ACK"]
    assert all(v is None or math.isfinite(v) for v in state.values.values())    # NaN/inf bytes are refused


@settings(max_examples=200, deadline=None)
@given(data=st.binary(max_size=600))
def test_random_bytes_never_crash_either_emulator(data):
    msgs = _parse(data)
    _feed(_fresh_wiris(), msgs)
    _feed(RedEdgeState(MX), msgs)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), cut=st.integers(0, 60), flip=st.integers(0, 60))
def test_truncated_and_corrupted_frames(seed, cut, flip):
    rng = random.Random(seed)
    g = Wire()
    frames = [g.cmd(rng.choice(COMMANDS), *[rng.choice([math.nan, 0, 1, 2, 300]) for _ in range(7)]).get_msgbuf(),
              g.mav.param_ext_set_encode(1, 100, b"LAYOUT", b"\x01", 5).pack(g.mav),
              g.mav.digicam_control_encode(1, 100, 1, 1, 0, 0, 1, 0, 0, 0).pack(g.mav)]
    stream = bytearray()
    for f in frames:
        f = bytearray(f)
        if flip < len(f):
            f[flip] ^= 0xFF                 # a wrong byte: the CRC no longer matches
        stream += f[:max(1, len(f) - cut)]
    _feed(_fresh_wiris(), _parse(bytes(stream)))
    _feed(RedEdgeState(MX), _parse(bytes(stream)))


@settings(max_examples=60, deadline=None)
@given(lat=st.integers(-2**31, 2**31 - 1), lon=st.integers(-2**31, 2**31 - 1), alt=st.integers(-2**31, 2**31 - 1),
       roll=floats, shot=st.integers(0, 255), comp=st.sampled_from([0, 100, 7]))
def test_rededge_state_messages_with_extreme_values(lat, lon, alt, roll, shot, comp):
    g = Wire(system=3, component=1, mavlink1=True)
    cam = RedEdgeState(MX)
    for key, value in (("autoCapMode", 2), ("operatingAlt", 0), ("opAltTolerance", 1000)):
        cam.handle(g(g.mav.param_set_encode(3, 100, key.encode(), paramext.encode_classic(value, "uint32"),
                                            m.MAV_PARAM_TYPE_UINT32)), 0)
    assert cam._auto_mode() == "overlap" and cam.values["opAltTolerance"] == 1000
    msgs = [g(g.mav.global_position_int_encode(0, lat, lon, alt, 0, 0, 0, 0, 0)),
            g(g.mav.gps_raw_int_encode(2**63, 3, lat, lon, alt, 0, 0, 0, 0, 0)),
            g(g.mav.attitude_encode(0, roll, roll, roll, 0, 0, 0)),
            g(g.mav.mount_status_encode(0, comp, lat, lon, alt)),
            g(g.mav.digicam_control_encode(3, comp, 0, 0, 0, 0, shot, 0, 0, roll)),
            g(g.mav.param_set_encode(3, comp, b"timerPeriod", roll, m.MAV_PARAM_TYPE_REAL32)),
            g(g.mav.param_set_encode(3, comp, b"operatingAlt", roll, m.MAV_PARAM_TYPE_REAL32))]   # any 4 bytes
    _feed(cam, msgs)


def test_flood_over_udp_keeps_the_emulator_answering():
    """Thousands of junk datagrams and foreign messages over a real socket; then it still answers."""
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0") as emu:
        port = emu.link.local_port
        rng = random.Random(1)
        g = Wire()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for i in range(3000):
                kind = i % 4
                if kind == 0 and i % 8:
                    data = rng.randbytes(rng.randint(1, 300))
                elif kind == 0:
                    data = g.cmd(m.MAV_CMD_USER_2, 1, 2, 3).get_msgbuf()[:-rng.randint(1, 20)]   # truncated
                elif kind == 1:
                    data = g.cmd(rng.choice(COMMANDS), *[rng.choice([math.nan, math.inf, -1, 0, 1, 1e30])
                                                         for _ in range(7)]).get_msgbuf()
                elif kind == 2:
                    data = g.cmd(m.MAV_CMD_USER_1, 1, target_component=101).get_msgbuf()     # someone else's
                else:
                    data = g.mav.param_ext_request_list_encode(1, 100).pack(g.mav)
                s.sendto(bytes(data), ("127.0.0.1", port))
        time.sleep(0.5)
        with Link(f"udpout:127.0.0.1:{port}", heartbeat_s=0.2) as link:
            link.wait_heartbeat(timeout=5, component=100)
            ack = link.command_long(1, 100, m.MAV_CMD_REQUEST_CAMERA_INFORMATION, [1], timeout=1.0, retries=5)
            assert ack.result == m.MAV_RESULT_ACCEPTED
        assert emu.errors == 0
        with emu.lock:
            assert emu.state.ignored > 0            # the messages to component 101 were ignored


SETTING_COMMANDS = sorted({getattr(m, s.command.cmd) for s in catalogue().get("wiris-pro").settings
                           if s.command is not None and s.command.cmd} | {m.MAV_CMD_SET_CAMERA_ZOOM})
PARAMS = [p.name for p in PRO.definition.params]
action = st.one_of(
    st.tuples(st.just("cmd"), st.sampled_from(SETTING_COMMANDS), st.lists(floats, min_size=7, max_size=7)),
    # NaN and the infinities as PARAM_EXT values: a stored NaN zoom once left DIGICAM_CONTROL unanswered
    st.tuples(st.just("set"), st.sampled_from(PARAMS),
              st.one_of(st.sampled_from([math.nan, math.inf, -math.inf]), st.floats(-2000, 2000, width=32))))


@settings(max_examples=80, deadline=None)
@given(actions=st.lists(action, min_size=1, max_size=25))
@example(actions=[("set", "CAM_ZOOM", math.nan),                       # the reviewer's: then a relative zoom
                  ("cmd", m.MAV_CMD_DO_DIGICAM_CONTROL, [math.nan, math.nan, 2.0] + [math.nan] * 4)])
def test_commands_and_param_ext_share_one_consistent_state(actions):
    """Any sequence of setting commands and PARAM_EXT sets: a refusal changes nothing, every value stays
    allowed, and PARAM_EXT reads back exactly what the commands report."""
    from wiris_tools import paramext

    state = _fresh_wiris()
    g = Wire()
    for kind, what, value in actions:
        before = dict(state.values)
        if kind == "cmd":
            out = state.handle(g.cmd(what, *value), 0.0)
            acks = [o for o in out if o.get_type() == "COMMAND_ACK"]
            assert len(acks) == 1, (what, value)                 # every command is answered, once
            refused = acks[0].result != m.MAV_RESULT_ACCEPTED
        else:
            p = state.definition.param(what)
            if p.integer and not math.isfinite(value):
                continue                                         # an integer type cannot carry it
            v = int(value) if p.integer else value
            try:
                raw = paramext.encode(v, p.type)
            except paramext.WireValueError:
                continue
            out = state.handle(g(g.mav.param_ext_set_encode(1, 100, what.encode(), raw,
                                                            paramext.wire_type(p.type).ext_type)), 0.0)
            refused = out[0].param_result != m.PARAM_ACK_ACCEPTED
        if refused:
            assert state.values == before
        assert state.faults == 0
        for s in state.camera.settings:
            v = state.values.get(s.param)
            if v is None:
                continue
            if s.options:
                assert any(o.value == v for o in s.options), s.param
            elif s.min is not None:
                assert s.min <= v <= s.max, (s.param, v)
            else:
                assert math.isfinite(v), (s.param, v)
    listed = state.handle(g(g.mav.param_ext_request_list_encode(1, 100)), 0.0)
    for msg, p in zip(listed, state.definition.params):
        assert paramext.decode(paramext.raw_value(msg), p.type) == pytest.approx(state.values[p.name],
                                                                                               rel=1e-6, abs=1e-6)
    z = state.camera.setting("zoom")                        # zoomLevel: % of the zoom range (common.xml)
    assert state.camera_settings(0.0).zoomLevel == pytest.approx(
        100 * (state.value("zoom") - z.min) / (z.max - z.min), rel=1e-5, abs=1e-3)
