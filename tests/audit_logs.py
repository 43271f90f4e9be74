"""Flight logs written the way a ground station writes them (tlog: an 8-byte big-endian microsecond time stamp
before each MAVLink frame, packed by pymavlink) from a compiled plan's predicted flight, with the faults of
the field: every n-th capture dropped, the camera stopping after a time, an RTL that cuts the mission short."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.measure.flight import simulate

T0 = 1_780_000_000.0


@dataclass(frozen=True)
class Faults:
    drop_every: int = 0          # the camera fails every n-th capture (the trigger is logged, no image)
    stop_after: int | None = None    # the camera takes nothing from this photo on
    rtl_after: int | None = None     # the pilot switches to RTL after this photo: no further triggers


def write_tlog(path: Path, compiled, payload: str = "thermal", faults: Faults = Faults(),
               offset_deg: tuple[float, float] = (0.0, 0.0)) -> dict:
    """A tlog of the compiled mission flown as predicted; returns what was dropped."""
    sim = simulate(compiled)
    photos = [p for p in sim.photos if payload in p.payloads]
    proj = sim.projection
    ap = mavlink2.MAVLink(None, srcSystem=1, srcComponent=mavlink2.MAV_COMP_ID_AUTOPILOT1)
    cam = mavlink2.MAVLink(None, srcSystem=1, srcComponent=mavlink2.MAV_COMP_ID_CAMERA)
    out = bytearray()
    dropped, triggered = [], 0
    t = T0

    def put(link, msg, at):
        out.extend(int(at * 1e6).to_bytes(8, "big") + msg.pack(link))

    def heartbeat(mode: int, armed: bool, at: float):
        put(ap, mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
            mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink2.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0),
            mode, mavlink2.MAV_STATE_ACTIVE, 3), at)

    heartbeat(0, False, t)          # STABILIZE, disarmed
    heartbeat(3, True, t + 1)       # AUTO, armed
    t += 2
    for k, p in enumerate(photos):
        if faults.rtl_after is not None and k >= faults.rtl_after:
            break
        lat, lon = proj.to_latlon(p.x, p.y)
        lat, lon = float(lat) + offset_deg[0], float(lon) + offset_deg[1]
        yaw = math.radians(p.heading_deg)
        t += 1.2
        put(ap, mavlink2.MAVLink_mission_current_message(p.item + 1), t - 0.1)
        put(ap, mavlink2.MAVLink_global_position_int_message(int((t - T0) * 1e3), int(lat * 1e7), int(lon * 1e7),
                                                             int((compiled.home[2] + p.alt_m) * 1e3),
                                                             int(p.alt_m * 1e3), 0, 0, 0, int(p.heading_deg * 100)),
            t - 0.05)
        put(ap, mavlink2.MAVLink_attitude_message(int((t - T0) * 1e3), 0.0, 0.0, yaw if yaw <= math.pi else
                                                  yaw - 2 * math.pi, 0, 0, 0), t - 0.04)
        triggered += 1
        put(ap, mavlink2.MAVLink_camera_feedback_message(int(t * 1e6), 1, 0, k, int(lat * 1e7), int(lon * 1e7),
                                                         compiled.home[2] + p.alt_m, p.alt_m, 0.0, 0.0,
                                                         p.heading_deg, 0.0, 0, 0), t)
        if (faults.drop_every and (k + 1) % faults.drop_every == 0) or \
                (faults.stop_after is not None and k >= faults.stop_after):
            dropped.append(k)
            continue
        q = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
        put(cam, mavlink2.MAVLink_camera_image_captured_message(int((t - T0) * 1e3), int(t * 1e6), 1,
                                                                int(lat * 1e7), int(lon * 1e7),
                                                                int((compiled.home[2] + p.alt_m) * 1e3),
                                                                int(p.alt_m * 1e3), q, k, 1, b""), t + 0.3)
    if faults.rtl_after is not None:
        heartbeat(6, True, t + 1)   # RTL
    else:
        put(ap, mavlink2.MAVLink_mission_current_message(len(compiled.items)), t + 20)   # its last item, RTL
    heartbeat(9 if faults.rtl_after is None else 6, True, t + 30)
    heartbeat(9, False, t + 60)
    Path(path).write_bytes(bytes(out))
    return {"photos": len(photos), "triggered": triggered, "dropped": dropped}
