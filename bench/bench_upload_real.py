#!/usr/bin/env python3
"""Mission upload through bench/relay.py into real mission servers: ours vs MAVSDK's uploader vs the bound.

    WIRIS_SITL_DIR=/work/shared/sitl WIRIS_PX4_SITL_DIR=/work/shared/px4-sitl .venv/bin/python \
        bench/bench_upload_real.py [--servers mavsdk,sitl,px4]
        [--items 100] [--seed 25]

Servers: MAVSDK 4.1.0's mission_raw_server (in a child process, tests/mission_peers.py), ArduPilot SITL
arducopter at speedup 1 (its mission protocol timers run in real time), reached through its SERIAL2 as a UDP
client of the relay, and PX4 SITL (WIRIS_PX4_SITL_DIR) at speedup 1 on its payload link. Link: bench/relay.py, 57600 baud 8N1 each way, 20 ms each way, the loss on both
directions from the same seed for both uploaders. Ours: `wiris mission upload FILE.plan --json` (its own
upload time); MAVSDK: MissionRaw.upload_mission (the time of the call). Bound: bench_upload.lower_bound_s,
the bytes of the strict ping-pong at 57600 baud plus 2n+2 one-way latencies. ArduPilot gets n+1 items on
the wire (its home row) from both uploaders. Every number of a table comes from this one run.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "bench"))

import mission_peers  # noqa: E402
from bench_upload import BAUD, LATENCY_S, lower_bound_s, mission  # noqa: E402
from missions.formats.planfile import write_plan  # noqa: E402
from relay import Relay  # noqa: E402
from wiris_tools.readback import compare_items  # noqa: E402
from wiris_tools.transfer import home_item  # noqa: E402

SITL_UPLOAD_TIMEOUT_S = 10.0
# MavlinkMissionManager's transfer timeout (MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT, 5 s) with a margin
PX4_UPLOAD_TIMEOUT_S = 7.0


def ours(plan: Path, relay_port: int) -> tuple[float | None, str]:
    proc = subprocess.run([str(Path(sys.executable).with_name("wiris")), "mission", "upload", str(plan),
                           "--connect", f"udpout:127.0.0.1:{relay_port}", "--json", "--force"],
                          capture_output=True, text=True, timeout=900)
    if proc.returncode != 0:
        return None, proc.stderr.strip().splitlines()[0] if proc.stderr.strip() else f"exit {proc.returncode}"
    return json.loads(proc.stdout)["seconds"], "ok"


def theirs(items, relay_port: int, scratch: Path) -> tuple[float | None, str]:
    try:
        client = mission_peers.MavsdkClient(relay_port, scratch)
    except RuntimeError as err:
        return None, str(err)
    try:
        res = client.upload(items, timeout=900)
    finally:
        client.close()
    return (res["seconds"], "ok") if res.get("ok") else (None, str(res.get("error")))


class MavsdkVehicle:
    """A fresh mission_raw_server per upload (its state after a failed upload is its own business)."""
    name = "MAVSDK mission_raw_server"
    home_row = False

    def __init__(self, scratch: Path) -> None:
        self.scratch = scratch

    def run(self, upload, loss: float, seed: int, sent) -> tuple[float | None, str]:
        server = mission_peers.MavsdkServer(self.scratch)
        try:
            with Relay(server.port, loss=loss, seed=seed, baud=BAUD, latency_s=LATENCY_S) as relay:
                seconds, status = upload(relay.port)
            return (seconds, status) if status != "ok" else (seconds, self.check(server, sent))
        finally:
            server.close()

    @staticmethod
    def check(server, sent) -> str:
        """What the server reports it received, against what was sent ("ok" when they agree)."""
        got = server.incoming(timeout=5)
        if got is None:
            return "WRONG: the server reported no incoming mission"
        result, items = got
        if len(items) != len(sent):
            return f"WRONG: the server holds {len(items)} items ({result}), {len(sent)} were sent"
        try:
            compare_items(sent, items)
        except Exception as err:  # noqa: BLE001 - a bench reports, it does not stop
            return f"WRONG: {err}".splitlines()[0]
        return "ok"

    def close(self) -> None:
        pass


class SitlVehicle:
    """One ArduPilot SITL for all runs; a fresh relay (and so a fresh loss stream) per upload."""
    name = "ArduPilot SITL (arducopter)"
    home_row = True

    def __init__(self) -> None:
        from wiris_tools.sitl import SitlOptions, find_sitl_dir, start_sitl
        self.relay = Relay(loss=0.0, baud=BAUD, latency_s=LATENCY_S)
        self.sitl = start_sitl("ardupilot", find_sitl_dir(near=ROOT),
                               SitlOptions(speedup=1, camera_port=self.relay.vehicle_side))
        self.sitl.wait_ready(timeout=120)

    def run(self, upload, loss: float, seed: int, sent) -> tuple[float | None, str]:
        # The SITL sends to a fixed port: keep the relay's sockets, restart its loss stream and clocks.
        from relay import _Direction
        import random
        r = self.relay
        r.loss = loss
        r.up = _Direction(random.Random(f"{seed}-up"))
        r.down = _Direction(random.Random(f"{seed}-down"))
        r.gcs_peer = None
        seconds, status = upload(r.port)
        if status != "ok":
            # ArduPilot answers DENIED to a new MISSION_COUNT while a failed upload is still "receiving", until
            # its own upload timeout (8 s, MissionItemProtocol.cpp) gives up: the next run waits that out.
            time.sleep(SITL_UPLOAD_TIMEOUT_S)
        return seconds, status

    def close(self) -> None:
        self.sitl.close()
        self.relay.close()


class Px4Vehicle:
    """One PX4 SITL (SIH quad, speedup 1: its mission timers run in simulated time) for all runs, reached on its
    payload link (PX4 listens on 14280+N and answers the first address it hears from: the relay's vehicle
    side); a fresh loss stream per upload. The link's streams are turned off through the relay before the
    first run, so the radio carries the mission protocol and heartbeats only."""
    name = "PX4 SITL (sihsim_quadx)"
    home_row = False

    def __init__(self) -> None:
        from pymavlink.dialects.v20 import ardupilotmega as mavlink2

        from wiris_tools.link import Link
        from wiris_tools.sitl import SitlOptions, find_px4_dir, start_sitl
        from wiris_tools.sitl.px4 import ports
        self.sitl = start_sitl("px4", find_px4_dir(near=ROOT), SitlOptions(speedup=1))
        self.sitl.wait_ready(timeout=120)
        self.relay = Relay(ports(self.sitl.instance)["payload"], loss=0.0, baud=BAUD, latency_s=LATENCY_S)
        with Link(f"udpout:127.0.0.1:{self.relay.port}") as link:
            # PX4 learns the relay as its peer from the first packet
            link.send(link.mav.heartbeat_encode(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0))
            self.sitl.quieten(link)

    def run(self, upload, loss: float, seed: int, sent) -> tuple[float | None, str]:
        from relay import _Direction
        import random
        r = self.relay
        r.loss = loss
        r.up = _Direction(random.Random(f"{seed}-up"))
        r.down = _Direction(random.Random(f"{seed}-down"))
        r.gcs_peer = None
        seconds, status = upload(r.port)
        if status != "ok":
            time.sleep(PX4_UPLOAD_TIMEOUT_S)    # PX4 drops a half-done transfer after its own timeout
        return seconds, status

    def close(self) -> None:
        self.sitl.close()
        self.relay.close()


def fmt(v: float | None) -> str:
    return "fail" if v is None else f"{v:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--servers", default="mavsdk,sitl,px4")
    ap.add_argument("--items", type=int, default=100)
    ap.add_argument("--seed", type=int, default=25)
    ap.add_argument("--losses", default="0,5,20", help="loss levels in percent")
    a = ap.parse_args()
    rate = BAUD / 10.0
    print(f"# relay: {BAUD} baud 8N1 = {rate:.0f} B/s each way, {LATENCY_S * 1000:.0f} ms each way, seed {a.seed}")
    print("| server | loss | bound s | ours s | ours/bound | mavsdk s | mavsdk/bound | ours/mavsdk |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    notes = []
    with tempfile.TemporaryDirectory(prefix="bench-upload-real-") as tmp:
        scratch = Path(tmp)
        for name in a.servers.split(","):
            vehicle = (MavsdkVehicle(scratch) if name == "mavsdk" else Px4Vehicle() if name == "px4"
                       else SitlVehicle())
            try:
                body = mission(a.items)
                if vehicle.home_row:
                    # ArduPilot refuses IMAGE_START_CAPTURE with a NaN param4 (INVALID_PARAM4): send 0 there
                    body = [replace(it, param4=0.0) if math.isnan(it.param4) else it for it in body]
                wire = [home_item(None)] + body if vehicle.home_row else body
                plan = scratch / "bench.plan"
                plan.write_text(write_plan(body, None, firmware="ardupilot" if vehicle.home_row else "px4",
                                           vehicle="copter"))
                bound = lower_bound_s(wire, rate, LATENCY_S)
                for loss in [float(p) / 100 for p in a.losses.split(",")]:
                    seed = a.seed + int(loss * 100)
                    t_ours, s_ours = vehicle.run(lambda port: ours(plan, port), loss, seed, wire)
                    t_sdk, s_sdk = vehicle.run(lambda port: theirs(wire, port, scratch), loss, seed, wire)
                    for who, s in (("ours", s_ours), ("mavsdk", s_sdk)):
                        if s.startswith("WRONG"):
                            t_ours, t_sdk = (None, t_sdk) if who == "ours" else (t_ours, None)
                        if s != "ok":
                            notes.append(f"{vehicle.name}, {loss:.0%}, {who}: {s}")
                    rb = None if t_ours is None else t_ours / bound
                    mb = None if t_sdk is None else t_sdk / bound
                    om = None if t_ours is None or t_sdk is None else t_ours / t_sdk
                    print(f"| {vehicle.name} | {loss:.0%} | {bound:.2f} | {fmt(t_ours)} | {fmt(rb)} | {fmt(t_sdk)} | "
                          f"{fmt(mb)} | {fmt(om)} |", flush=True)
            finally:
                vehicle.close()
    for n in notes:
        print(f"note: {n}")


if __name__ == "__main__":
    main()
