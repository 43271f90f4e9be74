"""`wiris mission upload`: a file's list up to the vehicle (upload_file), checked against the firmware its
HEARTBEAT reports, ArduPilot's home as item 0; and what to upload instead when the vehicle has no room.
"""

from __future__ import annotations

import re
from pathlib import Path

import glob
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import FRAME_GLOBAL, MISSION_TYPE_MISSION, MissionItem, deg_to_e7
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.transfer.results import Progress, TYPE_NAMES, VehicleRefused
from wiris_tools.transfer.client import MissionClient, find_autopilot
from wiris_tools.transfer.file_lists import (CAPTURE_SUFFIXES, CHECKED_FIRMWARES, FIRMWARE_LABELS, Home, LoadedList,
                                             PLAN_SUFFIXES, WPL_SUFFIXES, capture_plan_part, load_for_upload)


def home_item(home: Home | None) -> MissionItem:
    """ArduPilot's item 0: the home position (it replaces it with its own home on upload)."""
    lat, lon, alt = home if home is not None else (0.0, 0.0, 0.0)
    return MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL, x=deg_to_e7(lat),
                       y=deg_to_e7(lon), z=float(alt))


def upload_file(link: Link, path: str, *, mission_type: int = MISSION_TYPE_MISSION, verify: bool = False,
                target_system: int | None = None, target_component: int = 1, part: int | None = None,
                firmware: str | None = None, timeout: float = 10.0, progress: Progress | None = None,
                loaded: LoadedList | None = None, force: bool = False) -> dict:
    """Load `path` (or take `loaded`, from load_for_upload), check it was made for the vehicle's firmware
    (`force`: upload anyway), upload it (ArduPilot: home as item 0), optionally verify; a summary dict.
    A capture plan is compiled for the vehicle's firmware unless `firmware` names one."""
    loaded = loaded if loaded is not None else load_for_upload(path, mission_type, part=part, firmware=firmware)
    hb = find_autopilot(link, target_system, timeout)
    notes: list[str] = []
    if Path(path).suffix.lower() in CAPTURE_SUFFIXES and firmware is None:
        loaded, note = _compiled_for_the_vehicle(path, loaded, hb.autopilot, part)
        notes += [note] if note else []
    elif not force:
        check_firmware(path, loaded.firmware, hb)
    elif loaded.firmware is not None and loaded.firmware != hb.autopilot:
        notes.append(f"uploaded with --force: {firmware_mismatch(path, loaded.firmware, hb).message}")
    items, home = loaded.items, loaded.home
    system = hb.get_srcSystem()
    ardupilot = hb.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    if ardupilot and mission_type == MISSION_TYPE_MISSION:
        items = [home_item(home)] + items
    client = MissionClient(link, system, target_component)
    try:
        result = (client.upload_verified if verify else client.upload)(items, mission_type=mission_type,
                                                                        progress=progress)
    except VehicleRefused as err:
        if err.result == mavlink2.MAV_MISSION_NO_SPACE:
            err.hint = too_big_hint(path, len(items), mission_type)
        raise
    return {"file": str(path), "type": TYPE_NAMES[mission_type], "target_system": system,
            "autopilot": "ardupilot" if ardupilot else "px4" if hb.autopilot == mavlink2.MAV_AUTOPILOT_PX4
            else str(hb.autopilot), "items": len(items), "home_row": ardupilot and mission_type == MISSION_TYPE_MISSION,
            "seconds": round(result.seconds, 3), "verified": result.verified,
            "opaque_id": result.opaque_id, "resent": result.resent, "nacks_tolerated": result.nacks_tolerated,
            "warnings": list(loaded.notes), "notes": notes + list(result.notes)}


