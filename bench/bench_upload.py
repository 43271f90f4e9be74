#!/usr/bin/env python3
"""Mission upload over an emulated 57600-baud radio: ours vs the protocol's lower bound vs MAVSDK.

    .venv/bin/python bench/bench_upload.py [--quick] [--reps 3] [--trials 200] [--flavour px4|ardupilot]

Setup per row (items x loss): a PX4-like vehicle_sim (MISSION_REQUEST_INT, re-requests after
250 ms; `--flavour ardupilot`: legacy MISSION_REQUEST, 1 s re-requests, INVALID_SEQUENCE NACKs) behind tests/linkemu.py at 57600 baud 8N1 = 5760 bytes/s each way, 20 ms latency each
way, the given loss on both directions, seeded. Our uploader (`wiris mission upload FILE.plan
--json`, default spec timeouts; its own measured upload time) and MAVSDK 4.1.0's mission_raw
uploader (default 0.5 s timeout; the time of upload_mission()) each run in a child process and
get a fresh vehicle and an emulator with the same profile and seed. Every upload is checked
against what the vehicle stores. Each row is the median of --reps runs with different seeds (a
failed run ranks as slowest; "fail" when most runs failed).

Lower bound: the upload is a strict ping-pong of 2n+2 one-way messages
    MISSION_COUNT, then n x (MISSION_REQUEST_INT k, MISSION_ITEM_INT k), then MISSION_ACK
and none can leave before the previous one arrived, so with byte rate r and one-way latency L
    T_bound = (B_count + sum_k B_request(k) + sum_k B_item(k) + B_ack) / r + (2n + 2) * L
where B_* are the exact MAVLink 2 frame sizes (pymavlink packs them; MAVLink 2 trims trailing
zero bytes, so sizes vary per item). Heartbeats (1 Hz, ~21 bytes, both sides) and loss are not in
the bound: at 5 % and 20 % loss the ratio shows the cost of the losses.

At 0 % loss a third uploader runs for reference: a bare responder that answers each request with
pre-packed bytes and does nothing else (no retries, so only at 0 % loss). It measures the floor that
the vehicle_sim and the emulator set for any uploader on this link.

Also runs the 200-trial reliability check of tests/transfer_trials.py and prints its count.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from pymavlink.dialects.v20 import ardupilotmega as mavlink2  # noqa: E402

import mission_peers  # noqa: E402
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem  # noqa: E402
from missions.formats.planfile import write_plan  # noqa: E402
from linkemu import LinkEmulator, LinkProfile  # noqa: E402
from wiris_tools.readback import compare_items  # noqa: E402
from wiris_tools.transfer import home_item  # noqa: E402
from wiris_tools.vehicle_sim import VehicleSim  # noqa: E402

BAUD = 57600
LATENCY_S = 0.020


def mission(n: int) -> list[MissionItem]:
    out = []
    for i in range(n):
        if i % 10 == 5:
            out.append(MissionItem(command=mavlink2.MAV_CMD_IMAGE_START_CAPTURE, frame=FRAME_MISSION, param2=2.0,
                                   param4=math.nan))
        else:
            out.append(MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                                   param4=math.nan, x=490000000 + 1000 * i, y=160000000 + 700 * i, z=50.0))
    return out


def frame_bytes(msg) -> int:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    return len(msg.pack(mav))


def lower_bound_s(items: list[MissionItem], rate: float, latency: float) -> float:
    enc = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
    n = len(items)
    total = frame_bytes(enc.mission_count_encode(1, 1, n, 0))
    for k, it in enumerate(items):
        total += frame_bytes(enc.mission_request_int_encode(255, 190, k, 0))
        total += frame_bytes(enc.mission_item_int_encode(1, 1, k, it.frame, it.command, it.current, it.autocontinue,
                                                         it.param1, it.param2, it.param3, it.param4, it.x, it.y,
                                                         it.z, 0))
    total += frame_bytes(enc.mission_ack_encode(255, 190, 0, 0))
    return total / rate + (2 * n + 2) * latency


def profile(loss: float) -> LinkProfile:
    return LinkProfile.serial(BAUD, latency_s=LATENCY_S, loss=loss)


def ours(items: list[MissionItem], loss: float, seed: int, scratch: Path,
         flavour: str = "px4") -> tuple[float | None, str]:
    """`wiris mission upload` in a child process, like MAVSDK's uploader, so that neither shares
    the bench process (vehicle_sim + emulator) and its interpreter lock."""
    plan = scratch / f"bench-{len(items)}.plan"
    # `items` is the list on the wire; for ArduPilot its item 0 is the home row, which the file
    # keeps in plannedHomePosition and `wiris mission upload` puts back in front.
    plan.write_text(write_plan(items[1:] if flavour == "ardupilot" else items, None, firmware=flavour,
                               vehicle="copter"))
    with VehicleSim(flavour=flavour, item_limit=None, heartbeat_s=1.0) as sim, \
            LinkEmulator(sim.port, profile=profile(loss), seed=seed) as emu:
        proc = subprocess.run([str(Path(sys.executable).with_name("wiris")), "mission", "upload", str(plan),
                               "--connect", f"udpout:127.0.0.1:{emu.port}", "--json"],
                              capture_output=True, text=True, timeout=900)
        if proc.returncode != 0:
            return None, f"failed: {proc.stderr.strip().splitlines()[0] if proc.stderr.strip() else proc.returncode}"
        seconds = json.loads(proc.stdout)["seconds"]
        try:
            compare_items(items, sim.items())
        except Exception as err:  # noqa: BLE001 - a bench reports, it does not stop
            return None, f"WRONG: {err}".splitlines()[0]
        return seconds, "ok"


def mavsdk(items: list[MissionItem], loss: float, seed: int, scratch: Path,
           flavour: str = "px4") -> tuple[float | None, str]:
    with VehicleSim(flavour=flavour, item_limit=None, heartbeat_s=1.0) as sim, \
            LinkEmulator(sim.port, profile=profile(loss), seed=seed) as emu:
        try:
            client = mission_peers.MavsdkClient(emu.port, scratch)
        except RuntimeError as err:
            return None, f"failed: {err}"
        try:
            res = client.upload(items, timeout=900)
        finally:
            client.close()
        if not res.get("ok"):
            return None, f"failed: {res.get('error')}"
        try:
            compare_items(items, sim.items())
        except Exception as err:  # noqa: BLE001
            return None, f"WRONG: {err}".splitlines()[0]
        return res["seconds"], "ok"


# the bare responder: MISSION_COUNT, then each request answered with the pre-packed item, until MISSION_ACK
BARE_RESPONDER = """
import json, socket, struct, sys, time
port, frames = int(sys.argv[1]), [bytes.fromhex(h) for h in json.load(open(sys.argv[2]))]
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.connect(("127.0.0.1", port))
t0 = time.monotonic()
s.send(frames[0])
while True:
    data, i, done = s.recv(4096), 0, False
    while i + 10 <= len(data):
        if data[i] != 0xFD:
            i += 1
            continue
        size, msgid = data[i + 1], int.from_bytes(data[i + 7:i + 10], "little")
        if msgid in (40, 51):  # MISSION_REQUEST, MISSION_REQUEST_INT: seq is the first payload field
            s.send(frames[1 + struct.unpack_from("<H", data[i + 10:i + 10 + size] + bytes(2))[0]])
        done |= msgid == 47  # MISSION_ACK
        i += 12 + size + (13 if data[i + 2] & 1 else 0)
    if done:
        break
