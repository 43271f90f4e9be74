"""A ground-station client for any MAVLink camera (camera protocol v2): identify, definition, settings,
capture, and running a pre-flight command sequence.

    from wiris_tools.link import Link
    from wiris_tools.camera_client import CameraClient

    with Link("udpin:127.0.0.1:14550") as link:
        cam = CameraClient(link)                     # finds the camera by its HEARTBEAT
        info = cam.information()                     # CAMERA_INFORMATION (REQUEST_MESSAGE, falls back to 521)
        d = cam.definition(info)                     # download (http/https, bounded) + strict validation
        values = cam.read_settings(d.definition)     # PARAM_EXT_REQUEST_LIST, then reads of what is missing
        cam.set_setting(d.definition, "LAYOUT", "Blended")   # PARAM_EXT_SET, waits for PARAM_EXT_ACK
        for shot in cam.capture(interval_s=2, count=3): ...   # IMAGE_START_CAPTURE, CAMERA_IMAGE_CAPTURED
        cam.apply(load_setup("flight.setup.json"))   # each step acknowledged (or sent, where the camera
                                                     # answers nothing); stops at the first refusal

Every wait is bounded; errors are LinkError naming the step, setting or command and saying what to do.

Setup files (load_setup, parse_setup, steps_of_payload, Step) are read in wiris_tools.camera_setup.
"""

from __future__ import annotations

import difflib
import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.errors import CdfError
from cdf.validation import CameraInfo as ValidationInfo
from cdf.validation import validate_bytes
from cdf.xmlsafe import fetch_url
from wiris_tools import paramext
from wiris_tools.camera_definition import Definition, DefParam, parse_definition
from wiris_tools.errors import CommandRefused, LinkError, NoAnswer
from wiris_tools.link import IN_PROGRESS_TIMEOUTS, Link, command_name, result_name
from wiris_tools.mavftp import download
from wiris_tools.camera_setup import MESSAGE_GAP_S, Step, message_fields, nan_params

# also importable from here, where the rest of the tools import them
from wiris_tools.camera_setup import load_setup, parse_setup, steps_of_payload


CAMERA_COMPONENTS = range(mavlink2.MAV_COMP_ID_CAMERA, mavlink2.MAV_COMP_ID_CAMERA6 + 1)


class Target(NamedTuple):
    """The component a request goes to (and whose answers count)."""
    system: int
    component: int


@dataclass(frozen=True)
class CameraInformation:
    """What the camera's CAMERA_INFORMATION says. (cdf.validation's CameraInfo, built from it, is what the
    definition validator checks a definition against.)"""

    system: int
    component: int
    vendor: str
    model: str
    firmware_version: int
    focal_length_mm: float
    sensor_size_mm: tuple[float, float]
    resolution_px: tuple[int, int]
    lens_id: int
    flags: int
    definition_version: int
    definition_uri: str

    @property
    def flag_names(self) -> tuple[str, ...]:
        names = []
        for value, entry in sorted(mavlink2.enums["CAMERA_CAP_FLAGS"].items()):
            if value and value != max(mavlink2.enums["CAMERA_CAP_FLAGS"]) and self.flags & value == value:
                names.append(entry.name.removeprefix("CAMERA_CAP_FLAGS_"))
        return tuple(names)

    def to_json(self) -> dict:
        return {"system": self.system, "component": self.component, "vendor": self.vendor, "model": self.model,
                "firmware_version": self.firmware_version,
                "focal_length_mm": None if math.isnan(self.focal_length_mm) else self.focal_length_mm,
                "sensor_size_mm": list(self.sensor_size_mm), "resolution_px": list(self.resolution_px),
                "lens_id": self.lens_id, "flags": self.flags, "flag_names": list(self.flag_names),
                "definition_version": self.definition_version, "definition_uri": self.definition_uri}


@dataclass(frozen=True)
class LoadedDefinition:
    uri: str
    data: bytes
    definition: Definition
    report: Any            # cdf.validation.Report (strict profile)


@dataclass(frozen=True)
class Shot:
    index: int
    result: int
    file: str
    lat: int
    lon: int
    alt_mm: int
    time_utc_us: int

    def to_json(self) -> dict:
        return {"index": self.index, "ok": self.result == mavlink2.MAV_BOOL_TRUE, "file": self.file,
                "lat": self.lat / 1e7, "lon": self.lon / 1e7, "alt_m": self.alt_mm / 1000.0,
                "time_utc_us": self.time_utc_us}


