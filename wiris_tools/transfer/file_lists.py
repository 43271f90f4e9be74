"""The list a file holds for upload (load_for_upload): a .plan, a WPL 110 file or a capture plan compiled on
the fly (a sortie of it, or its fence), without a home row, with the firmware it was made for.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.compile import compile_plan
from missions.emit.items import MISSION_TYPE_MISSION, MissionItem
from missions.errors import PlanError
from missions.formats.planfile import load_plan_file
from missions.formats.wpl import LIST_NAMES, load_wpl_file
from missions.measure.report import report
from wiris_tools.transfer.results import TYPE_NAMES


PLAN_SUFFIXES = (".plan",)
WPL_SUFFIXES = (".waypoints", ".wpl", ".txt")
CAPTURE_SUFFIXES = (".yaml", ".yml")


Home = tuple[float, float, float]


class LoadedList(NamedTuple):
    """What load_for_upload read: the items of one list, without a home row, and the file's home; the
    MAV_AUTOPILOT the file was made for (None: it does not say) and what the reader repaired or skipped."""
    items: list[MissionItem]
    home: Home | None
    firmware: int | None = None
    notes: tuple[str, ...] = ()


# The firmwares whose files differ (ArduPilot's item 0 is home, commands and frames each accepts): a file made
# for one of them is checked against the vehicle's HEARTBEAT; a generic one (firmwareType 0) is not.
CHECKED_FIRMWARES = {mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA: "ardupilot", mavlink2.MAV_AUTOPILOT_PX4: "px4"}
FIRMWARE_LABELS = {"ardupilot": "ArduPilot", "px4": "PX4"}


def load_for_upload(path: str, mission_type: int = MISSION_TYPE_MISSION, *, part: int | None = None,
                    firmware: str | None = None) -> LoadedList:
    """The items of `mission_type` in a .plan, a WPL 110 file (a mission, or a fence or rally list as
    Mission Planner saves one) or a capture plan (compiled on the fly), without a home row, and the file's
    home. PlanError/LinkError for anything unusable."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in PLAN_SUFFIXES:
        loaded = _list_of_plan_file(p, mission_type)
    elif suffix in WPL_SUFFIXES:
        loaded = _list_of_wpl_file(p, mission_type)
    elif suffix in CAPTURE_SUFFIXES and mission_type == mavlink2.MAV_MISSION_TYPE_FENCE:
        loaded = _capture_plan_fence(p, firmware)
    elif suffix in CAPTURE_SUFFIXES:
        _require_mission(p, mission_type, "a capture plan compiles to a mission")
        loaded = capture_plan_part(p, part, firmware)
    else:
        raise PlanError(f"unknown file type {suffix or '(no suffix)'!r}", where=str(p),
                        hint="upload a .plan, a .waypoints (QGC WPL 110) or a capture plan .yaml")
    chosen = [it.with_(mission_type=mission_type) for it in loaded.items]
    if not chosen:
        raise PlanError(f"the file holds no {TYPE_NAMES.get(mission_type, str(mission_type))} items", where=str(p),
                        hint="check --type (mission, fence or rally); to clear a list, use the ground station")
    return loaded._replace(items=chosen)


def _list_of_plan_file(p, mission_type: int) -> LoadedList:
    read = load_plan_file(p)
    chosen = {MISSION_TYPE_MISSION: read.items, mavlink2.MAV_MISSION_TYPE_FENCE: read.fence,
              mavlink2.MAV_MISSION_TYPE_RALLY: read.rally}[mission_type]
    firmware = read.firmware if read.firmware in CHECKED_FIRMWARES else None
    return LoadedList(chosen, read.home, firmware, tuple(map(str, read.notes)))


def _list_of_wpl_file(p, mission_type: int) -> LoadedList:
    """A WPL 110 file's list, which must be the one asked for: a Mission Planner fence file is no mission."""
    read = load_wpl_file(p)
    if read.mission_type != mission_type:
        held, asked = LIST_NAMES[read.mission_type], TYPE_NAMES.get(mission_type, str(mission_type))
        if read.mission_type == MISSION_TYPE_MISSION:
            hint = f"upload a {asked} from a .plan file or from a WPL file of {asked} rows"
        else:
            hint = f"to send it to the vehicle's {held} list, give --type {held}"
        raise PlanError(f"the file holds a {held} list ({len(read.items)} rows), not a {asked}", where=str(p),
                        hint=hint)
    return LoadedList(read.items, read.home, None, tuple(map(str, read.notes)))


def _require_mission(p, mission_type: int, what: str) -> None:
    """PlanError unless a mission is asked for: a capture plan compiles to a mission only."""
    if mission_type != MISSION_TYPE_MISSION:
        raise PlanError(f"{what}, not a {TYPE_NAMES.get(mission_type, str(mission_type))} list", where=str(p),
                        hint="upload fence and rally from a .plan file")


def capture_plan_part(p, part: int | None, firmware: str | None) -> LoadedList:
    """The mission of capture plan `p` compiled for `firmware` (None: the plan's), its sortie `part` (1..N) when
    it is flown in sorties (missions.sorties)."""
    compiled = _compiled_without_errors(p, firmware)
    parts = list(compiled.parts) if compiled.parts else [compiled.items]
    made_for = next((code for code, name in CHECKED_FIRMWARES.items() if name == compiled.firmware), None)
    return LoadedList(list(parts[_part_index(p, part, len(parts), compiled.item_limit)]), compiled.home, made_for)


def _capture_plan_fence(p, firmware: str | None) -> LoadedList:
    """The fence capture plan `p` compiles to: its exclusion zones and `fence: {margin_m}` inclusion polygon."""
    compiled = _compiled_without_errors(p, firmware)
    if not compiled.fence:
        raise PlanError("the capture plan has no fence: no step has no_fly: or exclude: zones and it has no fence: key",
                        where=str(p), hint="add fence: {margin_m: 30} for an inclusion fence around the flight")
    made_for = next((code for code, name in CHECKED_FIRMWARES.items() if name == compiled.firmware), None)
    return LoadedList(list(compiled.fence), compiled.home, made_for)


def _compiled_without_errors(p, firmware: str | None):
    """missions.compile.compile_plan of `p`; PlanError when the report of the compiled mission finds errors."""
    compiled = compile_plan(str(p), firmware=firmware)
    try:
        errors = [e.to_json() for e in report(compiled).errors]
    except PlanError as err:  # from measuring the mission (a photo budget): about the plan as a whole
        err.where = err.where or str(p)
        raise
    if errors:
        raise PlanError(f"the compiled mission has {len(errors)} error(s): {errors[0]}", where=str(p),
                        hint="run `wiris mission check` and fix the plan before uploading")
    return compiled


def _part_index(p, part: int | None, count: int, item_limit: int) -> int:
    """The index into the `count` sorties of --sortie `part` (None: the only one); PlanError when it names none."""
    if count > 1 and part is None:
        raise PlanError(f"the mission is flown in {count} sorties (one battery or {item_limit} items each)",
                        where=str(p), hint=f"choose one with --sortie 1..{count}")
    if part is not None and not 1 <= part <= count:
        raise PlanError(f"--sortie {part}: the mission has {count} sortie(s)", where=str(p),
                        hint="leave out --sortie: the mission is flown in one" if count == 1
                        else f"give --sortie 1..{count}: each sortie is a complete mission, flown in turn")
    return (part or 1) - 1