print(time.monotonic() - t0)
"""


def bare(items: list[MissionItem], seed: int, scratch: Path, flavour: str = "px4") -> tuple[float | None, str]:
    mav = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
    frames = [mav.mission_count_encode(1, 1, len(items), 0).pack(mav)]
    frames += [mav.mission_item_int_encode(1, 1, k, it.frame, it.command, it.current, it.autocontinue, it.param1,
                                           it.param2, it.param3, it.param4, it.x, it.y, it.z, 0).pack(mav)
               for k, it in enumerate(items)]
    path = scratch / "bare-frames.json"
    path.write_text(json.dumps([f.hex() for f in frames]))
    with VehicleSim(flavour=flavour, item_limit=None, heartbeat_s=1.0) as sim, \
            LinkEmulator(sim.port, profile=profile(0.0), seed=seed) as emu:
        try:
            proc = subprocess.run([sys.executable, "-c", BARE_RESPONDER, str(emu.port), str(path)],
                                  capture_output=True, text=True, timeout=300)
        except subprocess.TimeoutExpired:
            return None, "failed: timed out"
        if proc.returncode != 0:
            return None, f"failed: {proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else proc.returncode}"
        try:
            compare_items(items, sim.items())
        except Exception as err:  # noqa: BLE001
            return None, f"WRONG: {err}".splitlines()[0]
        return float(proc.stdout), "ok"


def median(values: list[float | None]) -> float | None:
    """Median of the runs; a failed run counts as slower than any success (None if most failed)."""
    ranked = sorted(values, key=lambda v: math.inf if v is None else v)
    return ranked[len(ranked) // 2]


def fmt(v: float | None, spec: str = ".2f") -> str:
    return "fail" if v is None else format(v, spec)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="100 items only")
    ap.add_argument("--trials", type=int, default=200, help="reliability trials (0 to skip)")
    ap.add_argument("--reps", type=int, default=3, help="runs per row (different seeds); medians are printed")
    ap.add_argument("--flavour", choices=["px4", "ardupilot"], default="px4",
                    help="vehicle_sim behaviour: px4 (re-requests after 250 ms) or ardupilot (legacy "
                         "MISSION_REQUEST, re-requests after 1 s, INVALID_SEQUENCE NACKs)")
    a = ap.parse_args()
    sizes = (100,) if a.quick else (100, 500)
    rate = BAUD / 10.0
    print(f"# link: {BAUD} baud 8N1 = {rate:.0f} B/s each way, {LATENCY_S * 1000:.0f} ms latency each way; "
          f"vehicle: vehicle_sim {a.flavour} flavour")
    print("| items | loss | ours s | bound s | ours/bound | mavsdk s | ours/mavsdk | bare responder s (floor) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    notes = []
    with tempfile.TemporaryDirectory(prefix="bench-upload-") as tmp:
        for n in sizes:
            items = mission(n)
            if a.flavour == "ardupilot":
                items = [home_item(None)] + items   # the same n+1 items on the wire for both uploaders
            bound = lower_bound_s(items, rate, LATENCY_S)
            for loss in (0.0, 0.05, 0.20):
                runs_ours, runs_sdk, runs_bare = [], [], []
                for rep in range(a.reps):
                    seed = 1000 * rep + n + int(loss * 100)   # the same seed for all uploaders
                    t_ours, s_ours = ours(items, loss, seed, Path(tmp), a.flavour)
                    t_sdk, s_sdk = mavsdk(items, loss, seed, Path(tmp), a.flavour)
                    t_bare, s_bare = bare(items, seed, Path(tmp), a.flavour) if loss == 0 else (None, "ok")
                    runs_ours.append(t_ours)
                    runs_sdk.append(t_sdk)
                    runs_bare.append(t_bare)
                    for who, s in (("ours", s_ours), ("mavsdk", s_sdk), ("bare responder", s_bare)):
                        if s != "ok":
                            notes.append(f"{n} items, {loss:.0%} loss, seed {seed}, {who}: {s}")
                t_ours, t_sdk = median(runs_ours), median(runs_sdk)
                ratio_b = None if t_ours is None else t_ours / bound
                ratio_m = None if t_ours is None or t_sdk is None else t_ours / t_sdk
                fails = f" ({runs_sdk.count(None)}/{a.reps} failed)" if None in runs_sdk else ""
                t_bare = median(runs_bare) if loss == 0 else None
                floor = f"{fmt(t_bare)} ({fmt(t_bare / bound if t_bare else None)}× bound)" if loss == 0 else "—"
                print(f"| {n} | {loss:.0%} | {fmt(t_ours)} | {bound:.2f} | {fmt(ratio_b)} | {fmt(t_sdk)}{fails} | "
                      f"{fmt(ratio_m)} | {floor} |", flush=True)
    for note in notes:
        print(f"note: {note}")
    if a.trials:
        from transfer_trials import run_trials
        t0 = time.monotonic()
        outs = run_trials(range(a.trials), workers=4)
        ok = sum(o.ok for o in outs)
        silent = sum(o.silent_corruption for o in outs)
        print(f"reliability: {a.trials} seeded trials (loss 0-30 %, dup 0-20 %, reorder 0-20 %, ArduPilot-/PX4-like): "
              f"{ok} verified identical, {a.trials - ok} clear LinkError, {silent} silent corruption "
              f"({time.monotonic() - t0:.0f} s)")


if __name__ == "__main__":
    main()
