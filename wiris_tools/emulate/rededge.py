"""A MicaSense RedEdge on its serial API (shared/seeds/micasense-rededge-serial-api.txt), as pure logic.

`RedEdgeState.handle(msg, now)` / `tick(now)` return the messages to send, like wiris.WirisState. The runner
sends them as MAVLink 1 frames (the API: "RedEdge uses Mavlink v1.0 messages") from component 100, with
`system_id` as the header's system id: the camera adopts the system id of whatever it hears (catalogue
`adopts_sender_system_id`; 255 until then).

What the API says, and how it is emulated:
- HEARTBEAT about once a second with the API's fixed field values (catalogue `heartbeat`: type 0, autopilot 1,
  base mode 2, custom mode 3, system status 4) — not MAV_TYPE_CAMERA, so camera-v2 ground stations and
  ArduPilot's MAVLinkCamV2 backend do not discover it;
- MAVLink 1 only (catalogue `link`): MAVLink 2 frames are ignored, as a real RedEdge drops them;
- PING with target 0/0 is answered with the same sequence number, addressed to the sender;
- state: GPS_RAW_INT (fix > 2 is a fix; its time sets UTC), or SYSTEM_TIME + GLOBAL_POSITION_INT; ATTITUDE;
  MOUNT_STATUS. Serial state is used for 5 s after it arrived (no internal GPS is emulated: after that the
  position is unknown, 0);
- DIGICAM_CONFIGURE (154): mode 1 auto, 4 manual (others no effect); in a manual-mode message the shutter
  divisor and ISO gain (1, 2, 4, 8 for ISO 100–800) apply to sensor `extra_param` (0–4) or all (255). (The
  values are the API page's <li value="...">; the seed text's flattened lists renumber them 1, 2, 3, ...);
- DIGICAM_CONTROL (155): shot 1 flight capture, 2 panel capture, anything else no capture; a commanded
  capture answers CAMERA_STATUS (TRIGGER) and CAMERA_FEEDBACK (CLOSEDLOOP) with position and attitude;
- classic PARAM_REQUEST_LIST / PARAM_REQUEST_READ / PARAM_SET -> PARAM_VALUE for the catalogue's PARAM_SET
  parameters, each of its own MAV_PARAM_TYPE (REAL32, UINT32, INT32). The 4-byte value is read "as a union",
  as the parameter's type whatever type the sender names, so an integer sent as a float (2.0 for
  autoCapMode) is a huge number. A value outside the parameter's options or range is not applied and
  PARAM_VALUE reports the unchanged value (the classic protocol's refusal);
- anything whose target_component is not 100 or 0 is ignored; COMMAND_LONG is not part of the API and gets
  no answer (so MAV_CMD_DO_DIGICAM_CONTROL from an autopilot does not trigger it).
- auto-capture, only while the height above the ground estimate is at least operatingAlt − opAltTolerance
  ("distance, in meters, below the operating altitude to enable automatic capture modes"; no upper limit):
  timer mode (autoCapMode 1) every timerPeriod (at least 1 s: "below 1 s it captures as fast as it can,
  about 1 Hz"); overlap mode (2) from position updates: a capture each time the camera moved the along-track
  footprint × (1 − overlapAlongTrk) since the last one. Auto captures send no MAVLink message (the API
  reports only MAVLink-commanded captures); they are counted in `auto_captures`.

Approximations (the API does not specify them): the ground level is the altitude of the first position fix
(CAMERA_FEEDBACK.alt_rel is "above estimated ground level"); the camera's earth-frame roll/pitch/yaw are the
vehicle's plus the mount's angles (exact when either is zero); the footprint takes the camera's top towards
the vehicle's front (the API's zero mount orientation), so the along-track side is the sensor height.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.catalogue import Camera, Setting
from cdf.errors import CdfError
from missions.geometry.geo import great_circle_m
from wiris_tools import paramext

Message = Any

HEARTBEAT_S = 1.0
STATE_VALID_S = 5.0          # "override ... for 5 seconds since the last state message was received"
DEFAULT_SYSTEM_ID = 255      # "defaults to 255 otherwise"
ALL_SENSORS = 255            # DIGICAM_CONFIGURE extra_param: "Set to 255 for all"
MIN_TIMER_S = 1.0
UINT64_MAX = 2**64 - 1
MAVLINK2_MAGIC = bytes([mavlink2.PROTOCOL_MARKER_V2])


@dataclass
class Exposure:
    shutter_divisor: int
    iso: int


@dataclass(frozen=True)
class Feedback:
    index: int
    time_usec: int
    lat: int
    lon: int
    alt_msl_m: float
    alt_rel_m: float
    roll: float
    pitch: float
    yaw: float
    panel: bool


class RedEdgeState:
    def __init__(self, camera: Camera, *, now: float = 0.0, utc_offset_s: float = 0.0) -> None:
        if camera.protocol != "rededge-serial":
            raise ValueError(f"{camera.id} is not a RedEdge serial-API camera")
        extra = dict(camera.extra)
        self.camera = camera
        self.component = camera.default_component_id
        self.heartbeat_fields = dict(extra.get("heartbeat") or {})
        self.adopts = bool(extra.get("adopts_sender_system_id", False))
        self.mavlink1_only = camera.mavlink_version == 1
        self.system_id = DEFAULT_SYSTEM_ID
        self.mav = mavlink2.MAVLink(None, srcSystem=self.system_id, srcComponent=self.component)
        self.params: tuple[Setting, ...] = tuple(s for s in camera.settings
                                                 if s.command is not None and s.command.message == "PARAM_SET")
        self.values: dict[str, float | int] = {s.param: s.check(s.default) for s in self.params
                                               if s.default is not None}
        imager = camera.imagers[0] if camera.imagers else None
        self.bands = int(imager.bands or 1) if imager else 1
        self.focal_mm = float(imager.lenses_mm[0]) if imager and imager.lenses_mm else 0.0
        self.sensor_mm = imager.sensor_size_mm if imager else None
        modes = camera.setting("exposure_mode")
        self.auto_mode, self.manual_mode = ((modes.option_by_key("auto").value, modes.option_by_key("manual").value)
                                            if modes is not None else (1, 4))
        self.exposure_mode = self._default("exposure_mode", self.auto_mode)
        shutter = self._default("shutter_divisor", 1000)
        iso = self._default("iso", 1)
        self.exposures = [Exposure(shutter, iso) for _ in range(self.bands)]
        self.boot = now
        self.utc_offset_s = utc_offset_s
        self.utc_base: tuple[float, float] | None = None    # (UTC seconds, at `now`) from GPS or SYSTEM_TIME
        self.pos: tuple[int, int, int] | None = None        # lat, lon (degE7), alt MSL (mm)
        self.pos_time = -math.inf
        self.fix = False
        self.ground_mm: int | None = None
        self.attitude: tuple[float, float, float] | None = None   # roll, pitch, yaw (rad)
        self.att_time = -math.inf
        self.mount: tuple[float, float, float] | None = None      # pitch, roll, yaw (deg)
        self.mount_time = -math.inf
        self.satellites = 0
        self.capture_count = 0
        self.feedback: list[Feedback] = []
        self.auto_captures: list[tuple[float, int, int]] = []    # (time, lat, lon)
        self._last_auto_pos: tuple[int, int] | None = None
        self._next_timer = now
        self._next_heartbeat = now
        self.ignored = 0

    def _default(self, key: str, fallback: int) -> int:
        s = self.camera.setting(key)
        return int(s.default) if s is not None and s.default is not None else fallback

    # -- entry points --------------------------------------------------------------------------
    def tick(self, now: float) -> list[Message]:
        out = []
        if now >= self._next_heartbeat:
            hb = self.heartbeat_fields
            out.append(self.mav.heartbeat_encode(int(hb.get("type", 0)), int(hb.get("autopilot", 0)),
                                                 int(hb.get("base_mode", 0)), int(hb.get("custom_mode", 0)),
                                                 int(hb.get("system_status", 0))))
            self._next_heartbeat = now + HEARTBEAT_S
        if self._auto_mode() == "timer" and now >= self._next_timer:
            if self._high_enough(self._height_m()):
                self._auto_capture(now)
            self._next_timer = now + max(MIN_TIMER_S, self.values.get("timerPeriod", 2.0))
        return out

    def handle(self, msg: Message, now: float) -> list[Message]:
        mtype = msg.get_type()
        if mtype == "BAD_DATA" or mtype.startswith("UNKNOWN"):
            return []
        if self.mavlink1_only and bytes(msg.get_msgbuf()[:1]) == MAVLINK2_MAGIC:
            self.ignored += 1     # "RedEdge uses Mavlink v1.0 messages": a MAVLink 2 frame is not read
            return []
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        if sender == (self.system_id, self.component):
            return []
        if self.adopts and 0 < sender[0] and sender[0] != self.system_id:
            self.system_id = sender[0]
            self.mav.srcSystem = sender[0]
        target = getattr(msg, "target_component", None)
        if target is not None and target not in (mavlink2.MAV_COMP_ID_ALL, self.component):
            self.ignored += 1
            return []
        handler = getattr(self, "_on_" + mtype.lower(), None)
        if handler is None:
            return []     # COMMAND_LONG and everything else the API does not list
        return handler(msg, now) or []

    # -- state messages ------------------------------------------------------------------------
    def _on_ping(self, msg, now):
        if msg.target_system != 0 or msg.target_component != 0:
            return []     # a ping response, not a request
        return [self.mav.ping_encode(msg.time_usec, msg.seq, msg.get_srcSystem(), msg.get_srcComponent())]

    def _on_gps_raw_int(self, msg, now):
        if msg.time_usec > 0:
            self.utc_base = (msg.time_usec / 1e6, now)
        self.fix = msg.fix_type >= mavlink2.GPS_FIX_TYPE_3D_FIX
        if self.fix:
            self._position(msg.lat, msg.lon, msg.alt, now)
        return []

    def _on_system_time(self, msg, now):
        if msg.time_unix_usec > 0:
            self.utc_base = (msg.time_unix_usec / 1e6, now)
        return []

    def _on_global_position_int(self, msg, now):
        self.fix = True    # "sending it will imply a 3D GPS fix"
        self._position(msg.lat, msg.lon, msg.alt, now)
        return []

    def _on_attitude(self, msg, now):
        self.attitude = (msg.roll, msg.pitch, msg.yaw)
        self.att_time = now
        return []

    def _on_mount_status(self, msg, now):
        self.mount = (msg.pointing_a / 100.0, msg.pointing_b / 100.0, msg.pointing_c / 100.0)
        self.mount_time = now
        return []

    def _on_gps_status(self, msg, now):
        self.satellites = msg.satellites_visible
        return []

    def _position(self, lat: int, lon: int, alt_mm: int, now: float) -> None:
        self.pos = (lat, lon, alt_mm)
        self.pos_time = now
        if self.ground_mm is None:
            self.ground_mm = alt_mm
        if self._auto_mode() == "overlap":
            self._overlap_check(now)

    # -- capture -------------------------------------------------------------------------------
    def _auto_mode(self) -> str | None:
        s = self.camera.setting("auto_capture")
        if s is None or s.enum is None:
            return None
        option = s.enum.by_value(int(self.values.get(s.param, 0)))
        return option.key if option else None

    def _valid(self, stamp: float, now: float) -> bool:
        return now - stamp <= STATE_VALID_S

    def _utc_us(self, now: float) -> int:
        if self.utc_base is not None:
            utc, at = self.utc_base
            t = int((utc + now - at) * 1e6)
        else:
            t = int((now + self.utc_offset_s) * 1e6)
        return min(max(t, 0), UINT64_MAX)   # a GPS time near the end of uint64 must not break the answer

    def _height_m(self) -> float | None:
        if self.pos is None or self.ground_mm is None:
            return None
        return (self.pos[2] - self.ground_mm) / 1000.0

    def _high_enough(self, height: float | None) -> bool:
        """Whether the automatic capture modes are enabled at `height` (self._height_m()): at most
        opAltTolerance below operatingAlt."""
        target = self.values.get("operatingAlt")
        return height is not None and target is not None and \
            height >= target - self.values.get("opAltTolerance", 0)

    def _overlap_check(self, now: float) -> None:
        height = self._height_m()
        if not self._high_enough(height) or not self.sensor_mm or not self.focal_mm:
            return
        lat, lon = self.pos[0], self.pos[1]
        if self._last_auto_pos is None:
            self._auto_capture(now)
            return
        along_m = height * self.sensor_mm[1] / self.focal_mm
        spacing = along_m * (1.0 - self.values.get("overlapAlongTrk", 75.0) / 100.0)
        last = self._last_auto_pos
        if great_circle_m(last[0] / 1e7, last[1] / 1e7, lat / 1e7, lon / 1e7) >= spacing:
            self._auto_capture(now)

    def _auto_capture(self, now: float) -> None:
        lat, lon = (self.pos[0], self.pos[1]) if self.pos and self._valid(self.pos_time, now) else (0, 0)
        self.auto_captures.append((now, lat, lon))
        del self.auto_captures[:-10000]
        self._last_auto_pos = (lat, lon)

    def _on_digicam_configure(self, msg, now):
        if msg.mode == self.auto_mode:
            self.exposure_mode = self.auto_mode
        elif msg.mode == self.manual_mode:
            self.exposure_mode = self.manual_mode
            sensors = range(self.bands) if msg.extra_param == ALL_SENSORS else (
                [msg.extra_param] if msg.extra_param < self.bands else [])
            iso_setting = self.camera.setting("iso")
            iso_ok = iso_setting is None or iso_setting.enum is None or iso_setting.enum.by_value(msg.iso) is not None
            for i in sensors:
                if msg.shutter_speed >= 1:
                    self.exposures[i].shutter_divisor = int(msg.shutter_speed)
                if iso_ok:
                    self.exposures[i].iso = int(msg.iso)
        return []   # the API documents no answer

    def _on_digicam_control(self, msg, now):
        if msg.shot not in (1, 2):
            return []
        self.capture_count += 1
        index = self.capture_count & 0xFFFF   # Image Index is uint16: it wraps
        valid_pos = self.pos is not None and self.fix and self._valid(self.pos_time, now)
        lat, lon, alt_mm = self.pos if valid_pos else (0, 0, 0)
        height = self._height_m() if valid_pos else 0.0
        roll = pitch = yaw = 0.0
        if self.attitude is not None and self._valid(self.att_time, now):
            roll, pitch, yaw = (math.degrees(a) for a in self.attitude)
        if self.mount is not None and self._valid(self.mount_time, now):
            pitch += self.mount[0]
            roll += self.mount[1]
            yaw += self.mount[2]
        roll, pitch = _wrap180(roll), _wrap180(pitch)   # "earth frame, degrees, +-180"
        yaw %= 360.0
        t_us = self._utc_us(now)
        fb = Feedback(index, t_us, lat, lon, alt_mm / 1000.0, height or 0.0, roll, pitch, yaw, msg.shot == 2)
        self.feedback.append(fb)
        del self.feedback[:-10000]
        return [
            self.mav.camera_status_encode(t_us, self.system_id, 0, index, mavlink2.CAMERA_STATUS_TYPE_TRIGGER,
                                          0.0, 0.0, 0.0, 0.0),
            self.mav.camera_feedback_encode(t_us, self.system_id, 0, index, lat, lon, fb.alt_msl_m, fb.alt_rel_m,
                                            roll, pitch, yaw, self.focal_mm, mavlink2.CAMERA_FEEDBACK_CLOSEDLOOP,
                                            index),
        ]

    # -- classic parameters --------------------------------------------------------------------
    def _param_value(self, index: int) -> Message:
        s = self.params[index]
        value = paramext.encode_classic(self.values.get(s.param, 0), s.type)
        return self.mav.param_value_encode(s.param.encode(), value, paramext.classic_type(s.type), len(self.params),
                                           index)

    def _index(self, name: str) -> int | None:
        return next((i for i, s in enumerate(self.params) if s.param == name), None)

    def _on_param_request_list(self, msg, now):
        return [self._param_value(i) for i in range(len(self.params))]

    def _on_param_request_read(self, msg, now):
        if msg.param_index >= 0:
            return [self._param_value(msg.param_index)] if msg.param_index < len(self.params) else []
        index = self._index(msg.param_id)
        return [] if index is None else [self._param_value(index)]

    def _on_param_set(self, msg, now):
        index = self._index(msg.param_id)
        if index is None:
            return []
        s = self.params[index]
        value = paramext.decode_classic(msg.param_value, paramext.classic_type(s.type))   # its own type, always
        if _allowed(s, value):
            self.values[s.param] = value
            if s.key == "auto_capture":
                self._last_auto_pos = None
                self._next_timer = now
        return [self._param_value(index)]


def _allowed(s: Setting, value: float | int | None) -> bool:
    """Whether the catalogue takes `value` for `s` (its options or range, whole numbers for integer types,
    finite): the camera keeps its value otherwise."""
    try:
        s.check(value)
    except CdfError:
        return False
    return True


def _wrap180(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0