@dataclass(frozen=True)
class StepResult:
    step: Step
    outcome: str
    detail: str = ""

    def to_json(self) -> dict:
        return {"step": self.step.number, "description": self.step.description, "kind": self.step.kind,
                "outcome": self.outcome, "detail": self.detail}


def _text(raw: Any) -> str:
    if isinstance(raw, (bytes, bytearray)):
        return bytes(raw).split(b"\0", 1)[0].decode("utf-8", errors="replace")
    if isinstance(raw, (list, tuple)):
        return bytes(int(b) & 0xFF for b in raw).split(b"\0", 1)[0].decode("utf-8", errors="replace")
    return str(raw).split("\0", 1)[0]


def _stopped(err: LinkError, where: str) -> LinkError:
    """The error that ends a command sequence at step `where`: the step's own error, its hint kept."""
    return LinkError(f"stopped the sequence: {err.message}", where=where, hint=err.hint)


# A camera that answers a request with these does not report that part (a camera without storage, an
# older one without capture status): `wiris camera info` says "not reported" and carries on.
_REFUSED = (mavlink2.MAV_RESULT_UNSUPPORTED, mavlink2.MAV_RESULT_DENIED)


def resolve_param(definition: Definition, name: str, camera: Any = None) -> DefParam:
    """The definition's parameter a person means by `name`: its PARAM_EXT name ("RANGE_MODE") in any case, or,
    with `camera` (the catalogue's entry of this camera), the name a capture plan gives it ("range_mode"):
    the same names a plan takes. LinkError with did-you-mean otherwise."""
    p = definition.param(name)
    if p is None and camera is not None:
        s = camera.setting_named(name)
        p = definition.param(s.param) if s is not None else None
    if p is None:
        folded = name.strip().casefold()
        p = next((q for q in definition.params if q.name.casefold() == folded), None)
    if p is not None:
        return p
    names = [q.name for q in definition.params]
    if camera is not None:
        names += [s.key for s in camera.settings if definition.param(s.param) is not None]
    close = _closest(name, names)
    raise LinkError(f"the camera's definition has no setting {name!r}",
                    hint=f"did you mean {close}?" if close else "see `wiris camera settings`")


def _closest(text: str, names: list[str]) -> str | None:
    """The name nearest `text`: as written first (RANGE_MOD -> RANGE_MODE, range_mod -> range_mode), then
    in any case."""
    close = difflib.get_close_matches(text.strip(), names, n=1)
    if close:
        return close[0]
    folded = {n.casefold(): n for n in reversed(names)}
    close = difflib.get_close_matches(text.strip().casefold(), list(folded), n=1)
    return folded[close[0]] if close else None


def _close_option(text: str, p: DefParam, setting: Any) -> str:
    """"did you mean 'Manual'? " for a near miss of an option label (or catalogue option name), else ""."""
    names = [o.label for o in p.options] + ([o.key for o in setting.options] if setting is not None else [])
    close = _closest(text, names)
    return f"did you mean {close!r}? " if close else ""


