"""`wiris mission download`: what the vehicle holds written atomically to a .plan (mission, fence, rally) or
.waypoints file, ArduPilot's item 0 split off as the file's home.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MISSION_TYPE_MISSION, MissionItem
from missions.errors import PlanError
from missions.formats.planfile import atomic_write, check_writable, write_plan
from missions.formats.wpl import write_wpl
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.transfer.results import ListUnsupported, Progress, TYPE_NAMES
from wiris_tools.transfer.client import MissionClient, find_autopilot
from wiris_tools.transfer.file_lists import Home, PLAN_SUFFIXES, WPL_SUFFIXES


def download_file(link: Link, out: str, *, target_system: int | None = None, target_component: int = 1,
                  timeout: float = 10.0, progress: Progress | None = None, deadline_s: float | None = None) -> dict:
    """Download what the vehicle holds and write it to `out` (.plan: mission, fence and rally;
    .waypoints: the mission) atomically; a summary dict. `deadline_s` bounds each list's download
    (None: MissionClient.download's own, from the count and the round trip)."""

    p = Path(out)
    suffix = _output_suffix(p)
    hb = find_autopilot(link, target_system, timeout)
    system = hb.get_srcSystem()
    client = MissionClient(link, system, target_component)
    mission, res = client.download(mission_type=MISSION_TYPE_MISSION, progress=progress, deadline_s=deadline_s)
    items, home = _split_home(mission, hb.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA)
    others = {kind: _download_other_list(client, kind, res.mavlink1, deadline_s)
              for kind in (mavlink2.MAV_MISSION_TYPE_FENCE, mavlink2.MAV_MISSION_TYPE_RALLY)
              } if suffix in PLAN_SUFFIXES else {}
    atomic_write(p, _file_text(p, suffix, items, home, hb, others))
    return {"file": str(p), "target_system": system,
            "items": {"mission": len(items), **{TYPE_NAMES[kind]: len(o.items) for kind, o in others.items()}},
            "home": list(home) if home else None, "opaque_id": res.opaque_id, "seconds": round(res.seconds, 3),
            "notes": [o.note for o in others.values() if o.note is not None]}


def _output_suffix(p) -> str:
    """The suffix of output file `p`, after checking it can be written - before the download, not after it."""

    suffix = p.suffix.lower()
    if suffix not in PLAN_SUFFIXES + WPL_SUFFIXES:
        raise PlanError(f"unknown output type {suffix or '(no suffix)'!r}", where=str(p),
                        hint="write a .plan or a .waypoints file")
    check_writable(p)
    return suffix


def _split_home(items: list[MissionItem], ardupilot: bool) -> tuple[list[MissionItem], Home | None]:
    """The mission without ArduPilot's item 0, and that item's position as the file's home."""
    if not ardupilot or not items:
        return items, None
    h = items[0]
    return items[1:], (h.x / 1e7, h.y / 1e7, h.z)


class _OtherList(NamedTuple):
    """A fence or rally list for a .plan file."""
    items: list[MissionItem]
    note: str | None = None     # why it is empty without having been downloaded


def _download_other_list(client: MissionClient, kind: int, mavlink1: bool, deadline_s: float | None) -> _OtherList:
    """The vehicle's fence or rally list; empty, with a note, when the vehicle cannot give it; LinkError when
    the download fails (an empty list in the file would claim "no fence" for a vehicle that has one)."""
    name = TYPE_NAMES[kind]
    # mission_type is a MAVLink 2 extension: a vehicle that answered our (MAVLink 2) list request in MAVLink 1
    # cannot carry a fence or rally list (ArduPilot answers UNSUPPORTED, GCS_Common.cpp mavlink2_requirement_met,
    # in a MAVLink 1 ack without the mission_type that says which list). Its answer, not its HEARTBEAT: PX4
    # talks MAVLink 1 until it hears MAVLink 2.
    if mavlink1:
        return _OtherList([], f"{name} not downloaded: the vehicle talks MAVLink 1, which cannot carry fence or "
                              "rally lists")
    try:
        items, _ = client.download(mission_type=kind, deadline_s=deadline_s)
    except ListUnsupported as err:      # the vehicle has no such list: an empty one is the truth
        return _OtherList([], f"{name} not downloaded: {err.message}")
    except LinkError as err:
        raise LinkError(f"the {name} list could not be downloaded, so no file was written: {err.message}",
                        where=err.where, hint=f"{err.hint}; to save the mission alone, use -o FILE.waypoints") from None
    return _OtherList(items)


def _file_text(p, suffix: str, items: list[MissionItem], home: Home | None, hb,
               others: dict[int, _OtherList]) -> str:
    """The text of output file `p`; PlanError (where: `p`) when what the vehicle holds does not fit the file
    form (an infinite float)."""

    try:
        if suffix in PLAN_SUFFIXES:
            return write_plan(items, home, firmware=int(hb.autopilot), vehicle=int(hb.type),
                              fence=others[mavlink2.MAV_MISSION_TYPE_FENCE].items,
                              rally=others[mavlink2.MAV_MISSION_TYPE_RALLY].items)
        return write_wpl(items, home)
    except PlanError as err:
        if err.where is None:
            err.where = str(p)
        raise
