"""Worker process for peers.mavsdk_load_definitions: the real MAVSDK camera plugin loads CDFs one after another.

Run by peers.py as a subprocess (MAVSDK may crash the whole process on a bad definition; the parent
restarts the worker and records the crash). Protocol: one JSON job per stdin line
`{"job": int, "path": str, "model": str}`; one result per job on stdout as a line `@@RESULT <json>`.

Per job: an http.server on 127.0.0.1 (port 0) serves the XML, a pymavlink camera (sysid 1, compid 100,
MAV_TYPE_CAMERA) on udpin 127.0.0.1:0 answers REQUEST_MESSAGE(CAMERA_INFORMATION / CAMERA_SETTINGS /
STORAGE_INFORMATION / CAMERA_CAPTURE_STATUS), PARAM_EXT_REQUEST_LIST/READ (the file's defaults, encoded
by the file's type) and PARAM_EXT_SET; a fresh MAVSDK ground station connects with udpout to that port.
The model name is unique per job, so MAVSDK's definition cache (keyed by vendor+model+version under
$HOME, which the parent points at a scratch directory) can never serve an earlier file.
"""

from __future__ import annotations

import http.server
import json
import os
import re
import struct
import sys
import threading
import time
from pathlib import Path

os.environ.setdefault("MAVLINK20", "1")

from lxml import etree  # noqa: E402
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

# CDF type -> (MAV_PARAM_EXT_TYPE, struct format); bool travels as uint8 (QGC QGCCameraIO.cc).
WIRE = {
    "bool": (mav.MAV_PARAM_EXT_TYPE_UINT8, "<B"), "uint8": (mav.MAV_PARAM_EXT_TYPE_UINT8, "<B"),
    "int8": (mav.MAV_PARAM_EXT_TYPE_INT8, "<b"), "uint16": (mav.MAV_PARAM_EXT_TYPE_UINT16, "<H"),
    "int16": (mav.MAV_PARAM_EXT_TYPE_INT16, "<h"), "uint32": (mav.MAV_PARAM_EXT_TYPE_UINT32, "<I"),
    "int32": (mav.MAV_PARAM_EXT_TYPE_INT32, "<i"), "uint64": (mav.MAV_PARAM_EXT_TYPE_UINT64, "<Q"),
    "int64": (mav.MAV_PARAM_EXT_TYPE_INT64, "<q"), "float": (mav.MAV_PARAM_EXT_TYPE_REAL32, "<f"),
    "double": (mav.MAV_PARAM_EXT_TYPE_REAL64, "<d"),
}
MARK = "@@RESULT "


def _file_params(data: bytes) -> list[tuple[str, str, bytes]]:
    """(name, type, 128-byte wire value of the default) for every parameter we can encode."""
    # MAVSDK reads UTF-8 whatever the declaration says: so does the camera (UTF-8 declared as UTF-16)
    data = re.sub(rb'^(\s*<\?xml[^>]*encoding\s*=\s*["\'])[A-Za-z0-9._-]+', rb"\1UTF-8", data, count=1) \
        if not data.startswith((b"\xff\xfe", b"\xfe\xff")) else data
    try:
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True,
                                                     load_dtd=False, recover=True))
    except etree.XMLSyntaxError:
        return []
    if root is None:
        return []
    out = []
    for p in root.iter("parameter"):
        name = (p.get("name") or "")[:16]
        ptype = (p.get("type") or "").lower()
        if not name:
            continue
        if ptype in WIRE:
            fmt = WIRE[ptype][1]
            try:
                text = p.get("default", "0")
                val = float(text) if fmt in ("<f", "<d") else int(float(text))
                raw = struct.pack(fmt, val)
            except (ValueError, struct.error, OverflowError):
                raw = struct.pack(fmt, 0)
        else:
            raw = (p.get("default") or "").encode()[:128]
        out.append((name, ptype, raw.ljust(128, b"\0")))
    return out