class CameraClient:
    """The camera side of a Link (see the module docstring)."""

    def __init__(self, link: Link, *, component: int | None = None, system: int | None = None,
                 find_timeout_s: float = 5.0, timeout_s: float = 1.0, retries: int = 3) -> None:
        self.link = link
        self.timeout_s = timeout_s
        self.retries = retries
        self.system, self.component = self._find(component, system, find_timeout_s)
        self.reported_types: dict[str, str] = {}     # parameter -> CDF type of the PARAM_EXT type it came with

    @property
    def camera(self) -> Target:
        """The camera this client found (a command sequence's steps may name other components)."""
        return Target(self.system, self.component)

    # -- discovery -----------------------------------------------------------------------------
    def _find(self, component: int | None, system: int | None, timeout_s: float) -> tuple[int, int]:
        deadline = time.monotonic() + timeout_s

        def pick() -> tuple[int, int] | None:
            for (s, c), hb in self.link.heartbeats().items():
                if (s, c) == (self.link.system, self.link.component):
                    continue
                if system is not None and s != system:
                    continue
                if component is not None:
                    if c == component:
                        return s, c
                elif hb.type == mavlink2.MAV_TYPE_CAMERA or c in CAMERA_COMPONENTS:
                    return s, c
            return None

        while True:
            found = pick()
            if found is not None:
                return found
            if time.monotonic() >= deadline:
                who = f"component {component}" if component is not None else "a camera (MAV_TYPE_CAMERA or component 100–105)"
                raise LinkError(f"no HEARTBEAT from {who} within {timeout_s:g} s", where=self.link.url,
                                hint="check the connection string and that the camera is powered; give --component "
                                     "if the camera uses another id")
            time.sleep(0.05)

    # -- requests ------------------------------------------------------------------------------
    def command(self, command: int, params: list[float | None], *, timeout_s: float | None = None) -> Any:
        return self.link.command_long(self.system, self.component, command, nan_params(params),
                                      timeout=timeout_s or self.timeout_s, retries=self.retries)

    def request(self, message: str, param2: float = 0.0, *, fallback: int | None = None,
                fallback_params: tuple[float, ...] = (), count: int = 1, wait_s: float | None = None) -> list[Any]:
        """Ask for `message` with REQUEST_MESSAGE (or the older dedicated command `fallback`, with
        `fallback_params` first and 0 after, when that is UNSUPPORTED) and return the copies that arrive (at
        least one, up to `count`).

        Unused params are common.xml's defaults: REQUEST_MESSAGE params 3-7 "by default assumed not used (0)"
        (param 7 = 0: the flight stack's default address), and the dedicated requests' "Reserved (default:0)".
        A request changes nothing, so NaN (the Workswell manual's "keep") has no meaning here; a strict camera
        refuses NaN where common.xml defines a MAV_BOOL ("values not equal to 0 or 1 are invalid")."""
        msg_id = getattr(mavlink2, f"MAVLINK_MSG_ID_{message}")
        wait = wait_s if wait_s is not None else self.timeout_s
        with self.link.inbox(message, src_system=self.system, src_component=self.component) as box:
            try:
                self.command(mavlink2.MAV_CMD_REQUEST_MESSAGE, [msg_id, param2, 0, 0, 0, 0, 0])
            except CommandRefused as err:
                if fallback is None or err.result != mavlink2.MAV_RESULT_UNSUPPORTED:
                    raise
                self.command(fallback, [*fallback_params, *[0.0] * (7 - len(fallback_params))])
            got = []
            first = box.get(wait)
            if first is None:
                raise LinkError(f"the camera acknowledged the request but sent no {message} within {wait:g} s",
                                where=f"component {self.component}", hint="the link may be losing packets; retry")
            got.append(first)
            while len(got) < count:
                more = box.get(wait)
                if more is None:
                    break
                got.append(more)
            return got

    def information(self) -> CameraInformation:
        try:
            # 521 param1: "Request camera capabilities (MAV_BOOL_TRUE)"
            m = self.request("CAMERA_INFORMATION", fallback=mavlink2.MAV_CMD_REQUEST_CAMERA_INFORMATION,
                             fallback_params=(mavlink2.MAV_BOOL_TRUE,))[0]
        except NoAnswer as err:
            hb = self.link.heartbeats().get((self.system, self.component))
            if hb is not None and hb.type != mavlink2.MAV_TYPE_CAMERA:
                raise LinkError(f"{err.message}; component {self.component} announces MAV_TYPE {hb.type}, not "
                                "MAV_TYPE_CAMERA", where=err.where,
                                hint="a MicaSense RedEdge speaks only its serial API (no camera protocol): set its "
                                     "parameters with `wiris camera apply` param_set steps (--mavlink1)") from None
            raise
        return CameraInformation(
            system=self.system, component=self.component, vendor=_text(m.vendor_name), model=_text(m.model_name),
            firmware_version=m.firmware_version, focal_length_mm=m.focal_length,
            sensor_size_mm=(m.sensor_size_h, m.sensor_size_v), resolution_px=(m.resolution_h, m.resolution_v),
            lens_id=m.lens_id, flags=m.flags, definition_version=m.cam_definition_version,
            definition_uri=_text(m.cam_definition_uri))

    def storage(self) -> list[dict] | None:
        """STORAGE_INFORMATION of every storage: asks for the first, then for the others it announces.

        None when the camera refuses the request (MAV_RESULT_UNSUPPORTED or DENIED: a camera without
        storage reporting); a storage it refuses to describe on its own is left out. Silence is still a
        LinkError: it says more about the link than about the camera."""
        def ask(param2: float, count: int, wait_s: float | None) -> list[Any] | None:
            # 525: param1 the storage id (0 for all in common.xml), param2 "Request storage information
            # (MAV_BOOL_TRUE). Values not equal to 0 or 1 are invalid", so 1 and never NaN
            try:
                return self.request("STORAGE_INFORMATION", param2,
                                    fallback=mavlink2.MAV_CMD_REQUEST_STORAGE_INFORMATION,
                                    fallback_params=(param2, mavlink2.MAV_BOOL_TRUE), count=count, wait_s=wait_s)
            except CommandRefused as err:
                if err.result in _REFUSED:
                    return None
                raise

        # param2 0: "0 for all" in common.xml; the Workswell manual numbers storages from 0 (its Storage ID),
        # so a WIRIS sends the first only, with storage_count, and the loop below asks for the others
        first = ask(0, 16, 0.3)
        if first is None:
            return None
        seen = {m.storage_id: m for m in first}
        count = max((m.storage_count for m in first), default=0)
        for sid in range(count):
            if sid not in seen and len(seen) < count:
                for m in ask(sid, 1, None) or ():
                    seen[m.storage_id] = m
        return [{"id": m.storage_id, "name": _text(m.name), "status": m.status, "type": m.type,
                 "total_mib": m.total_capacity, "used_mib": m.used_capacity, "available_mib": m.available_capacity}
                for _, m in sorted(seen.items())]

    def capture_status(self) -> dict | None:
        """CAMERA_CAPTURE_STATUS; None when the camera refuses the request (UNSUPPORTED or DENIED)."""
        try:
            # 527 param1: "Request camera capture status (MAV_BOOL_TRUE)"
            m = self.request("CAMERA_CAPTURE_STATUS", fallback=mavlink2.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS,
                             fallback_params=(mavlink2.MAV_BOOL_TRUE,))[0]
        except CommandRefused as err:
            if err.result in _REFUSED:
                return None
            raise
        return {"image_status": m.image_status, "video_status": m.video_status, "image_interval_s": m.image_interval,
                "recording_time_ms": m.recording_time_ms, "available_mib": m.available_capacity,
                "image_count": m.image_count}

    # -- the definition ------------------------------------------------------------------------
    def definition(self, info: CameraInformation, *, timeout_s: float = 10.0,
                   progress: Callable[[int, int], None] | None = None) -> LoadedDefinition:
        """Download the definition the camera names and validate it (strict profile). `progress(done, total)`
        is called during a MAVLink FTP download (slow on a 57600 baud serial link)."""
        uri = info.definition_uri
        if not uri:
            raise LinkError("the camera names no camera definition (empty cam_definition_uri)",
                            where=f"{info.vendor} {info.model}",
                            hint="its settings cannot be read through PARAM_EXT without one")
        scheme = uri.split("://", 1)[0].lower() if "://" in uri else ""
        if scheme in ("mftp", "mavlinkftp"):
            path = uri.split("://", 1)[1]
            # MAVLink FTP URL scheme (devguide ftp.md): an optional "comp=ID:" or QGC's "[;comp=ID]" prefix
            # names the component that serves the file; by default it is the camera itself.
            component, comp_text = self.component, ""
            if path.startswith("[;comp=") and "]" in path:
                comp_text, path = path[len("[;comp="):].split("]", 1)
            elif path.startswith("comp=") and ":" in path:
                comp_text, path = path[len("comp="):].split(":", 1)
            if comp_text.isdigit():
                component = int(comp_text)
                if component > 255:  # the camera's own radio says so: an error, not a crash in the encoder
                    raise LinkError(f"the definition URI names component {component}, not 0-255", where=uri,
                                    hint="the camera reports a broken cam_definition_uri")
            data = download(self.link, self.system, component, path, timeout_s=self.timeout_s,
                            retries=max(self.retries, 3), progress=progress)
        elif scheme in ("http", "https"):
            try:
                data = fetch_url(uri, timeout_s=timeout_s)
            except CdfError as err:
                raise LinkError(f"cannot download the camera definition: {err.message}",
                                where=uri, hint="is the camera's web server reachable from here?") from None
        else:
            raise LinkError(f"unsupported definition URI scheme {scheme or uri!r}", where=uri,
                            hint="cam_definition_uri must be http://, https:// or mftp://")
        report = validate_bytes(data, uri, "strict", camera_info=ValidationInfo(
            vendor_name=info.vendor, model_name=info.model, cam_definition_version=info.definition_version,
            cam_definition_uri=uri))
        try:
            parsed = parse_definition(data, uri)
        except CdfError as err:     # its message and place; its hint travels as ours
            what = f"{err.where}: {err.message}" if err.where else err.message
            raise LinkError(f"the camera's definition cannot be read: {what}", where=uri,
                            hint=err.hint or "see the validation findings (`wiris cdf validate URL`)") from None
        return LoadedDefinition(uri, data, parsed, report)

    # -- settings over PARAM_EXT ---------------------------------------------------------------
    def read_settings(self, definition: Definition, *, quiet_s: float | None = None) -> dict[str, float | int | None]:
        """Current value of every definition parameter (None when the camera never answered for it)."""
        values: dict[str, float | int | None] = {p.name: None for p in definition.params}
        quiet = quiet_s if quiet_s is not None else max(0.3, self.timeout_s / 2)
        with self.link.inbox("PARAM_EXT_VALUE", src_system=self.system, src_component=self.component) as box:
            self.link.send(self.link.mav.param_ext_request_list_encode(self.system, self.component))
            deadline = time.monotonic() + max(5.0, 4 * self.timeout_s)
            while time.monotonic() < deadline:
                m = box.get(quiet)
                if m is None:
                    break
                self._store(definition, values, m)
                if all(v is not None for v in values.values()):
                    break
            for p in definition.params:
                for _ in range(self.retries + 1):
                    if values[p.name] is not None:
                        break
                    self.link.send(self.link.mav.param_ext_request_read_encode(
                        self.system, self.component, p.name.encode(), -1))
                    end = time.monotonic() + self.timeout_s
                    while time.monotonic() < end and values[p.name] is None:
                        m = box.get(max(0.0, end - time.monotonic()))
                        if m is not None:
                            self._store(definition, values, m)
        return values

    def _store(self, definition: Definition, values: dict, m: Any) -> None:
        name = paramext.param_id(m)
        p = definition.param(name)
        if p is None:
            return
        wt = paramext.BY_EXT.get(m.param_type)
        self.reported_types[name] = wt.cdf if wt is not None else "custom"
        v = paramext.decode_ext(paramext.raw_value(m), m.param_type)
        if v is not None:
            values[name] = v

    def check_against_camera(self, loaded: LoadedDefinition, info: CameraInformation) -> Any:
        """Validate the definition again with what the camera answered (types, parameters it never
        answered: the validator's CDF3xx rules). Call after read_settings."""
        return validate_bytes(loaded.data, loaded.uri, "strict", camera_info=ValidationInfo(
            vendor_name=info.vendor, model_name=info.model, cam_definition_version=info.definition_version,
            cam_definition_uri=loaded.uri, param_types=dict(self.reported_types),
            answered=frozenset(self.reported_types)))

    @staticmethod
    def parse_value(p: DefParam, text: str, setting: Any = None) -> float | int:
        """An option label (any case), the catalogue's option name a plan writes (with `setting`, the camera's
        catalogue entry: "manual", "radiometric_jpeg+visible_jpeg"), or a number, checked against the
        definition."""
        option = next((o for o in p.options if o.label.lower() == text.strip().lower()), None)
        if option is not None:
            return option.value
        named = setting.option_named(text) if setting is not None else None
        if named is not None and any(o.value == named.value for o in p.options):
            return named.value
        try:
            number = float(text)
        except ValueError:
            choices = ", ".join(f"{o.label} ({o.value})" for o in p.options)
            raise LinkError(f"{text!r} is neither an option nor a number", where=p.name,
                            hint=_close_option(text, p, setting)
                            + (f"choose one of {choices}" if choices else "give a number")) from None
        value: float | int = int(number) if p.integer and number.is_integer() else number
        problem = p.check(value)
        if problem is not None:
            raise LinkError(f"{text} is {problem}", where=p.name,
                            hint="see `wiris camera settings` for the allowed values")
        return value

    def set_setting(self, definition: Definition, name: str, text: str, camera: Any = None) -> float | int:
        """PARAM_EXT_SET of setting `name` (see `resolve_param`) with the definition's type; waits for
        PARAM_EXT_ACK (retries); the value now held. `camera`: the catalogue's entry of this camera, whose
        plan names are taken too."""
        p = resolve_param(definition, name, camera)
        setting = camera.setting_by_param(p.name) if camera is not None else None
        value = self.parse_value(p, text, setting)
        return self.set_param_ext(p.name, value, p.type)

    def set_param_ext(self, name: str, value: float | int, cdf_type: str, *, where: str | None = None,
                      target: Target | None = None) -> float | int:
        """PARAM_EXT_SET to `target` (the camera unless told); waits for PARAM_EXT_ACK (retries); the value
        now held."""
        to = target or self.camera
        try:
            raw = paramext.encode(value, cdf_type)
            ext = paramext.wire_type(cdf_type).ext_type
        except paramext.WireValueError as err:
            raise LinkError(f"{name}: {err}", where=where or name,
                            hint="the definition gives this setting an unusable type or range: "
                                 "check it with `wiris cdf validate URL`") from None
        msg = self.link.mav.param_ext_set_encode(to.system, to.component, name.encode(), raw, ext)

        def ours(m: Any) -> bool:
            return paramext.param_id(m) == name

        busy_until: float | None = None    # as Link.command_long: IN_PROGRESS extends the wait, up to a cap
        with self.link.inbox("PARAM_EXT_ACK", src_system=to.system, src_component=to.component,
                             predicate=ours) as box:
            for _attempt in range(self.retries + 1):
                self.link.send(msg)
                deadline = time.monotonic() + self.timeout_s
                while True:
                    ack = box.get(max(0.0, deadline - time.monotonic()))
                    if ack is None:
                        if busy_until is not None and time.monotonic() >= busy_until:
                            limit = IN_PROGRESS_TIMEOUTS * self.timeout_s
                            raise LinkError(f"{name} = {value}: still not set {limit:g} s after the camera "
                                            "answered PARAM_ACK_IN_PROGRESS", where=where or name,
                                            hint="the camera reports the change as under way but never confirms "
                                                 "it; check the camera, or give a longer --timeout (the wait is "
                                                 f"capped at {IN_PROGRESS_TIMEOUTS} times the timeout)")
                        break
                    if ack.param_result == mavlink2.PARAM_ACK_IN_PROGRESS:
                        now = time.monotonic()
                        if busy_until is None:
                            busy_until = now + IN_PROGRESS_TIMEOUTS * self.timeout_s
                        deadline = min(now + self.timeout_s, busy_until)
                        continue
                    held = paramext.decode_ext(paramext.raw_value(ack), ack.param_type)
                    if ack.param_result == mavlink2.PARAM_ACK_ACCEPTED:
                        return held if held is not None else value
                    reason = mavlink2.enums["PARAM_ACK"][ack.param_result].name \
                        if ack.param_result in mavlink2.enums["PARAM_ACK"] else str(ack.param_result)
                    hint = {mavlink2.PARAM_ACK_VALUE_UNSUPPORTED: "the camera does not accept this value",
                            mavlink2.PARAM_ACK_FAILED: "the camera does not know this parameter or its type"}
                    raise LinkError(f"{name} = {value}: the camera answered {reason}"
                                    + (f" (it keeps {held})" if held is not None else ""),
                                    where=where or name,
                                    hint=hint.get(ack.param_result, "a result PARAM_ACK does not define: check the "
                                                                    "camera's firmware"))
        raise LinkError(f"{name}: no PARAM_EXT_ACK after {self.retries + 1} tries ({self.timeout_s:g} s each)",
                        where=where or name, hint="is the camera still connected? does it speak PARAM_EXT?")

    def set_param(self, name: str, value: float | int, cdf_type: str = "float", *,
                  where: str | None = None, target: Target | None = None) -> float | int:
        """Classic PARAM_SET (a RedEdge's parameters) to `target` (the camera unless told), the value byte-wise
        as `cdf_type` (the camera reads the 4 bytes as its parameter's type: paramext.encode_classic); the
        camera answers PARAM_VALUE with what it holds."""
        to = target or self.camera

        def ours(m: Any) -> bool:
            return m.param_id == name

        try:
            carried = paramext.encode_classic(value, cdf_type)
        except paramext.WireValueError as err:
            raise LinkError(f"{name}: {err}", where=where or name,
                            hint="a classic parameter is at most 4 bytes: uint8…int32 or float") from None
        msg = self.link.mav.param_set_encode(to.system, to.component, name.encode(), carried,
                                             paramext.classic_type(cdf_type))
        with self.link.inbox("PARAM_VALUE", src_component=to.component, predicate=ours) as box:
            for _attempt in range(self.retries + 1):
                self.link.send(msg)
                answer = box.get(self.timeout_s)
                if answer is not None:
                    held = paramext.decode_classic(answer.param_value, answer.param_type)
                    if held is None or not math.isclose(held, value, rel_tol=1e-6, abs_tol=1e-6):
                        shown = f"{held:g}" if held is not None else f"a value of type {answer.param_type}"
                        raise LinkError(f"{name} = {value}: the camera kept {shown}", where=where or name,
                                        hint="the value is outside what the camera accepts")
                    return held
        raise LinkError(f"{name}: no PARAM_VALUE after {self.retries + 1} tries ({self.timeout_s:g} s each)",
                        where=where or name, hint="is the camera connected, and is the parameter name right?")

    # -- capture -------------------------------------------------------------------------------
    def capture(self, *, interval_s: float = 0.0, count: int = 1, duration_s: float | None = None,
                image_timeout_s: float = 5.0) -> Iterator[Shot]:
        """IMAGE_START_CAPTURE, then each CAMERA_IMAGE_CAPTURED as it arrives (count 0: until `duration_s`)."""
        if count < 0 or interval_s < 0 or not math.isfinite(interval_s):
            raise LinkError("count and interval must not be negative", hint="e.g. --interval 2 --count 5")
        with self.link.inbox("CAMERA_IMAGE_CAPTURED", src_system=self.system, src_component=self.component) as box:
            # params 5-7 at common.xml's defaults (0, 0, NaN); the Workswell manual reads 0 in 5 (capture
            # flags) and 6 (storage + 1) as "keep", like NaN
            self.command(mavlink2.MAV_CMD_IMAGE_START_CAPTURE, [0, interval_s, count, 0, 0, 0, None])
            got = 0
            start = time.monotonic()
            try:
                while count == 0 or got < count:
                    if duration_s is not None and time.monotonic() - start >= duration_s:
                        break
                    wait = interval_s + image_timeout_s
                    if duration_s is not None:
                        wait = min(wait, max(0.0, duration_s - (time.monotonic() - start)))
                    m = box.get(wait)
                    if m is None:
                        if duration_s is not None and time.monotonic() - start >= duration_s:
                            break
                        raise LinkError(f"no CAMERA_IMAGE_CAPTURED within {wait:g} s ({got} of "
                                        f"{count or 'unlimited'} images so far)", where=f"component {self.component}",
                                        hint="is the camera still connected?")
                    shot = Shot(m.image_index, m.capture_result, _text(m.file_url), m.lat, m.lon, m.alt, m.time_utc)
                    yield shot
                    got += 1
                    if m.capture_result != mavlink2.MAV_BOOL_TRUE:
                        raise LinkError(f"the camera failed to capture image {m.image_index} (capture_result "
                                        f"{m.capture_result})", where=f"component {self.component}",
                                        hint="check its storage (`wiris camera info`)")
            finally:
                if count != 1:
                    try:
                        # param1 0 = "all cameras" (common.xml: a camera NACKs other values, NaN included,
                        # and a refused stop would leave it capturing); 5-6 default 0, the rest NaN
                        self.command(mavlink2.MAV_CMD_IMAGE_STOP_CAPTURE, [0, None, None, None, 0, 0, None])
                    except LinkError:
                        pass

    # -- command sequences ---------------------------------------------------------------------
    def apply(self, steps: list[Step], *, on_step: Callable[[StepResult], None] | None = None) -> list[StepResult]:
        """Run `steps` in order; LinkError naming the first step that is refused or not answered."""
        results = []
        for step in steps:
            result = self._run_step(step)
            results.append(result)
            if on_step is not None:
                on_step(result)
        return results

    def _system_of(self, component: int) -> int:
        """The system id of the component a step names (a RedEdge adopts ours; a WIRIS has its own)."""
        for (s, c) in self.link.heartbeats():
            if c == component and (s, c) != (self.link.system, self.link.component):
                return s
        return self.system

    def _target_of(self, step: Step) -> Target:
        """Whom a step is for: its target_component, on the system that component's HEARTBEAT comes from, or
        the camera connected to (target_component 0)."""
        component = step.target_component or self.component
        if component == self.component:
            return self.camera
        return Target(self._system_of(component), component)

    def _run_step(self, step: Step) -> StepResult:
        target = self._target_of(step)
        if step.kind == "command_long":
            return self._run_command_step(step, target)
        if step.kind == "message":
            return self._send_message(step, target)
        try:
            if step.kind == "param_ext_set":
                held = self.set_param_ext(step.param_id, step.value, step.type, where=step.label, target=target)
                return StepResult(step, "PARAM_ACK_ACCEPTED", f"{step.param_id} = {held:.7g}")
            held = self.set_param(step.param_id, step.value, step.type, where=step.label, target=target)
            return StepResult(step, "PARAM_VALUE", f"{step.param_id} = {held:g}")
        except LinkError as err:
            raise _stopped(err, step.label) from None

    def _run_command_step(self, step: Step, target: Target) -> StepResult:
        """A COMMAND_LONG step: done when the camera answers the result the step expects (ACCEPTED unless the
        setup file says otherwise)."""
        assert step.command is not None
        where = step.label
        expect = getattr(mavlink2, step.expect, mavlink2.MAV_RESULT_ACCEPTED)
        try:
            self.link.command_long(target.system, target.component, step.command, list(step.params),
                                   timeout=self.timeout_s, retries=self.retries)
        except CommandRefused as err:
            if err.result != expect:
                raise _stopped(err, where) from None
            return StepResult(step, result_name(err.result))
        except LinkError as err:
            raise _stopped(err, where) from None
        if expect != mavlink2.MAV_RESULT_ACCEPTED:
            raise LinkError(f"{where}: {command_name(step.command)} answered "
                            f"{result_name(mavlink2.MAV_RESULT_ACCEPTED)}, expected {step.expect}", where=where,
                            hint='the camera accepted it; if it should, set the step\'s "expect": '
                                 '{"result": "MAV_RESULT_ACCEPTED"}')
        return StepResult(step, result_name(mavlink2.MAV_RESULT_ACCEPTED))

    def _send_message(self, step: Step, target: Target) -> StepResult:
        """A message the camera answers with nothing (a RedEdge's DIGICAM_CONFIGURE): sent as many times as a
        request is tried, MESSAGE_GAP_S apart, so that one lost frame on a radio link does not lose the step
        (it sets absolute values, so a repeat changes nothing). Arrival cannot be confirmed, and the result
        says so. Refused when the camera speaks MAVLink 1 (a RedEdge) and the link does not: nothing would
        show that it dropped the MAVLink 2 frames."""
        hb = self.link.heartbeats().get(target)
        if hb is not None and not self.link.mavlink1 and hb.get_msgbuf()[:1] == bytes([mavlink2.PROTOCOL_MARKER_V1]):
            raise LinkError(f"component {target.component} speaks MAVLink 1 and does not answer {step.message}, so a "
                            "MAVLink 2 frame it cannot read would be lost without a trace; nothing was sent",
                            where=step.label, hint="run again with --mavlink1")
        values = dict.fromkeys(message_fields(step.message), 0)
        values.update(step.fields)
        msg = getattr(self.link.mav, f"{step.message.lower()}_encode")(target.system, target.component, **values)
        tries = self.retries + 1
        for n in range(tries):
            if n:
                time.sleep(MESSAGE_GAP_S)
            self.link.send(msg)
        return StepResult(step, "SENT", f"{step.message} sent {tries} times; the camera does not answer it, so "
                                        "its arrival is not confirmed")


__all__ = ["CameraClient", "CameraInformation", "LoadedDefinition", "Shot", "Step", "StepResult", "Target", "load_setup",
           "parse_setup", "steps_of_payload"]
