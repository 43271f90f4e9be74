"""The ArduPilot Lua bridge: in-flight camera setting changes as DO_SEND_SCRIPT_MESSAGE items + a script.

ArduPilot rejects MAV_CMD_USER_1..5 and SET_CAMERA_MODE in missions, and its MAVLinkCamV2 backend (CAMx_TYPE
6, the one that finds a WIRIS) does not forward DO_DIGICAM_CONFIGURE/CONTROL settings (reference
autopilots-and-cameras §0.1–0.2, §2.1, §7). It does accept MAV_CMD_DO_SEND_SCRIPT_MESSAGE (217: param1 uint16
id, params 2–4 floats, ardupilotmega.xml) and hands it to Lua (`mission_receive()`); the generated script
(templates/ardupilot_bridge.lua.j2) rebuilds the COMMAND_LONG and sends it to the camera's component with
`mavlink:send_chan()`.

A 7-param command becomes 1–3 items, one per chunk of three params that has something set (see the id
layout below, also printed in the script). Params not set travel as "unset" bits, not as NaN, and the
script fills NaN = "keep" (Workswell manual §6.3) — no NaN on the mission wire, where .plan JSON and WPL
files cannot carry it reliably.

Requires ArduPilot 4.5+ (the scripting `mavlink` binding) with SCR_ENABLE=1. The script carries a small codec
for the three messages it handles, so it runs on stock firmware without AP_Scripting's MAVLink modules on the
SD card (it uses them when they are there).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Iterable, Sequence

from missions.errors import PlanError
from missions.emit.items import FRAME_MISSION, MissionItem, mavlink

MARKER = 0xA000          # bits 15–13 = 0b101: our ids; other scripts' DO_SEND_SCRIPT_MESSAGE ids are left alone
MARKER_MASK = 0xE000
FIRST_COMPONENT = mavlink.MAV_COMP_ID_CAMERA    # 100; components 100..105 fit three bits
QUEUE_SIZE = 5           # AP_Scripting::mission_cmd_queue_size: items queued for scripts before drops
PERIOD_MS = 20           # script update period: drains the queue long before a batch refills it

# Command index (3 bits) -> MAV_CMD name. Only commands whose settings make sense in flight.
BRIDGE_COMMANDS = ("MAV_CMD_USER_1", "MAV_CMD_USER_2", "MAV_CMD_SET_CAMERA_MODE", "MAV_CMD_DO_DIGICAM_CONFIGURE",
                   "MAV_CMD_DO_DIGICAM_CONTROL")


@dataclass(frozen=True)
class BridgeCommand:
    command: str                           # MAV_CMD_* name
    component: int                         # 100..105
    params: tuple[float | None, ...]       # 7; None = keep (NaN)


def encode(cmd: BridgeCommand, comment: str = "") -> list[MissionItem]:
    """DO_SEND_SCRIPT_MESSAGE items carrying one command (1–3 items; the last one says "send")."""
    if cmd.command not in BRIDGE_COMMANDS:
        raise PlanError(f"{cmd.command} cannot go through the Lua bridge",
                        hint="bridge commands: " + ", ".join(BRIDGE_COMMANDS))
    if not FIRST_COMPONENT <= cmd.component <= FIRST_COMPONENT + 5:
        raise PlanError(f"camera component {cmd.component} is outside 100..105",
                        hint="the bridge addresses MAV_COMP_ID_CAMERA..CAMERA6; from a plan (ids checked when it "
                             "loads) this is a bug in wiris-tools: please report it")
    if len(cmd.params) != 7:
        raise ValueError("a command has 7 params")
    index = BRIDGE_COMMANDS.index(cmd.command)
    chunks = []
    for chunk in range(3):
        vals = cmd.params[chunk * 3: chunk * 3 + 3]
        mask = sum(1 << j for j, v in enumerate(vals) if v is not None)
        if mask:
            chunks.append((chunk, mask, [0.0 if v is None else float(v) for v in vals] + [0.0] * (3 - len(vals))))
    if not chunks:
        # nothing set: still send the (all-keep) command so the mission does what the plan says
        chunks.append((0, 0, [0.0, 0.0, 0.0]))
    items = []
    for n, (chunk, mask, vals) in enumerate(chunks):
        if any(not math.isfinite(v) for v in vals):
            raise PlanError(f"{cmd.command}: a value to send is not finite",
                            hint="a bug in wiris-tools (plan settings are range-checked when it loads): please "
                                 "report it with the plan")
        last = n == len(chunks) - 1
        ident = MARKER | (index << 10) | ((cmd.component - FIRST_COMPONENT) << 7) | (chunk << 5) | (mask << 2) \
            | (int(last) << 1)
        items.append(MissionItem(command=mavlink.MAV_CMD_DO_SEND_SCRIPT_MESSAGE, frame=FRAME_MISSION,
                                 param1=float(ident), param2=vals[0], param3=vals[1], param4=vals[2],
                                 comment=comment or f"Lua bridge: {cmd.command} to camera {cmd.component}"))
    return items


def decode(items: Iterable[MissionItem]) -> list[BridgeCommand]:
    """What the script sends for these items (the Python mirror of the Lua decoder, used by tests and the
    report). Items that are not ours are skipped, as the script skips them."""
    out: list[BridgeCommand] = []
    pending: dict | None = None
    for it in items:
        if it.command != mavlink.MAV_CMD_DO_SEND_SCRIPT_MESSAGE:
            continue
        ident = int(it.param1)
        if ident & MARKER_MASK != MARKER:
            continue
        index = (ident >> 10) & 7
        if index >= len(BRIDGE_COMMANDS):
            continue
        comp = FIRST_COMPONENT + ((ident >> 7) & 7)
        chunk, mask, last = (ident >> 5) & 3, (ident >> 2) & 7, (ident >> 1) & 1
        if pending is None or pending["index"] != index or pending["component"] != comp:
            pending = {"index": index, "component": comp, "params": [None] * 7}
        for j, v in enumerate((it.param2, it.param3, it.param4)):
            slot = chunk * 3 + j
            if mask & (1 << j) and slot < 7:
                pending["params"][slot] = v
        if last:
            out.append(BridgeCommand(BRIDGE_COMMANDS[index], comp, tuple(pending["params"])))
            pending = None
    return out


def render_script(plan_name: str) -> str:
    """The bridge script for a plan (the same decoder for every plan; the name is for people)."""
    from templates import render

    commands = [{"index": i, "name": n, "short": n.removeprefix("MAV_CMD_"), "id": int(getattr(mavlink, n))}
                for i, n in enumerate(BRIDGE_COMMANDS)]
    return render("ardupilot_bridge.lua.j2", plan_name=plan_name, marker=MARKER, marker_mask=MARKER_MASK,
                  first_component=FIRST_COMPONENT, commands=commands, queue_size=QUEUE_SIZE, period_ms=PERIOD_MS)


def batches(items: Sequence[MissionItem]) -> list[list[MissionItem]]:
    """Split script items into runs of at most QUEUE_SIZE (the emitter separates runs by a short hold). A
    command's chunks may straddle two runs: the script keeps its pending command between updates."""
    return [list(items[i:i + QUEUE_SIZE]) for i in range(0, len(items), QUEUE_SIZE)]