class FakeCamera:
    """A pymavlink camera that lives for one job."""

    def __init__(self, data: bytes, model: str, events: list) -> None:
        self.data = data
        self.model = model
        self.events = events
        self.params = _file_params(data)
        self.requested: list[str] = []
        self.stop = threading.Event()
        body = data

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802 (http.server API)
                self.send_response(200)
                self.send_header("Content-Type", "application/xml")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)
                events.append("http GET " + self.path)

            def log_message(self, *a):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.uri = f"http://127.0.0.1:{self.httpd.server_address[1]}/{model.replace(' ', '_')}.xml"
        self.conn = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=1, source_component=100,
                                               dialect="common")
        self.conn.mav.robust_parsing = True
        self.port = self.conn.port.getsockname()[1]
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        self.httpd.shutdown()
        self.httpd.server_close()
        self.conn.close()

    def _send_param(self, i: int) -> None:
        name, ptype, raw = self.params[i]
        ext = WIRE[ptype][0] if ptype in WIRE else mav.MAV_PARAM_EXT_TYPE_CUSTOM
        self.conn.mav.param_ext_value_send(name.encode(), raw, ext, len(self.params), i)

    def _run(self) -> None:
        m = self.conn
        last_hb = 0.0
        t0 = time.time()
        while not self.stop.is_set():
            now = time.time()
            if now - last_hb >= 1.0 and m.port.getsockname() and getattr(m, "last_address", None):
                m.mav.heartbeat_send(mav.MAV_TYPE_CAMERA, mav.MAV_AUTOPILOT_INVALID, 0, 0, mav.MAV_STATE_ACTIVE)
                last_hb = now
            msg = m.recv_match(blocking=True, timeout=0.05)
            if msg is None:
                continue
            mt = msg.get_type()
            if mt in ("BAD_DATA", "HEARTBEAT"):
                if mt == "HEARTBEAT" and now - last_hb >= 1.0:
                    m.mav.heartbeat_send(mav.MAV_TYPE_CAMERA, mav.MAV_AUTOPILOT_INVALID, 0, 0,
                                         mav.MAV_STATE_ACTIVE)
                    last_hb = now
                continue
            if getattr(msg, "target_component", None) not in (None, 0, 100):
                continue
            ms = int((now - t0) * 1000)
            if mt == "COMMAND_LONG":
                cmd, p1 = msg.command, int(msg.param1)
                result, after = mav.MAV_RESULT_ACCEPTED, None
                if cmd == mav.MAV_CMD_REQUEST_CAMERA_INFORMATION or (
                        cmd == mav.MAV_CMD_REQUEST_MESSAGE and p1 == mav.MAVLINK_MSG_ID_CAMERA_INFORMATION):
                    flags = (mav.CAMERA_CAP_FLAGS_CAPTURE_IMAGE | mav.CAMERA_CAP_FLAGS_HAS_MODES)
                    after = lambda: m.mav.camera_information_send(  # noqa: E731
                        ms, b"WirisPeer".ljust(32, b"\0"), self.model.encode().ljust(32, b"\0"),
                        0x01000000, 13.0, 10.88, 8.704, 640, 512, 0, flags, 1, self.uri.encode(), 0, 0)
                elif cmd == mav.MAV_CMD_REQUEST_MESSAGE and p1 == mav.MAVLINK_MSG_ID_CAMERA_SETTINGS:
                    after = lambda: m.mav.camera_settings_send(ms, mav.CAMERA_MODE_IMAGE, 1.0,  # noqa: E731
                                                               float("nan"))
                elif cmd == mav.MAV_CMD_REQUEST_MESSAGE and p1 == mav.MAVLINK_MSG_ID_STORAGE_INFORMATION:
                    after = lambda: m.mav.storage_information_send(  # noqa: E731
                        ms, 1, 1, 2, 64000.0, 1000.0, 63000.0, 0.0, 0.0)
                elif cmd == mav.MAV_CMD_REQUEST_MESSAGE and p1 == mav.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS:
                    after = lambda: m.mav.camera_capture_status_send(ms, 0, 0, 0.0, 0, 63000.0, 0)  # noqa: E731
                else:
                    result = mav.MAV_RESULT_UNSUPPORTED
                m.mav.command_ack_send(cmd, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())
                if after:
                    after()
            elif mt == "PARAM_EXT_REQUEST_LIST":
                for i in range(len(self.params)):
                    self._send_param(i)
            elif mt == "PARAM_EXT_REQUEST_READ":
                name = msg.param_id
                self.requested.append(name)
                names = [p[0] for p in self.params]
                if 0 <= msg.param_index < len(names):
                    self._send_param(msg.param_index)
                elif name in names:
                    self._send_param(names.index(name))
            elif mt == "PARAM_EXT_SET":
                m.mav.param_ext_ack_send(msg.param_id.encode(), msg._param_value_raw, msg.param_type,
                                         mav.PARAM_ACK_ACCEPTED)


