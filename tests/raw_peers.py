"""Hand-scripted MAVLink peers and a bounded call in a thread, for the link tests.

    veh = raw_peers.scripted_vehicle(script, ("MISSION_COUNT", "MISSION_ITEM_INT"))  # script(veh, msg) answers
    call = raw_peers.timed_call(lambda: link.command_long(...), limit_s=6)          # never blocks the test
    call.finished, call.waited, call.value, call.error
    left = raw_peers.lose_accepted_acks(sim)   # a VehicleSim's next ACCEPTED is lost; left["n"] = 1 re-arms
    veh, seen = raw_peers.rarely_answering_vehicle(65535)   # claims 65535 items, answers every 6th request
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import LinkError
from wiris_tools.link import Link


def scripted_vehicle(script, types=("MISSION_COUNT", "MISSION_ITEM_INT")) -> Link:
    """A raw vehicle on a Link (ArduPilot quadrotor, system 1): `script(link, msg)` answers each message of
    `types` addressed to it."""
    veh = Link("udpin:127.0.0.1:0", system=1, component=1, mav_type=mavlink2.MAV_TYPE_QUADROTOR,
               autopilot=mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, heartbeat_s=0.2)
    veh.subscribe(lambda m: script(veh, m), list(types), to_me=True)
    return veh


@dataclass
class TimedCall:
    finished: bool          # False: still running after limit_s (a wait that is not bounded)
    waited: float           # seconds from start until it returned (or the limit)
    value: Any = None
    error: LinkError | None = None


def timed_call(fn: Callable[[], Any], limit_s: float) -> TimedCall:
    """Run `fn` in a daemon thread for at most `limit_s`: its value or LinkError, and how long it took."""
    outcome: dict = {}

    def call() -> None:
        try:
            outcome["value"] = fn()
        except LinkError as err:
            outcome["error"] = err

    caller = threading.Thread(target=call, daemon=True)
    started = time.monotonic()
    caller.start()
    caller.join(limit_s)
    waited = time.monotonic() - started
    return TimedCall(not caller.is_alive(), waited, outcome.get("value"), outcome.get("error"))


def lose_accepted_acks(sim, count: int = 1) -> dict:
    """Make VehicleSim `sim` lose its next `count` final MISSION_ACK ACCEPTED, as a radio would. Returns the
    counter ({"n": left to lose}): set it again to lose more."""
    left = {"n": count}
    send = sim._ack

    def ack(to, result, kind, opaque=0):
        if result == mavlink2.MAV_MISSION_ACCEPTED and left["n"] > 0:
            left["n"] -= 1
            return
        send(to, result, kind, opaque)

    sim._ack = ack
    return left


def rarely_answering_vehicle(count: int) -> tuple[Link, dict]:
    """A hostile vehicle: claims `count` items and answers only every 6th item request - each item arrives just
    before the per-item retries run out, so without an overall deadline the download crawls on for hours."""
    seen = {"requests": 0}   # item requests received

    def script(veh, m):
        src = (m.get_srcSystem(), m.get_srcComponent())
        if m.get_type() == "MISSION_REQUEST_LIST":
            veh.send(veh.mav.mission_count_encode(*src, count, 0))
            return
        seen["requests"] += 1
        if seen["requests"] % 6 == 0:
            veh.send(veh.mav.mission_item_int_encode(*src, m.seq, mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                                     mavlink2.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0,
                                                     490000000, 160000000, 50, 0))

    return scripted_vehicle(script, ("MISSION_REQUEST_LIST", "MISSION_REQUEST_INT")), seen