def firmware_mismatch(path, made_for: int, hb) -> LinkError:
    """The error for a file made for firmware `made_for` (a MAV_AUTOPILOT) and a vehicle whose HEARTBEAT says
    otherwise."""
    want = FIRMWARE_LABELS[CHECKED_FIRMWARES[made_for]]
    has = FIRMWARE_LABELS.get(CHECKED_FIRMWARES.get(hb.autopilot, ""), f"MAV_AUTOPILOT {hb.autopilot}")
    return LinkError(f"the file was made for {want} but system {hb.get_srcSystem()} reports {has} in its HEARTBEAT: "
                     f"{has} reads {want}'s mission differently (ArduPilot keeps home as item 0; each accepts "
                     "its own commands, frames and params)", where=str(path),
                     hint=f"compile or save the mission for {has} (a capture plan compiles for the vehicle when "
                          "--firmware is left out), or give --force to upload this file anyway")


def check_firmware(path, made_for: int | None, hb) -> None:
    """LinkError when the file was made for ArduPilot or PX4 and the vehicle's HEARTBEAT reports another
    autopilot. A file that names no firmware (WPL, a generic .plan) is not judged."""
    if made_for is not None and hb.autopilot != made_for:
        raise firmware_mismatch(path, made_for, hb)


def _compiled_for_the_vehicle(path, loaded: LoadedList, autopilot: int, part: int | None) -> tuple[LoadedList, str]:
    """The capture plan compiled for the vehicle's firmware (a note says so) when it was compiled for another.
    A vehicle that is neither ArduPilot nor PX4 gets the plan's own firmware, and a note."""
    if loaded.firmware == autopilot:
        return loaded, ""
    name = CHECKED_FIRMWARES.get(autopilot)
    if name is None:
        return loaded, (f"the vehicle reports MAV_AUTOPILOT {autopilot}, neither ArduPilot nor PX4: the plan was "
                        "compiled for its own vehicle.firmware")
    return (capture_plan_part(Path(path), part, name),
            f"compiled for {FIRMWARE_LABELS[name]}, the firmware the vehicle reports (the plan names another)")


def split_files_beside(path) -> list[Path]:
    """The part and sortie files the compiler wrote beside `path`: NAME.partK.SUFFIX / NAME.sortieK.SUFFIX
    with `path`'s suffix (a capture plan's: .plan), NAME being `path`'s stem without a .partK / .sortieK of its
    own; in order of kind and K."""
    p = Path(path)
    stem = re.sub(r"\.(part|sortie)\d+$", "", p.stem)
    suffix = p.suffix if p.suffix.lower() in PLAN_SUFFIXES + WPL_SUFFIXES else ".plan"
    split = re.compile(rf"{re.escape(stem)}\.(part|sortie)(\d+){re.escape(suffix)}")
    found = [(m.group(1), int(m.group(2)), f) for f in p.parent.glob(f"{glob.escape(stem)}.*{suffix}")
             if (m := split.fullmatch(f.name)) and f != p]
    return [f for _kind, _k, f in sorted(found)]


def too_big_hint(path, count: int, mission_type: int) -> str:
    """What to upload instead of `path`'s `count` items, which the vehicle has no room for."""
    kind = TYPE_NAMES.get(mission_type, "mission")
    split = split_files_beside(path)
    already_split = re.search(r"\.(part|sortie)\d+$", Path(path).stem) is not None
    if split and mission_type == MISSION_TYPE_MISSION and not already_split:
        names = ", ".join(f.name for f in split)
        return (f"the vehicle has no room for {count} items; the compiler split this mission into {names} beside "
                "it: upload them one at a time, each after the last is flown")
    if Path(path).suffix.lower() in CAPTURE_SUFFIXES:
        return (f"the vehicle has no room for {count} items: set vehicle.max_mission_items in the plan to the "
                "vehicle's limit (PX4: 500 by default) and upload with --sortie 1..N")
    return (f"the vehicle has no room for {count} {kind} items (PX4 holds 500 by default, ArduPilot about 700 on "
            "common boards): compile the capture plan with vehicle.max_mission_items set to the vehicle's limit to "
            "get NAME.sortieK files, or use fewer items")