def run_job(job: dict) -> dict:
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.camera import Camera, CameraError, Setting

    data = Path(job["path"]).read_bytes()
    wait_s = float(job.get("wait_s", 12.0))
    log: list[str] = []
    events: list[str] = []
    cam = FakeCamera(data, job["model"], events)
    # the MAVSDK log callback is process-global: route it to this job's list
    CURRENT_LOG[0] = log
    gcs = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        gcs.add_any_connection(f"udpout://127.0.0.1:{cam.port}")
        system = None
        deadline = time.time() + wait_s
        while time.time() < deadline and system is None:
            systems = gcs.get_systems()
            system = systems[0] if systems else None
            time.sleep(0.02)
        if system is None:
            return {"outcome": "no-system", "log": log, "events": events}
        camera = Camera(system)
        outcome = None
        loaded_at = None
        while time.time() < deadline:
            text = "\n".join(log)
            if "Failed to load camera definition" in text or "Could not load camera definition" in text:
                outcome = "rejected"
                break
            if loaded_at is None and ("Cached path:" in text or "Using cached file" in text):
                loaded_at = time.time()  # parse runs right after the file lands in the cache
            if loaded_at is not None and time.time() - loaded_at > 0.3:
                try:
                    camera.get_possible_setting_options(100)
                    outcome = "accepted"
                    break
                except CameraError:
                    pass
            time.sleep(0.05)
        if outcome is None:
            return {"outcome": "timeout", "log": log, "events": events}
        if outcome == "rejected":
            return {"outcome": outcome, "log": log, "events": events}
        # Let the per-parameter PARAM_EXT_REQUEST_READ round-trips settle.
        settle_end = time.time() + 3.0
        last = -1
        while time.time() < settle_end:
            if len(cam.requested) == last and len(cam.requested) > 0:
                break
            last = len(cam.requested)
            time.sleep(0.4)
        settings = {}
        for so in camera.get_possible_setting_options(100):
            settings[so.setting_id] = [o.option_id for o in so.options]
        known = {}
        for name, _t, _raw in cam.params:
            before = len(log)
            try:
                got = camera.get_setting(100, Setting(setting_id=name))
                known[name] = got.option.option_id
            except CameraError as err:
                # "Unknown setting to get" = not in the parsed definition; other errors (e.g. the setting is
                # excluded by the current value) still mean MAVSDK parsed it
                known[name] = None if any("Unknown setting" in x for x in log[before:]) else f"error:{err}"
        return {"outcome": outcome, "settings": settings, "known": known,
                "requested": sorted(set(cam.requested)), "log": log, "events": events}
    finally:
        CURRENT_LOG[0] = []
        gcs.destroy()
        cam.close()


CURRENT_LOG: list[list[str]] = [[]]


def main() -> None:
    import mavsdk

    def on_log(level, msg, file, line):
        CURRENT_LOG[0].append(f"[{level.name}] {msg}")
        return True

    mavsdk.log_subscribe(on_log)
    for line in sys.stdin:
        if not line.strip():
            continue
        job = json.loads(line)
        print(f"@@START {job['job']}", flush=True)
        try:
            res = run_job(job)
        except Exception as err:  # report, keep serving the next job
            res = {"outcome": "harness-error", "error": f"{type(err).__name__}: {err}", "log": []}
        res["job"] = job["job"]
        sys.stdout.write(MARK + json.dumps(res) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
