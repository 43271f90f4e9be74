"""A Workswell WIRIS camera component as the Workswell MAVLink Interface manual (rev 231108EN) describes it.

Pure protocol logic: `WirisState.handle(msg, now)` takes one received pymavlink message and returns the
messages the camera sends in answer; `tick(now)` returns what it sends on its own (HEARTBEAT, periodic
captures, capture status while recording). No sockets, no threads: the runner (runner.py) owns those, and
tests and the fuzzer call these two methods directly.

Every camera fact comes from the catalogue (cdf/tables): which commands exist (§6.3), which setting each
command param carries (with its offset, `when` and `keep` values), the limits of params that carry no
setting, enumerators, capabilities, identity strings, imagers. The parameter list served over PARAM_EXT is
the definition's own (cdf.generate.definition_xml), so what a ground station loads and what it can read and
write are the same thing. One value table (`values`, keyed by PARAM_EXT name) sits behind both the commands
and PARAM_EXT: a USER_1 range change reads back as RANGE_MODE, a PARAM_EXT_SET of CAM_ZOOM shows in
CAMERA_SETTINGS.

Choices where the manual is silent or departs from common.xml (each also noted where it is made):
- a command naming another component is ignored silently (§3.2); target_system is not checked (§3.2 and
  §5.1 speak only of the component id);
- a command the manual does not list gets COMMAND_ACK UNSUPPORTED; a listed one with a value outside the
  manual's range gets DENIED and changes nothing (all params of one command are checked before any applies);
- a capture while the chosen storage has no room for an image: the command is ACCEPTED (it was valid),
  CAMERA_IMAGE_CAPTURED reports capture_result 0 with the index the image would have had, the image
  counter does not move, and a periodic capture stops;
- RTSP (VIDEO_START/STOP_STREAMING, stream information) needs the separately sold Ethernet Stream SDK:
  without it (the default) streaming commands are DENIED and VIDEO_STREAM_INFORMATION reports 0 streams;
- CAMERA_IMAGE_CAPTURED re-requested (§6.4.5) reads REQUEST_MESSAGE params 2-3 as common.xml does (image
  index, -1 all, a range), from the last 1000 images it holds;
- MAV_CMD_SET_CAMERA_ZOOM, which common.xml ties to the HAS_BASIC_ZOOM flag the manual claims, drives the
  same zoom as DO_DIGICAM_CONTROL; VIDEO_START_CAPTURE param 1 = 0 (common.xml: all streams) keeps the
  Video ID; STORAGE_FORMAT is followed by STORAGE_INFORMATION (common.xml);
- where the manual's messages contradict common.xml the standard's values are sent, noted where it is done
  (CAMERA_CAP_FLAGS, CAMERA_SETTINGS.zoomLevel in %, STORAGE_INFORMATION.type, CAMERA_IMAGE_CAPTURED units);
- every command gets exactly one COMMAND_ACK: an exception inside the emulator (a bug) is answered
  MAV_RESULT_FAILED and counted in `faults`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.catalogue import Camera, Setting
from cdf.generate import definition_file_name, definition_xml
from wiris_tools import paramext
from wiris_tools.camera_definition import Definition, DefParam, parse_definition
from wiris_tools.mavftp import FtpServer
from wiris_tools.serve import host_port

Message = Any

HEARTBEAT_S = 1.0
# STORAGE_INFORMATION.type of each Storage ID option (§7.2.1, by its catalogue key). §6.4.3 fills `type` with
# the Storage ID itself (0 SSD, 1 USB, 2 microSD); the field is common.xml's STORAGE_TYPE, where those numbers
# read as unknown, USB stick and SD card, so the standard's types are sent. common.xml has no SSD: the
# internal drive is its "HD mass storage type".
STORAGE_TYPES = {"ssd": mavlink2.STORAGE_TYPE_HD, "usb": mavlink2.STORAGE_TYPE_USB_STICK,
                 "microsd": mavlink2.STORAGE_TYPE_MICROSD}
# CAMERA_CAPTURE_STATUS.image_status and video_status (§6.4.4, as common.xml, which gives the numbers in the
# fields' descriptions and no enum that pymavlink could name): image 0 idle, 1 capture in progress, 2 interval
# set but idle, 3 interval set and capture in progress; video 0 idle, 1 capture in progress.
IMAGE_STATUS_IDLE = 0
IMAGE_STATUS_INTERVAL_CAPTURING = 3
VIDEO_STATUS_IDLE = 0
VIDEO_STATUS_CAPTURING = 1
_INFO = mavlink2.MAVLink_camera_information_message
# cam_definition_uri is char[140]: a URI of up to 139 characters keeps the NUL that ends it
DEFINITION_URI_CHARS = _INFO.array_lengths[_INFO.ordered_fieldnames.index("cam_definition_uri")] - 1
GPS_MESSAGES = ("GLOBAL_POSITION_INT", "GPS_STATUS")
PARAM_EXT_MESSAGES = ("PARAM_EXT_REQUEST_LIST", "PARAM_EXT_REQUEST_READ", "PARAM_EXT_SET")


@dataclass(frozen=True)
class WirisConfig:
    """How this emulated camera is set up (not camera facts: the catalogue holds those)."""

    system: int = 1
    component: int = 100                   # §3.2: 100–105, set in the camera menu
    definition_uri: str = ""               # where the runner serves the definition
    storage_capacity_mib: tuple[float, float, float] = (64000.0, 32000.0, 32000.0)  # SSD, USB, microSD
    image_size_mib: float = 4.0            # room one image of one format takes
    licensed: bool = True                  # §4: without the licence the camera ignores commands
    ethernet_sdk: bool = False             # §6.3.2.11: RTSP is the separately sold Ethernet Stream SDK
    stream_host: str = "127.0.0.1"
    lens_index: int = 0                    # index into the thermal imager's lenses (CAMERA_INFORMATION.lens_id)


@dataclass(frozen=True)
class CaptureFaults:
    """Faults of the field to inject (tests, `wiris mission audit`'s SITL flights): the camera misses every
    `drop_every`-th capture request (0: none) and takes nothing from request `stop_after` on (counting from 1;
    None: never). A missed request sends nothing, as a camera that did not see the trigger."""

    drop_every: int = 0
    stop_after: int | None = None

    def drops(self, request: int) -> bool:
        return bool((self.drop_every and request % self.drop_every == 0)
                    or (self.stop_after is not None and request >= self.stop_after))


@dataclass
class Position:
    lat: int = 0
    lon: int = 0
    alt: int = 0
    relative_alt: int = 0


@dataclass
class Captured:
    index: int
    time_boot_ms: int
    time_utc_us: int
    position: Position
    result: int
    file_name: str


@dataclass
class _Capture:
    interval_s: float = 0.0
    remaining: int = 0            # images still to take; 0 with `running` = until stopped
    until_stopped: bool = False
    running: bool = False
    next_due: float = 0.0


def _cmd_id(name: str) -> int | None:
    return getattr(mavlink2, name, None)


def _msg_id(name: str) -> int | None:
    return getattr(mavlink2, f"MAVLINK_MSG_ID_{name}", None)


def _finite(v: float) -> bool:
    return isinstance(v, (int, float)) and math.isfinite(v)


class CommandRefused(Exception):
    """A command param outside what the manual allows: COMMAND_ACK DENIED, nothing changes."""


class WirisState:
    """One WIRIS camera (see the module docstring)."""

    def __init__(self, camera: Camera, definition: Definition, config: WirisConfig | None = None,
                 *, now: float = 0.0, utc_offset_s: float = 0.0, ftp_files: dict[str, bytes] | None = None) -> None:
        if camera.protocol != "workswell-mavlink":
            raise ValueError(f"{camera.id} is not a Workswell MAVLink camera")
        self.camera = camera
        self.definition = definition
        self.config = config or WirisConfig()
        self.boot = now
        self.utc_offset_s = utc_offset_s      # UTC = now + offset (the runner passes wall-clock time)
        self.mav = mavlink2.MAVLink(None, srcSystem=self.config.system, srcComponent=self.config.component)
        self._by_param: dict[str, Setting] = {s.param: s for s in camera.settings}
        self._commands = {name: info for name, info in camera.commands}
        self._cmd_names = {cid: name for name in self._commands if (cid := _cmd_id(name)) is not None}
        self.values: dict[str, float | int | None] = {}
        self.camera_mode = mavlink2.CAMERA_MODE_IMAGE
        self.position = Position()
        self.satellites_visible = 0
        self.capture = _Capture()
        self.image_count = 0
        self.history: list[Captured] = []
        self.capture_faults = CaptureFaults()
        self.capture_requests = 0         # every image asked for, taken or not (CaptureFaults counts these)
        self.used_mib = [0.0 for _ in self.config.storage_capacity_mib]
        self.video_recording = False
        self.video_started = 0.0
        self.video_status_hz = 0.0
        self.video_status_next = 0.0
        self.streaming = False
        self.trigger_enabled = True
        self.menu_actions: list[int] = []
        self.ignored = 0                  # messages dropped by the component rule (§3.2)
        self.faults = 0                   # commands answered FAILED because the emulator raised (a bug)
        self._next_heartbeat = now
        # Not in the Workswell manual: the emulator can also serve its definition over MAVLink FTP (mftp://),
        # the other transport common.xml allows for cam_definition_uri.
        self.ftp = None
        if ftp_files:
            self.ftp = FtpServer(ftp_files, self.mav)
        self.reset_settings()

    # -- values --------------------------------------------------------------------------------
    def reset_settings(self) -> None:
        """Factory defaults (§6.3.2.4: everything but the MAVLink id, which lives in the config)."""
        self.values = {s.param: s.default for s in self.camera.settings}
        for p in self.definition.params:
            self.values.setdefault(p.name, p.default)
        self.camera_mode = mavlink2.CAMERA_MODE_IMAGE

    def value(self, key: str) -> float | int | None:
        """A setting's value by its catalogue key (None when this model has no such setting)."""
        s = self.camera.setting(key)
        return None if s is None else self.values.get(s.param)

    def time_boot_ms(self, now: float) -> int:
        return max(0, int((now - self.boot) * 1000)) & 0xFFFFFFFF

    # -- entry points --------------------------------------------------------------------------
    def tick(self, now: float) -> list[Message]:
        out: list[Message] = []
        if now >= self._next_heartbeat:
            out.append(self.mav.heartbeat_encode(mavlink2.MAV_TYPE_CAMERA, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0,
                                                 mavlink2.MAV_STATE_ACTIVE))
            self._next_heartbeat = now + HEARTBEAT_S
        c = self.capture
        if c.running and now >= c.next_due:
            out.extend(self._take_image(now))      # stops the capture when the storage is full
            if c.running and not c.until_stopped:
                c.remaining -= 1
                c.running = c.remaining > 0
            if c.running:
                c.next_due = max(c.next_due + c.interval_s, now)
        if self.video_recording and self.video_status_hz > 0 and now >= self.video_status_next:
            out.append(self._capture_status(now))
            self.video_status_next = now + 1.0 / self.video_status_hz
        return out

    def handle(self, msg: Message, now: float) -> list[Message]:
        """Messages to send in answer to `msg` (an empty list when the camera stays silent)."""
        mtype = msg.get_type()
        if mtype in ("BAD_DATA", "UNKNOWN") or mtype.startswith("UNKNOWN"):
            return []
        if (msg.get_srcSystem(), msg.get_srcComponent()) == (self.config.system, self.config.component):
            return []  # our own echo on a shared bus
        # §3.2: receiving broadcast GPS messages does not depend on the MAVLink id (and §4: nor on the licence)
        if mtype == "GLOBAL_POSITION_INT":
            self.position = Position(msg.lat, msg.lon, msg.alt, msg.relative_alt)
            return []
        if mtype == "GPS_STATUS":
            self.satellites_visible = msg.satellites_visible
            return []
        target = getattr(msg, "target_component", None)
        if target is not None and target not in (mavlink2.MAV_COMP_ID_ALL, self.config.component):
            self.ignored += 1
            return []
        if not self.config.licensed:
            return []  # §4: commands are recognised only with the MAVLink licence
        if mtype == "COMMAND_LONG":
            return self._command(msg, now)
        if mtype == "COMMAND_INT":
            # §6.3: the camera's commands are COMMAND_LONG; answer rather than leave the sender retrying,
            # with common.xml's result that names the way to send one the camera knows
            known = msg.command in self._cmd_names
            return [self._ack(msg, mavlink2.MAV_RESULT_COMMAND_LONG_ONLY if known else mavlink2.MAV_RESULT_UNSUPPORTED)]
        if mtype in PARAM_EXT_MESSAGES:
            return self._param_ext(msg, mtype)
        if mtype == "FILE_TRANSFER_PROTOCOL" and self.ftp is not None:
            return self.ftp.handle(msg, now)
        return []

    # -- the command protocol ------------------------------------------------------------------
    def _ack(self, msg: Message, result: int) -> Message:
        return self.mav.command_ack_encode(msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())

    def _command(self, msg: Message, now: float) -> list[Message]:
        name = self._cmd_names.get(msg.command)
        if name is None:
            return [self._ack(msg, mavlink2.MAV_RESULT_UNSUPPORTED)]   # not in the manual's §6.3
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7]
        handler = getattr(self, "_cmd_" + name.removeprefix("MAV_CMD_").lower(), None)
        try:
            self._check_limits(name, params)
            changes = self._slot_changes(name, params)
            if handler is None:
                self._apply(changes)
                return [self._ack(msg, mavlink2.MAV_RESULT_ACCEPTED)]
            result, after = handler(params, changes, now)
        except CommandRefused:
            return [self._ack(msg, mavlink2.MAV_RESULT_DENIED)]
        except (ArithmeticError, ValueError, TypeError):
            # An emulator bug (arithmetic on a stored value it did not expect, such as a NaN set over
            # PARAM_EXT). The sender still gets its one COMMAND_ACK: without it, it retries and then reports a
            # lost link, which hides the bug behind a radio problem. Counted in `faults`; tests and the fuzzer assert none.
            self.faults += 1
            return [self._ack(msg, mavlink2.MAV_RESULT_FAILED)]
        return [self._ack(msg, result), *after]

    def _check_limits(self, name: str, params: list[float]) -> None:
        """The manual's Values column for params that carry no setting (§6.3.x); NaN means 'ignore'."""
        info = self._commands[name]
        nearest = set(info.get("nearest", ()))
        for slot, lim in (info.get("limits") or {}).items():
            v = params[int(slot) - 1]
            if math.isnan(v) or any(params[int(k) - 1] == u for k, u in (lim.get("unless") or {}).items()):
                continue
            if not math.isfinite(v):
                raise CommandRefused
            if "enum" in lim:
                enum = self.camera.enum(lim["enum"])
                if enum is None or v != int(v) or enum.by_value(int(v)) is None:
                    raise CommandRefused
                continue
            if int(slot) in nearest:
                continue
            if lim.get("step") == 1 and v != int(v):
                raise CommandRefused
            if ("min" in lim and v < lim["min"]) or ("max" in lim and v > lim["max"]):
                raise CommandRefused

    def _slot_changes(self, name: str, params: list[float]) -> dict[str, float | int]:
        """Setting changes a command asks for: {PARAM name: value}; CommandRefused if one is not allowed.

        Slots with a `when` (USER_1 p3/p4 mean the manual range's limits in manual mode and the span's in
        span mode) are read after the unconditional ones, so a command that switches the range mode and sets
        the limits at once is read in the new mode."""
        info = self._commands[name]
        nearest = set(info.get("nearest", ()))
        slots = [s for s in self.camera.settings if s.command is not None and s.command.cmd == name]
        changes: dict[str, float | int] = {}
        for conditional in (False, True):
            for s in slots:
                if bool(s.command.when) != conditional:
                    continue
                if conditional and not all(self._current(k, changes) == v for k, v in s.command.when):
                    continue
                wire = params[s.command.param - 1]
                if not isinstance(wire, (int, float)) or (math.isinf(wire)):
                    raise CommandRefused
                value = s.command.decode(float(wire))
                if value is None:
                    continue
                changes[s.param] = self._setting_value(s, value, s.command.param in nearest)
        return changes

    def _current(self, key: str, changes: dict[str, float | int]) -> float | int | None:
        s = self.camera.setting(key)
        if s is None:
            return None
        return changes.get(s.param, self.values.get(s.param))

    @staticmethod
    def _setting_value(s: Setting, value: float, nearest: bool) -> float | int:
        if not math.isfinite(value):
            # NaN and the infinities fit no range (every comparison with NaN is false, so the range test below
            # would let it through) and would poison every later command that computes from the stored value
            raise CommandRefused
        if s.options:
            if value != int(value) or not any(o.value == int(value) for o in s.options):
                raise CommandRefused
            return int(value)
        if nearest:
            # "set the zoom of the camera to the closest possible value to the given one" (§6.3.2.2)
            lo = s.min if s.min is not None else value
            hi = s.max if s.max is not None else value
            value = min(max(value, lo), hi)
            if s.step:
                base = s.min if s.min is not None else 0.0
                value = min(base + round((value - base) / s.step) * s.step, hi)
                value = round(value, 6)
        if (s.min is not None and value < s.min) or (s.max is not None and value > s.max):
            raise CommandRefused
        if s.is_integer:
            if value != int(value):
                raise CommandRefused
            return int(value)
        return float(value)

    def _apply(self, changes: dict[str, float | int]) -> None:
        self.values.update(changes)

    # -- info requests (§6.3.1) ----------------------------------------------------------------
    def _cmd_request_message(self, params, changes, now):
        wanted = params[0]
        if not _finite(wanted) or wanted != int(wanted):
            raise CommandRefused
        names = {_msg_id(n): n for n in self._commands["MAV_CMD_REQUEST_MESSAGE"].get("answers", ())}
        name = names.get(int(wanted))
        if name is None:
            return mavlink2.MAV_RESULT_UNSUPPORTED, []
        arg = params[1]
        if name == "CAMERA_INFORMATION":
            return mavlink2.MAV_RESULT_ACCEPTED, [self.camera_information(now)]
        if name == "CAMERA_SETTINGS":
            return mavlink2.MAV_RESULT_ACCEPTED, [self.camera_settings(now)]
        if name == "STORAGE_INFORMATION":
            return mavlink2.MAV_RESULT_ACCEPTED, self._storages(arg, now)
        if name == "CAMERA_CAPTURE_STATUS":
            return mavlink2.MAV_RESULT_ACCEPTED, [self._capture_status(now)]
        if name == "VIDEO_STREAM_INFORMATION":
            return mavlink2.MAV_RESULT_ACCEPTED, self._streams(arg)
        if name == "CAMERA_IMAGE_CAPTURED":
            return self._captured_again(arg, params[2])
        return mavlink2.MAV_RESULT_UNSUPPORTED, []

    def _captured_again(self, first: float, last: float) -> tuple[int, list[Message]]:
        """CAMERA_IMAGE_CAPTURED re-requested (§6.4.5 says it can be; the manual gives the params no meaning,
        so common.xml's): param2 the image_index of the first image, -1 for every image; param3 0 (or NaN,
        unused) for that one image, -1 for it and all after it, else the index of the last one.

        Looked up by image_index, not by place in `history`, which keeps the last 1000 images only. An index
        never given out (or not a whole number) is DENIED; one given out but no longer held is FAILED (a valid
        request the camera cannot serve); -1 and ranges send what is still held."""
        if not _finite(first) or first != int(first) or not -1 <= first < self.image_count:
            raise CommandRefused
        if first == -1:
            return mavlink2.MAV_RESULT_ACCEPTED, [self._image_message(shot) for shot in self.history]
        if math.isnan(last) or last == 0:
            last = first
        elif last == -1:
            last = self.image_count - 1
        elif not _finite(last) or last != int(last) or last < first:
            raise CommandRefused
        wanted = [shot for shot in self.history if first <= shot.index <= last]
        if not wanted:
            return mavlink2.MAV_RESULT_FAILED, []
        return mavlink2.MAV_RESULT_ACCEPTED, [self._image_message(shot) for shot in wanted]

    def _cmd_request_camera_information(self, params, changes, now):
        return mavlink2.MAV_RESULT_ACCEPTED, [self.camera_information(now)]

    def _cmd_request_camera_settings(self, params, changes, now):
        if params[0] == mavlink2.MAV_BOOL_TRUE:
            return mavlink2.MAV_RESULT_ACCEPTED, [self.camera_settings(now)]
        return mavlink2.MAV_RESULT_ACCEPTED, []   # "0: No Action" (NaN ignores the parameter)

    def _cmd_request_storage_information(self, params, changes, now):
        return mavlink2.MAV_RESULT_ACCEPTED, self._storages(params[0], now)

    def _cmd_request_camera_capture_status(self, params, changes, now):
        return mavlink2.MAV_RESULT_ACCEPTED, [self._capture_status(now)]

    def _cmd_request_video_stream_information(self, params, changes, now):
        return mavlink2.MAV_RESULT_ACCEPTED, self._streams(float("nan"))

    # -- actions (§6.3.2) ----------------------------------------------------------------------
    def _cmd_do_digicam_control(self, params, changes, now):
        zoom = self.camera.setting("zoom")
        # param 3, relative zoom steps, is "considered only if Zoom absolute is NaN"
        if zoom is not None and zoom.param not in changes and math.isnan(params[1]) and _finite(params[2]) \
                and params[2] != 0:
            step = zoom.step or 1.0
            changes[zoom.param] = self._setting_value(zoom, self._zoom_now(zoom) + params[2] * step, True)
        self._apply(changes)
        after = self._take_image(now) if params[4] == 1 else []
        return mavlink2.MAV_RESULT_ACCEPTED, after

    def _cmd_set_camera_zoom(self, params, changes, now):
        # Not in the manual's §6.3: common.xml's command behind CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM, which the
        # camera claims (workswell.yaml capabilities_note); mapped onto the one zoom setting of §6.3.2.2.
        zoom = self.camera.setting("zoom")
        kind, value = params[0], params[1]
        if zoom is None or not _finite(value):
            raise CommandRefused
        if kind == mavlink2.ZOOM_TYPE_RANGE:
            # "proportion of full camera range (a value between 0.0 and 100.0)"; like §6.3.2.2's absolute
            # zoom, the camera goes to the closest zoom it has
            if not 0.0 <= value <= 100.0 or zoom.min is None or zoom.max is None:
                raise CommandRefused
            target = zoom.min + value / 100.0 * (zoom.max - zoom.min)
        elif kind == mavlink2.ZOOM_TYPE_STEP:
            # "-1 for wide, 1 for tele": §6.3.2.2's relative zoom steps, whole numbers only
            if value != int(value):
                raise CommandRefused
            target = self._zoom_now(zoom) + value * (zoom.step or 1.0)
        else:
            # ZOOM_TYPE_CONTINUOUS and ZOOM_TYPE_FOCAL_LENGTH: the manual describes no such zoom
            raise CommandRefused
        self._apply({zoom.param: self._setting_value(zoom, target, True)})
        # common.xml: "Camera must respond with a CAMERA_SETTINGS message (on success)"
        return mavlink2.MAV_RESULT_ACCEPTED, [self.camera_settings(now)]

    def _zoom_now(self, zoom: Setting) -> float:
        current = self.values.get(zoom.param)
        if not _finite(current):      # nothing stored (a model without a default): start from the widest
            current = zoom.min if zoom.min is not None else 1.0
        return float(current)

    def _cmd_storage_format(self, params, changes, now):
        storage = self._storage_index(params[0])
        after = []
        if params[1] == mavlink2.MAV_BOOL_TRUE:
            self.used_mib[storage] = 0.0
            # common.xml: "Once format is complete, a STORAGE_INFORMATION message is sent" (the manual is
            # silent); formatting here is instant, so it follows the ACK at once
            after.append(self.storage_information(storage, now))
        if params[2] == mavlink2.MAV_BOOL_TRUE:
            self.image_count = 0
            self.history.clear()
        return mavlink2.MAV_RESULT_ACCEPTED, after

    def _cmd_reset_camera_settings(self, params, changes, now):
        if params[0] == mavlink2.MAV_BOOL_TRUE:
            self.reset_settings()
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_set_camera_mode(self, params, changes, now):
        self._apply(changes)
        if _finite(params[1]):
            self.camera_mode = int(params[1])
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_image_start_capture(self, params, changes, now):
        interval, count = params[1], params[2]
        count_n = int(count) if _finite(count) else 1
        if count_n != 1:
            # periodic: the interval must be given, at least 1 s (§6.3.2.6) and at least the model's minimum
            minimum = self._min_interval_s()
            if not _finite(interval) or interval < minimum:
                raise CommandRefused
        self._apply(changes)
        if count_n == 1:
            return mavlink2.MAV_RESULT_ACCEPTED, self._take_image(now)
        self.capture = _Capture(interval_s=float(interval), remaining=count_n, until_stopped=count_n == 0,
                                running=True, next_due=now)
        # the first image is taken at once (on the next tick), the next ones `interval` apart
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _min_interval_s(self) -> float:
        lim = (self._commands["MAV_CMD_IMAGE_START_CAPTURE"].get("limits") or {}).get(2, {})
        minimum = float(lim.get("min", 0.0))
        thermal = self.camera.imager("thermal")
        if thermal is not None and thermal.min_interval_s:
            minimum = max(minimum, float(thermal.min_interval_s))
        return minimum

    def _cmd_image_stop_capture(self, params, changes, now):
        self.capture.running = False
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_do_trigger_control(self, params, changes, now):
        if _finite(params[0]):
            self.trigger_enabled = params[0] == 1
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_video_start_capture(self, params, changes, now):
        self._apply(changes)
        self.video_recording = True
        self.video_started = now
        self.video_status_hz = float(params[1]) if _finite(params[1]) else 0.0
        self.video_status_next = now
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_video_stop_capture(self, params, changes, now):
        self.video_recording = False
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_video_start_streaming(self, params, changes, now):
        if not self.config.ethernet_sdk:
            raise CommandRefused
        self.streaming = True
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_video_stop_streaming(self, params, changes, now):
        if not self.config.ethernet_sdk:
            raise CommandRefused
        self.streaming = False
        return mavlink2.MAV_RESULT_ACCEPTED, []

    def _cmd_user_3(self, params, changes, now):
        if _finite(params[0]):
            self.menu_actions.append(int(params[0]))   # the HDMI menu itself is not emulated
            del self.menu_actions[:-100]
        return mavlink2.MAV_RESULT_ACCEPTED, []

    # -- captures ------------------------------------------------------------------------------
    def _storage_index(self, wire: float) -> int:
        if _finite(wire):
            return int(wire)
        selected = self.value("storage")
        return int(selected) if selected is not None else 0

    def _formats(self) -> int:
        flags = self.value("capture")
        return max(1, bin(int(flags)).count("1")) if flags else 1

    def available_mib(self, storage: int) -> float:
        return max(0.0, self.config.storage_capacity_mib[storage] - self.used_mib[storage])

    def _take_image(self, now: float) -> list[Message]:
        self.capture_requests += 1
        if self.capture_faults.drops(self.capture_requests):
            return []
        storage = self._storage_index(float("nan"))
        size = self.config.image_size_mib * self._formats()
        utc_us = int((now + self.utc_offset_s) * 1e6)
        pos = Position(self.position.lat, self.position.lon, self.position.alt, self.position.relative_alt)
        if self.available_mib(storage) < size:
            self.capture.running = False
            shot = Captured(self.image_count, self.time_boot_ms(now), utc_us, pos, mavlink2.MAV_BOOL_FALSE, "")
            return [self._image_message(shot)]
        self.used_mib[storage] += size
        index = self.image_count
        self.image_count += 1
        enum = self.camera.enum("storage")
        option = enum.by_value(storage) if enum else None
        folder = option.key if option else f"storage{storage}"
        shot = Captured(index, self.time_boot_ms(now), utc_us, pos, mavlink2.MAV_BOOL_TRUE,
                        f"{folder}/IMG_{index:05d}.jpg")
        self.history.append(shot)
        del self.history[:-1000]
        return [self._image_message(shot)]

    def _image_message(self, shot: Captured) -> Message:
        # §6.4.5 prints time_utc in ms and positions in degE10; common.xml (and every reader) has us and degE7,
        # and the camera forwards GLOBAL_POSITION_INT's degE7 values, so the standard's units are used.
        # q: "unsupported by WORKSWELL devices" -> zeros. camera_id: "MAVLink Id of the camera".
        return self.mav.camera_image_captured_encode(
            shot.time_boot_ms, shot.time_utc_us, self.config.component, shot.position.lat, shot.position.lon,
            shot.position.alt, shot.position.relative_alt, [0.0, 0.0, 0.0, 0.0], shot.index, shot.result,
            shot.file_name.encode())

    # -- messages (§6.4) -----------------------------------------------------------------------
    def capability_flags(self) -> int:
        flags = 0
        for name in self.camera.capabilities:
            flags |= int(getattr(mavlink2, name))
        return flags

    def camera_information(self, now: float) -> Message:
        thermal = self.camera.imager("thermal")
        focal = float("nan")   # common.xml: NaN when unknown
        res = (0, 0)           # common.xml: 0 when unknown
        lens = 0
        if thermal is not None and thermal.known:
            if thermal.lenses_mm:
                lens = min(self.config.lens_index, len(thermal.lenses_mm) - 1)
                focal = thermal.lenses_mm[lens]
            if thermal.resolution_px:
                res = thermal.resolution_px
        uri = self.config.definition_uri.encode()[:DEFINITION_URI_CHARS]
        # §6.4.1: sensor size "not implemented, sends 0"; firmware version is not in the manual's table (0 =
        # unknown in common.xml).
        return self.mav.camera_information_encode(
            self.time_boot_ms(now), self.camera.vendor.encode()[:32].ljust(32, b"\0"),
            self.camera.model.encode()[:32].ljust(32, b"\0"), 0, focal, 0.0, 0.0, res[0], res[1], lens,
            self.capability_flags(), int(self.camera.definition_version or 0), uri)

    def camera_settings(self, now: float) -> Message:
        # §6.4.2 fills mode_id with the Main Camera enumerator (0 thermal, 1 visible), not common.xml's
        # CAMERA_MODE (0 image, 1 video). We follow the manual; a standard reader (MAVSDK) will take a
        # visible main camera for video mode.
        main = self.value("main_camera")
        return self.mav.camera_settings_encode(self.time_boot_ms(now), int(main or 0), self.zoom_level(),
                                               float("nan"))

    def zoom_level(self) -> float:
        """CAMERA_SETTINGS.zoomLevel. §6.4.2 prints the zoom factor ("1-10 (12)"); common.xml defines "Current
        zoom level as a percentage of the full range (0.0 to 100.0, NaN if not known)", which is what QGC's
        and MAVSDK's zoom sliders show and what MAV_CMD_SET_CAMERA_ZOOM's ZOOM_TYPE_RANGE sets, so the
        standard's percentage of the zoom setting's range is sent (the factor itself is CAM_ZOOM over
        PARAM_EXT)."""
        zoom = self.camera.setting("zoom")
        value = self.value("zoom")
        if zoom is None or not _finite(value) or zoom.min is None or zoom.max is None or zoom.max <= zoom.min:
            return float("nan")
        return round(100.0 * (float(value) - zoom.min) / (zoom.max - zoom.min), 4)

    def _storages(self, wire: float, now: float) -> list[Message]:
        count = len(self.config.storage_capacity_mib)
        if math.isnan(wire):
            return [self.storage_information(i, now) for i in range(count)]
        if not math.isfinite(wire) or wire != int(wire) or not 0 <= int(wire) < count:
            raise CommandRefused
        return [self.storage_information(int(wire), now)]

    def storage_information(self, storage: int, now: float) -> Message:
        # §6.4.3: storage id carries the Storage ID enumerator (0 SSD, 1 USB, 2 microSD), count is 3. common.xml
        # numbers storages from 1, but the manual uses the same 0-based Storage ID wherever a storage is named
        # (REQUEST_MESSAGE param2, REQUEST_STORAGE_INFORMATION, STORAGE_FORMAT), so the manual's numbering is
        # kept: renumbering only here would break its requests, and renumbering STORAGE_FORMAT too would format
        # another medium than a real camera does. `type` is common.xml's STORAGE_TYPE (STORAGE_TYPES above).
        # Its `status` row is a copy of another table's; common.xml's STORAGE_STATUS_READY is sent.
        total = self.config.storage_capacity_mib[storage]
        used = min(total, self.used_mib[storage])
        enum = self.camera.enum("storage")
        option = enum.by_value(storage) if enum else None
        usage = 0
        if storage == self._storage_index(float("nan")):
            usage = (mavlink2.STORAGE_USAGE_FLAG_SET | mavlink2.STORAGE_USAGE_FLAG_PHOTO
                     | mavlink2.STORAGE_USAGE_FLAG_VIDEO)
        return self.mav.storage_information_encode(
            self.time_boot_ms(now), storage, len(self.config.storage_capacity_mib), mavlink2.STORAGE_STATUS_READY,
            total, used, total - used, 0.0, 0.0,
            STORAGE_TYPES.get(option.key, mavlink2.STORAGE_TYPE_OTHER) if option else mavlink2.STORAGE_TYPE_UNKNOWN,
            (option.name if option else "").encode()[:32], usage)

    def _capture_status(self, now: float) -> Message:
        c = self.capture
        image_status = IMAGE_STATUS_INTERVAL_CAPTURING if c.running else IMAGE_STATUS_IDLE
        video_status = VIDEO_STATUS_CAPTURING if self.video_recording else VIDEO_STATUS_IDLE
        # §6.4.4: recording time "not implemented, sends 0"; available capacity is the internal SSD's
        return self.mav.camera_capture_status_encode(
            self.time_boot_ms(now), image_status, video_status,
            float(c.interval_s if c.running else 0.0), 0, self.available_mib(0), self.image_count)

    def _streams(self, wire: float) -> list[Message]:
        enum = self.camera.enum("stream_id")
        options = [o for o in (enum.options if enum else ()) if o.value != 0]   # 0 is "All"
        if not self.config.ethernet_sdk:
            # §6.4.6 count "2, 0": no RTSP stream without the Ethernet Stream SDK
            return [self.mav.video_stream_information_encode(0, 0, mavlink2.VIDEO_STREAM_TYPE_RTSP, 0, 0.0, 0, 0,
                                                             0, 0, 0, b"", b"")]
        count = len(options)
        if _finite(wire) and wire != 0:       # param2: 0 all streams, 1 the first, 2 the second (§6.4.6)
            options = [o for o in options if o.value == wire]
            if not options:
                raise CommandRefused
        out = []
        for o in options:
            imager = self.camera.imager(o.key)
            res = imager.resolution_px if imager is not None and imager.resolution_px else (0, 0)
            flags = mavlink2.VIDEO_STREAM_STATUS_FLAGS_RUNNING if self.streaming else 0
            if o.key == "thermal":
                flags |= mavlink2.VIDEO_STREAM_STATUS_FLAGS_THERMAL
            uri = f"rtsp://{host_port(self.config.stream_host, 8554)}/{o.key}".encode()
            # frame rate, bitrate and field of view are in no source read: 0 (hfov "not implemented", §6.4.6)
            out.append(self.mav.video_stream_information_encode(
                o.value, count, mavlink2.VIDEO_STREAM_TYPE_RTSP,
                flags, 0.0, res[0], res[1], 0, 0, 0, o.name.encode()[:32], uri))
        return out

    # -- PARAM_EXT (§6.2, camera protocol) -----------------------------------------------------
    def _param_value(self, index: int) -> Message:
        p = self.definition.params[index]
        value = self.values.get(p.name)
        if value is None:
            value = p.default if p.default is not None else 0
        return self.mav.param_ext_value_encode(p.name.encode(), paramext.encode(value, p.type),
                                               paramext.wire_type(p.type).ext_type, len(self.definition.params),
                                               index)

    def _param_ext(self, msg: Message, mtype: str) -> list[Message]:
        params = self.definition.params
        if mtype == "PARAM_EXT_REQUEST_LIST":
            return [self._param_value(i) for i in range(len(params))]
        if mtype == "PARAM_EXT_REQUEST_READ":
            if msg.param_index >= 0:
                return [self._param_value(msg.param_index)] if msg.param_index < len(params) else []
            name = paramext.param_id(msg)
            index = next((i for i, p in enumerate(params) if p.name == name), None)
            return [] if index is None else [self._param_value(index)]
        return [self._param_ext_set(msg)]

    def _param_ext_set(self, msg: Message) -> Message:
        name = paramext.param_id(msg)
        raw = paramext.raw_value(msg)
        p = self.definition.param(name)

        def ack(result: int, value_raw: bytes, ptype: int) -> Message:
            return self.mav.param_ext_ack_encode(name.encode()[:16], value_raw, ptype, result)

        if p is None:
            return ack(mavlink2.PARAM_ACK_FAILED, raw, msg.param_type)
        wt = paramext.wire_type(p.type)
        current = self.values.get(p.name, p.default)
        current_raw = paramext.encode(current if current is not None else 0, p.type)
        if msg.param_type != wt.ext_type:
            return ack(mavlink2.PARAM_ACK_FAILED, current_raw, wt.ext_type)
        value = paramext.decode(raw, p.type)
        if self._param_problem(p, value) is not None:
            return ack(mavlink2.PARAM_ACK_VALUE_UNSUPPORTED, current_raw, wt.ext_type)
        self.values[p.name] = value
        return ack(mavlink2.PARAM_ACK_ACCEPTED, paramext.encode(value, p.type), wt.ext_type)

    def _param_problem(self, p: DefParam, value: float | int) -> str | None:
        if not _finite(value):
            # a REAL32/REAL64 PARAM_EXT_SET can carry NaN or an infinity; no setting has such a value (the
            # definition's own check refuses them too), and a stored NaN broke the relative zoom
            return "not a finite number"
        s = self._by_param.get(p.name)
        if s is not None:
            try:
                self._setting_value(s, float(value), False)
            except CommandRefused:
                return "not allowed by the catalogue"
            return None
        return p.check(value)


def new_wiris(camera: Camera, config: WirisConfig | None = None, *, now: float = 0.0,
              utc_offset_s: float = 0.0, definition_bytes: bytes | None = None) -> WirisState:
    """A WirisState whose parameter list is the catalogue camera's generated definition."""
    data = definition_bytes if definition_bytes is not None else definition_xml(camera)
    return WirisState(camera, parse_definition(data, camera.id), config, now=now, utc_offset_s=utc_offset_s,
                      ftp_files={definition_file_name(camera): data})


__all__ = ["WirisConfig", "WirisState", "new_wiris", "Captured", "Position"]
