"""The I/O shell around the pure camera states: a Link, a tick thread and (for WIRIS) the definition's HTTP server.

    with start_emulator("wiris-pro", "udpin:127.0.0.1:0") as emu:    # or udpout:127.0.0.1:14550 to a GCS
        port = emu.link.local_port
        emu.definition_uri                                            # http://127.0.0.1:PORT/workswell_...xml
        with emu.lock: emu.state.values["RANGE_MODE"]                 # the camera's state, for tests

The HTTP server answers GET/HEAD of the definition's path only (404 for anything else) and binds to
127.0.0.1 unless told otherwise.
"""

from __future__ import annotations

import http.server
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.catalogue import Camera, catalogue
from cdf.errors import CdfError
from cdf.generate import definition_file_name, definition_xml
from wiris_tools.camera_definition import parse_definition
from wiris_tools.emulate.rededge import RedEdgeState
from wiris_tools.emulate.wiris import DEFINITION_URI_CHARS, WirisConfig, WirisState
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.serve import IDLE_TIMEOUT_S, bind_http, host_port

TICK_S = 0.02
WAIT_STEP_S = 0.1  # how soon wait() notices a close() from another thread (signals cut a step short)


class _DefinitionServer:
    def __init__(self, body: bytes, path: str, host: str, port: int) -> None:
        served_path = "/" + path

        class Handler(http.server.BaseHTTPRequestHandler):
            server_version = "wiris-emulator"
            sys_version = ""
            timeout = IDLE_TIMEOUT_S  # a stalled client must not hold a thread for ever (see wiris_tools.serve)

            def _answer(self, with_body: bool) -> None:
                if self.path.split("?", 1)[0] != served_path:
                    self.send_error(404, "only the camera definition is served here")
                    return
                self.send_response(200)
                self.send_header("Content-Type", "application/xml")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                if with_body:
                    self.wfile.write(body)

            def do_GET(self) -> None:  # noqa: N802 (http.server API)
                self._answer(True)

            def do_HEAD(self) -> None:  # noqa: N802
                self._answer(False)

            def log_message(self, *args: object) -> None:
                pass

        self.httpd = bind_http(http.server.ThreadingHTTPServer, host, port, Handler,
                               what="serve the camera definition", host_option="--http-host",
                               port_option="--http-port")
        self.httpd.daemon_threads = True
        self.port = self.httpd.server_address[1]
        self.uri = f"http://{host_port(host, self.port)}{served_path}"
        # shutdown() waits for the loop's next poll: 0.5 s by default, every time an emulator stops
        self._thread = threading.Thread(target=self.httpd.serve_forever, args=(0.05,), name="cdf-http", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()


@dataclass
class Emulator:
    camera: Camera
    state: Any
    link: Any
    lock: threading.Lock
    definition_uri: str = ""
    definition: bytes = b""
    _http: _DefinitionServer | None = None
    _stop: threading.Event = field(default_factory=threading.Event)
    _thread: threading.Thread | None = None
    errors: int = 0           # exceptions inside the camera logic (a bug; tests assert there are none)
    send_failures: int = 0    # nothing to send to yet (udpin before the first packet)

    def _send_all(self, out: list) -> None:
        system = getattr(self.state, "system_id", None)
        if system is not None:
            self.link.mav.srcSystem = system     # a RedEdge adopts its peer's system id
        for msg in out:
            try:
                self.link.send(msg)
            except LinkError:
                self.send_failures += 1
            except Exception:  # a message the camera logic filled wrongly (a field out of range): a bug, counted
                self.errors += 1

    def _on_message(self, msg: Any) -> None:
        with self.lock:
            try:
                out = self.state.handle(msg, time.monotonic())
            except Exception:  # an emulator bug must not take the link down; counted for tests
                self.errors += 1
                return
            self._send_all(out)

    def _tick_loop(self) -> None:
        while not self._stop.is_set():
            with self.lock:
                try:
                    out = self.state.tick(time.monotonic())
                except Exception:
                    self.errors += 1
                    out = []
                self._send_all(out)
            self._stop.wait(TICK_S)

    def wait(self, duration_s: float | None = None) -> None:
        """Block until close() (or `duration_s` seconds; None = forever).

        Sleeps in short steps instead of blocking in self._stop.wait: Ctrl-C and SIGTERM raise
        KeyboardInterrupt wherever the main thread is, and raised inside Event.wait it can leave the
        Event's lock held, so that close() then hangs for ever (seen once in 40 SIGTERMs). A sleep holds
        no lock, and a signal cuts it short at once."""
        deadline = None if duration_s is None else time.monotonic() + duration_s
        while not self._stop.is_set():  # is_set reads a flag: no lock
            left = WAIT_STEP_S if deadline is None else min(WAIT_STEP_S, deadline - time.monotonic())
            if left <= 0:
                return
            time.sleep(left)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2)
        self.link.close()
        if self._http is not None:
            self._http.close()

    def __enter__(self) -> "Emulator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass(frozen=True)
