"""Seeded upload + read-back trials through the link emulator (used by tests/link/test_reliability.py
and bench/bench_upload.py).

    outcome = run_trial(seed)      # Outcome(seed, ok, silent_corruption, error, ...)

Each trial builds its own vehicle_sim, link emulator and ground-station Link (fresh sockets, so no
packet of one trial can reach another), draws loss / duplication / reordering levels, a vehicle
flavour and a small random mission from random.Random(seed) - half the vehicles giving items back
as their firmware does (vehicle_sim stores_like_firmware), so the read-back is judged as the
firmware keeps items - runs MissionClient.upload_verified and then compares what the vehicle
really stores with what was sent. "Silent corruption" is the
one outcome that must never happen: upload_verified reporting success while the vehicle holds
something else.
"""

from __future__ import annotations

import math
import random
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from missions.emit.items import MissionItem
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from linkemu import LinkEmulator, LinkProfile
from wiris_tools.transfer import MissionClient, Timeouts
from wiris_tools.vehicle_sim import VehicleSim

LOSS = (0.0, 0.05, 0.1, 0.2, 0.3)
DUP = (0.0, 0.05, 0.2)
REORDER = (0.0, 0.05, 0.2)
# Short everything so 200 trials take seconds: localhost latencies of a few ms.
TRIAL_TIMEOUTS = Timeouts(ack_s=0.4, item_s=0.08, retries=6, nack_grace_s=0.6, min_rto_s=0.01, first_s=0.1)


@dataclass(frozen=True)
class Outcome:
    seed: int
    ok: bool
    silent_corruption: bool
    error: str
    items: int
    loss: float
    duplicate: float
    reorder: float
    flavour: str


def random_mission(rng: random.Random) -> list[MissionItem]:
    out = []
    for i in range(rng.randint(1, 12)):
        if rng.random() < 0.2:
            out.append(MissionItem(command=2000, frame=2, param2=rng.choice([0.0, 2.0]), param3=rng.randint(0, 3),
                                   param4=math.nan))
        else:
            out.append(MissionItem(command=16, frame=rng.choice([0, 3, 10]), param1=rng.choice([0.0, 2.5]),
                                   param4=math.nan, x=rng.randint(-900000000, 900000000),
                                   y=rng.randint(-1800000000, 1800000000), z=round(rng.uniform(5, 120), 2)))
    return out


def run_trial(seed: int) -> Outcome:
    rng = random.Random(seed)
    loss, dup, reorder = rng.choice(LOSS), rng.choice(DUP), rng.choice(REORDER)
    flavour = rng.choice(["ardupilot", "px4"])
    nack_rate = 0.1 if flavour == "ardupilot" and rng.random() < 0.5 else 0.0
    items = random_mission(rng)
    like_firmware = rng.random() < 0.5
    profile = LinkProfile(latency_s=rng.choice([0.001, 0.003, 0.006]), loss=loss, duplicate=dup, reorder=reorder,
                          reorder_delay_s=0.01)
    with VehicleSim(flavour=flavour, seed=seed, nack_rate=nack_rate, rerequest_s=0.1, heartbeat_s=0.1,
                    stores_like_firmware=like_firmware) as sim, \
            LinkEmulator(sim.port, profile=profile, seed=seed) as emu, \
            Link(f"udpout:127.0.0.1:{emu.port}", heartbeat_s=0.1) as link:
        client = MissionClient(link, 1, 1, timeouts=TRIAL_TIMEOUTS)
        try:
            client.upload_verified(items)
            ok, error = True, ""
        except LinkError as err:
            ok, error = False, str(err)
        held = sim.items()
    identical = len(held) == len(items) and all(a.same_on_wire(b) for a, b in zip(items, held))
    return Outcome(seed, ok, ok and not identical, error, len(items), loss, dup, reorder, flavour)


def run_trials(seeds, workers: int = 4) -> list[Outcome]:
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(run_trial, seeds))
