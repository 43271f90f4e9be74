#!/usr/bin/env python3
"""MAVSDK 4.1.0 mission peers, run as a child process (MAVSDK can abort or wedge the process).

Modes (one JSON object per output line on stdout; items as dicts of MISSION_ITEM_INT fields):
  import --autopilot px4|ardupilot          stdin: .plan text -> {"ok", "mission", "fence", "rally", "error"}
      MissionRaw.import_qgroundcontrol_mission_from_string, offline: raw:// connection and one
      injected HEARTBEAT (reference mavsdk-as-test-peer.md §D).
  server --port P                           MAVSDK mission_raw_server as the vehicle (1/1) on
      udpin://127.0.0.1:P. Prints {"ready": true}, then {"incoming": result, "items": [...]} per
      upload. Exits when stdin closes. Never send it MISSION_COUNT 0 (it wedges, §C.4).
  client --port P [--timeout S]             MAVSDK mission_raw as the ground station on
      udpout://127.0.0.1:P. stdin: one JSON command per line:
      {"op": "upload", "items": [...]} -> {"op", "ok", "seconds", "error"}
      {"op": "download"} -> {"op", "ok", "seconds", "items", "error"}
      Prints {"ready": true} once it sees the autopilot.

HOME and TMPDIR should point to scratch directories (tests/mission_peers.py sets them).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

FIELDS = ("seq", "frame", "command", "current", "autocontinue", "param1", "param2", "param3", "param4", "x", "y",
          "z", "mission_type")


def out(obj) -> None:
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def to_dict(it) -> dict:
    return {f: getattr(it, f) for f in FIELDS}


def quiet_logs() -> None:
    from mavsdk import log_subscribe
    log_subscribe(lambda level, msg, file, line: True)


def _autopilot_known(system, autopilot: str) -> bool:
    from mavsdk.autopilot import Autopilot

    return system.autopilot_type() == (Autopilot.PX4 if autopilot == "px4" else Autopilot.ARDUPILOT)


def do_import(autopilot: str) -> None:
    from pymavlink.dialects.v20 import common as mav
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.mission_raw import MissionRaw, MissionRawError

    text = sys.stdin.read()
    m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    m.add_any_connection("raw://")
    enc = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    ap = mav.MAV_AUTOPILOT_PX4 if autopilot == "px4" else mav.MAV_AUTOPILOT_ARDUPILOTMEGA
    heartbeat = bytes(enc.heartbeat_encode(mav.MAV_TYPE_QUADROTOR, ap, 0, 0, mav.MAV_STATE_STANDBY).pack(enc))
    system = None
    # The system shows up before MAVSDK has taken the autopilot type from its heartbeat; importing then reads
    # the plan as for a generic autopilot (no home row for ArduPilot). Keep beating until the type is known.
    for _ in range(250):
        m.pass_received_raw_bytes(heartbeat)
        systems = m.get_systems()
        if systems and systems[0].has_autopilot() and _autopilot_known(systems[0], autopilot):
            system = systems[0]
            break
        time.sleep(0.02)
    if system is None:
        out({"ok": False, "error": "no system"})
        return
    try:
        r = MissionRaw(system).import_qgroundcontrol_mission_from_string(text)
        out({"ok": True, "mission": [to_dict(i) for i in r.mission_items],
             "fence": [to_dict(i) for i in r.geofence_items], "rally": [to_dict(i) for i in r.rally_items]})
    except MissionRawError as err:
        out({"ok": False, "error": getattr(getattr(err, "result", None), "name", None) or str(err)[:200]})
    m.destroy()


def do_server(port: int) -> None:
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.mission_raw_server import MissionRawServer

    m = Mavsdk(Configuration.create_with_component_type(ComponentType.AUTOPILOT))
    m.add_any_connection(f"udpin://127.0.0.1:{port}")
    server = MissionRawServer(m.server_component())

    def on_incoming(result, plan, _ud):
        out({"incoming": getattr(result, "name", str(result)), "items": [to_dict(i) for i in plan.mission_items]})

    server.subscribe_incoming_mission(on_incoming)
    out({"ready": True})
    for _line in sys.stdin:
        pass
    m.destroy()


def do_client(port: int, timeout: float | None) -> None:
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.mission_raw import MissionItem, MissionRaw, MissionRawError

    m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    m.add_any_connection(f"udpout://127.0.0.1:{port}")
    system = m.first_autopilot(15.0)
    if system is None:
        out({"ready": False, "error": "no autopilot"})
        return
    mr = MissionRaw(system)
    out({"ready": True})
    for line in sys.stdin:
        cmd = json.loads(line)
        t0 = time.monotonic()
        try:
            if cmd["op"] == "upload":
                items = [MissionItem(**{f: d[f] for f in FIELDS}) for d in cmd["items"]]
                mr.upload_mission(items)
                out({"op": "upload", "ok": True, "seconds": time.monotonic() - t0})
            elif cmd["op"] == "download":
                got = mr.download_mission()
                out({"op": "download", "ok": True, "seconds": time.monotonic() - t0,
                     "items": [to_dict(i) for i in got]})
        except MissionRawError as err:
            out({"op": cmd["op"], "ok": False, "seconds": time.monotonic() - t0,
                 "error": getattr(getattr(err, "result", None), "name", None) or str(err)[:200]})
    m.destroy()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["import", "server", "client"])
    ap.add_argument("--autopilot", default="px4")
    ap.add_argument("--port", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=None)
    a = ap.parse_args()
    quiet_logs()
    {"import": lambda: do_import(a.autopilot), "server": lambda: do_server(a.port),
     "client": lambda: do_client(a.port, a.timeout)}[a.mode]()


if __name__ == "__main__":
    main()