class _Clock:
    """The states' clock (time.monotonic) at start, and what to add to it for UTC."""
    now: float
    utc_offset_s: float

    @classmethod
    def read(cls) -> "_Clock":
        now = time.monotonic()
        return cls(now, time.time() - now)


@dataclass(frozen=True)
class _WirisSetup:
    """How start_emulator sets up a WIRIS (a RedEdge takes only its component and the signing key)."""
    component: int | None = None
    system: int = 1
    http_port: int = 0
    http_host: str = "127.0.0.1"
    signing_key: bytes | None = None
    storage_capacity_mib: tuple[float, float, float] | None = None
    image_size_mib: float | None = None
    ethernet_sdk: bool = False
    licensed: bool = True
    definition: bytes | None = None
    definition_scheme: str = "http"

    def config(self, component: int, uri: str) -> WirisConfig:
        optional: dict[str, Any] = {}       # WirisConfig's own defaults unless given
        if self.storage_capacity_mib is not None:
            optional["storage_capacity_mib"] = tuple(self.storage_capacity_mib)
        if self.image_size_mib is not None:
            optional["image_size_mib"] = self.image_size_mib
        return WirisConfig(system=self.system, component=component, definition_uri=uri, licensed=self.licensed,
                           ethernet_sdk=self.ethernet_sdk, stream_host=self.http_host, **optional)


def start_emulator(model: str, url: str, *, component: int | None = None, system: int = 1,
                   http_port: int = 0, http_host: str = "127.0.0.1", signing_key: bytes | None = None,
                   storage_capacity_mib: tuple[float, float, float] | None = None, image_size_mib: float | None = None,
                   ethernet_sdk: bool = False, licensed: bool = True, definition: bytes | None = None,
                   definition_scheme: str = "http") -> Emulator:
    """Start the emulator of catalogue camera `model` on connection `url` (see the module docstring)."""
    camera = catalogue().get(model)
    clock = _Clock.read()
    if camera.protocol == "rededge-serial":
        emu = _start_rededge(camera, model, url, component, signing_key, clock)
    else:
        setup = _WirisSetup(component, system, http_port, http_host, signing_key, storage_capacity_mib,
                           image_size_mib, ethernet_sdk, licensed, definition, definition_scheme)
        emu = _start_wiris(camera, model, url, setup, clock)
    emu.link.subscribe(emu._on_message)
    emu._thread = threading.Thread(target=emu._tick_loop, name=f"emulator {model}", daemon=True)
    emu._thread.start()
    return emu


def _start_rededge(camera: Camera, model: str, url: str, component: int | None, signing_key: bytes | None,
                   clock: _Clock) -> Emulator:
    if component is not None and component != camera.default_component_id:
        raise CdfError(f"a {camera.model} always uses component {camera.default_component_id}",
                       where=model, hint="drop --component")
    state = RedEdgeState(camera, now=clock.now, utc_offset_s=clock.utc_offset_s)
    link = Link(url, system=state.system_id, component=state.component, mav_type=mavlink2.MAV_TYPE_GENERIC,
                heartbeat_s=0, mavlink1=camera.mavlink_version == 1, signing_key=signing_key)
    return Emulator(camera, state, link, threading.Lock())


def _start_wiris(camera: Camera, model: str, url: str, setup: _WirisSetup, clock: _Clock) -> Emulator:
    comp = camera.default_component_id if setup.component is None else setup.component
    if comp not in camera.component_ids:
        raise CdfError(f"component id {comp} is not one a {camera.model} can use",
                       where=model, hint=f"choose one of {', '.join(map(str, camera.component_ids))} (§3.2)")
    body = setup.definition if setup.definition is not None else definition_xml(camera)
    parsed = parse_definition(body, model)
    if setup.definition_scheme not in ("http", "mftp"):
        raise CdfError(f"unknown definition transport {setup.definition_scheme!r}", hint="use http or mftp")
    file_name = definition_file_name(camera)
    http = _DefinitionServer(body, file_name, setup.http_host, setup.http_port)
    uri = http.uri if setup.definition_scheme == "http" else f"mftp://{file_name}"
    try:  # the server is up: closed again if the camera cannot start
        if len(uri) > DEFINITION_URI_CHARS:
            raise CdfError(f"definition URI is {len(uri)} characters; CAMERA_INFORMATION holds {DEFINITION_URI_CHARS}",
                           where=uri, hint="use a shorter --http-host")
        state = WirisState(camera, parsed, setup.config(comp, uri), now=clock.now, utc_offset_s=clock.utc_offset_s,
                           ftp_files={file_name: body})
        link = Link(url, system=setup.system, component=comp, mav_type=mavlink2.MAV_TYPE_CAMERA, heartbeat_s=0,
                    signing_key=setup.signing_key)
    except BaseException:
        http.close()
        raise
    return Emulator(camera, state, link, threading.Lock(), uri, body, http)
