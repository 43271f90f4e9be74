"""QGroundControl `.plan` files: read and write (pure: no sockets).

    text = write_plan(items, (lat, lon, alt_amsl), firmware="ardupilot", vehicle="copter",
                      fence=fence_items, rally=rally_items, cruise_speed=12.0)
    items, fence, rally, home = read_plan(text, "survey.plan")

Conventions (shared with missions.formats.wpl and the transfer tools):
  * `items` never contain a home row: the file keeps home in `plannedHomePosition`. When uploading
    to ArduPilot the transfer layer puts home in as item 0, as QGC and MAVSDK do.
  * `home` is (lat_deg, lon_deg, alt_m_amsl) or None (written as [0, 0, 0]).
  * fence and rally are lists of MissionItem with mission_type FENCE / RALLY, exactly what is
    uploaded: polygon vertices NAV_FENCE_POLYGON_VERTEX_INCLUSION/EXCLUSION (param1 = vertex
    count), circles NAV_FENCE_CIRCLE_INCLUSION/EXCLUSION (param1 = radius m), the return point
    NAV_FENCE_RETURN_POINT, rally points NAV_RALLY_POINT.

What is written is what QGroundControl writes (MissionController, GeoFenceController,
RallyPointController): `fileType` "Plan", `version` 1, `groundStation` "QGroundControl";
`mission.version` 2 with firmwareType (MAV_AUTOPILOT), vehicleType (MAV_TYPE), cruiseSpeed,
hoverSpeed, globalPlanAltitudeMode, plannedHomePosition and SimpleItems (NaN params as null), with a compiled
mission's surveys (and corridors, when asked) as the ComplexItems of missions.formats.qgc_complex;
`geoFence.version` 2 with `polygons` / `circles` (each version 1); `rallyPoints.version` 2. Both
the geoFence and rallyPoints sections are always written (MAVSDK's importer fails silently without
them). Keys sorted and four-space indents, like Qt's QJsonDocument.

Reading is strict about what QGC is strict about (versions, required sections and keys), reads
what QGC reads, and tolerant of QGC's complex items. QGroundControl 3.x saves load as QGC loads them
(PlanMasterController::loadFromFile -> GeoFenceController/RallyPointController::load): a geoFence of
version 1 or without a version and a rallyPoints of version 1 are skipped, each with a ReadNote
(`read_plan_file(...).notes`); a rallyPoints without a version is refused, as QGC refuses it. A 3.x
SimpleItem keeps params 5-7 in "coordinate" (MissionItem::_convertJsonV2ToV3); it reads as 7 params.
Also: a Survey or CorridorScan ComplexItem contributes the
`TransectStyleComplexItem.Items` QGC stored in the file (QGC itself flies those verbatim until the
pattern is edited). A StructureScan stores no items, so it is refused with a hint. Errors are
PlanError with a location: `NAME:LINE:COL` for JSON syntax, `NAME: mission.items[3].params` for
content.

This module writes; missions.formats.planfile_read reads, missions.formats.planfile_common holds what both
share, missions.formats.atomic writes files atomically. Their public names are importable from here.
"""

from __future__ import annotations

import json
import math
import os
from decimal import Decimal
from pathlib import Path
from typing import Any

from missions.errors import PlanError
from missions.formats.itemcheck import check_items
from missions.emit.items import FRAME_GLOBAL, MissionItem
from missions.formats.planfile_common import (ALT_MODE_MIXED, ALT_MODE_RELATIVE, CMD_FENCE_CIRCLE_EXCLUSION,
                                              CMD_FENCE_CIRCLE_INCLUSION, CMD_FENCE_POLYGON_EXCLUSION,
                                              CMD_FENCE_POLYGON_INCLUSION, CMD_FENCE_RETURN_POINT, CMD_RALLY_POINT,
                                              FIRMWARE_TYPES, Home, MAX_ITEMS, MAX_PLAN_BYTES,
                                              QGC_DEFAULT_CRUISE_SPEED, QGC_DEFAULT_HOVER_SPEED, VEHICLE_TYPES,
                                              _FRAME_ALT_MODE, _scale)
from missions.formats.atomic import atomic_write

# also importable from here, where the rest of the tools import them
from cdf.float32 import FLOAT32_MAX
from missions.formats.planfile_common import READ_HINT, xy_hint
from missions.formats.atomic import check_writable, new_file_mode, replacing
from missions.formats.planfile_read import PlanFile, capped_text, load_plan, load_plan_file, read_plan, read_plan_file


def _num(v: float | int | None) -> float | int | None:
    """A JSON number as QGC writes it: integral values as integers, NaN as null."""
    if v is None:
        return None
    if isinstance(v, int):
        return v
    if math.isnan(v):
        return None
    if math.isinf(v):
        # items, fence, rally and home passed check_finite: only a library caller's speed gets here
        raise PlanError(f"an infinite value ({v}) cannot be written to a .plan file",
                        hint="give write_plan a finite cruise_speed and hover_speed (m/s)")
    return int(v) if v.is_integer() and abs(v) < 2**53 else v


def check_finite(form: str, home: Home | None, mission=(), fence=(), rally=()) -> None:
    """Refuse, naming the place, the one MAVLink value that the `form` file ("a .plan", "a waypoint")
    cannot hold: an infinite float, which a vehicle may answer a download with. Mission items are
    numbered as the .plan's doJumpId and the WPL row index number them (from 1), fence and rally
    items by their position in the list (from 0, their seq on the wire)."""
    hint = "set a finite value where the vehicle holds it (NaN is fine: it means unset), then try again"
    if home is not None and any(math.isinf(v) for v in home):
        raise PlanError(f"the home position {tuple(home)} holds an infinite value, which {form} file cannot hold",
                        hint=hint)
    for kind, items, first in (("mission", mission, 1), ("fence", fence, 0), ("rally", rally, 0)):
        for i, it in enumerate(items, first):
            bad = it.infinite_field()
            if bad is not None:
                raise PlanError(f"{kind} item {i} (command {it.command}) has {bad}, which {form} file cannot hold",
                                hint=hint)


def _coord(v: int, frame: int) -> float | int:
    s = _scale(frame)
    if s == 1:
        return int(v)
    q = Decimal(int(v)) / Decimal(s)
    return _num(float(q))  # type: ignore[return-value]


def _simple_item(item: MissionItem, jump_id: int) -> dict[str, Any]:
    out: dict[str, Any] = {
        "autoContinue": bool(item.autocontinue),
        "command": int(item.command),
        "doJumpId": jump_id,
        "frame": int(item.frame),
        "params": [_num(item.param1), _num(item.param2), _num(item.param3), _num(item.param4),
                   _coord(item.x, item.frame), _coord(item.y, item.frame), _num(item.z)],
        "type": "SimpleItem",
    }
    mode = _FRAME_ALT_MODE.get(item.frame)
    if mode is not None:
        # SimpleMissionItem::save writes these for items whose frame carries an altitude.
        out.update(AMSLAltAboveTerrain=None, Altitude=_num(item.z), AltitudeMode=mode)
    return out


def _degrees(item: MissionItem) -> list[float | int]:
    """[lat, lon] of a fence or rally item as the .plan's geoFence and rallyPoints keep them: degrees."""
    return [_coord(item.x, FRAME_GLOBAL), _coord(item.y, FRAME_GLOBAL)]


def _fence_json(fence: list[MissionItem]) -> dict[str, Any]:
    polygons: list[dict[str, Any]] = []
    circles: list[dict[str, Any]] = []
    out: dict[str, Any] = {"circles": circles, "polygons": polygons, "version": 2}
    i = 0
    while i < len(fence):
        it = fence[i]
        where = f"fence item {i}"
        if it.command in (CMD_FENCE_POLYGON_INCLUSION, CMD_FENCE_POLYGON_EXCLUSION):
            n = int(it.param1)
            if n < 3 or it.param1 != n or i + n > len(fence) or any(
                    f.command != it.command or f.param1 != it.param1 for f in fence[i:i + n]):
                raise PlanError(f"a fence polygon needs {max(n, 3)} consecutive vertices of command {it.command} "
                                f"with param1 = vertex count", where=where,
                                hint="emit each polygon as param1 = N on all N vertex items")
            polygons.append({"inclusion": it.command == CMD_FENCE_POLYGON_INCLUSION,
                             "polygon": [_degrees(f) for f in fence[i:i + n]],
                             "version": 1})
            i += n
        elif it.command in (CMD_FENCE_CIRCLE_INCLUSION, CMD_FENCE_CIRCLE_EXCLUSION):
            circles.append({"circle": {"center": _degrees(it), "radius": _num(it.param1)},
                            "inclusion": it.command == CMD_FENCE_CIRCLE_INCLUSION, "version": 1})
            i += 1
        elif it.command == CMD_FENCE_RETURN_POINT:
            out["breachReturn"] = [*_degrees(it), _num(it.z)]
            i += 1
        else:
            raise PlanError(f"command {it.command} is not a fence item", where=where,
                            hint="fence items are NAV_FENCE_* commands (5000-5004)")
    return out


def _rally_json(rally: list[MissionItem]) -> dict[str, Any]:
    for i, it in enumerate(rally):
        if it.command != CMD_RALLY_POINT:
            raise PlanError(f"command {it.command} is not a rally point", where=f"rally item {i}",
                            hint="rally items are NAV_RALLY_POINT (5100)")
    return {"points": [[*_degrees(r), _num(r.z)] for r in rally], "version": 2}


def _code(table: dict[str, int], value: str | int | None, what: str) -> int:
    if value is None:
        return table["generic"]
    if isinstance(value, int):
        return value
    try:
        return table[value.lower()]
    except KeyError:
        raise PlanError(f"unknown {what} {value!r}", hint=f"use one of: {', '.join(sorted(table))}") from None


def _mission_items(items: list[MissionItem], patterns, payloads, corridor_scan: bool, firmware: str | int | None,
                   speed: float | None) -> list[dict[str, Any]]:
    if not patterns:
        return [_simple_item(it, i + 1) for i, it in enumerate(items)]
    from missions.formats.qgc_complex import mission_items_json
    from missions.measure.flight import fired_spacing_m

    fw = "px4" if firmware in ("px4", FIRMWARE_TYPES.get("px4")) else "ardupilot"
    return mission_items_json(items, patterns, payloads, _simple_item, corridor_scan=corridor_scan,
                              spacing=lambda d: fired_spacing_m(fw, d, speed or 0.0))


def plan_document(items, home: Home | None, *, firmware: str | int | None, vehicle: str | int | None,
                  fence=None, rally=None, cruise_speed: float | None = None,
                  hover_speed: float | None = None, patterns=(), payloads=(),
                  corridor_scan: bool = False) -> dict[str, Any]:
    """The .plan JSON object (see write_plan). `patterns` (Compiled.patterns, indices into `items`) are written
    as QGC ComplexItems around the other items (missions.formats.qgc_complex); `payloads` give their optics."""
    items, fence, rally = list(items), list(fence or []), list(rally or [])
    if len(items) > MAX_ITEMS:
        raise PlanError(f"{len(items)} mission items do not fit a MAVLink mission (at most {MAX_ITEMS})",
                        hint="split the mission into several plans (smaller areas)")
    check_finite("a .plan", home, items, fence, rally)
    check_items("a .plan", home, items, fence, rally)   # what this writes, read_plan reads
    modes = {_FRAME_ALT_MODE.get(it.frame) for it in items if it.frame in _FRAME_ALT_MODE}
    alt_mode = modes.pop() if len(modes) == 1 else (ALT_MODE_RELATIVE if not modes else ALT_MODE_MIXED)
    lat, lon, alt = home if home is not None else (0.0, 0.0, 0.0)
    mission = {
        "cruiseSpeed": _num(float(cruise_speed if cruise_speed is not None else QGC_DEFAULT_CRUISE_SPEED)),
        "firmwareType": _code(FIRMWARE_TYPES, firmware, "firmware"),
        "globalPlanAltitudeMode": alt_mode,
        "hoverSpeed": _num(float(hover_speed if hover_speed is not None else QGC_DEFAULT_HOVER_SPEED)),
        "items": _mission_items(items, patterns, payloads, corridor_scan, firmware, cruise_speed),
        "plannedHomePosition": [_num(float(lat)), _num(float(lon)), _num(float(alt))],
        "vehicleType": _code(VEHICLE_TYPES, vehicle, "vehicle type"),
        "version": 2,
    }
    return {"fileType": "Plan", "geoFence": _fence_json(fence), "groundStation": "QGroundControl",
            "mission": mission, "rallyPoints": _rally_json(rally), "version": 1}


def write_plan(items, home=None, /, *, firmware: str | int | None = None, vehicle: str | int | None = None,
               fence=None, rally=None, cruise_speed: float | None = None, hover_speed: float | None = None,
               patterns=(), payloads=(), corridor_scan: bool = False, **file_form) -> str:
    """The .plan text for `items` (no home row) with `home` = (lat, lon, alt AMSL) or None.

    `firmware`: "ardupilot" | "px4" | a MAV_AUTOPILOT number; `vehicle`: "copter" | "plane" |
    "vtol" | "rover" | … | a MAV_TYPE number. `fence`/`rally`: MissionItem lists (module docstring).

    File form, used by missions.formats.outputs: `write_plan(path, compiled, items=part)` writes the plan
    of a compiled mission (its items, or `items`) to `path` atomically and returns the text.
    """
    if isinstance(items, (str, os.PathLike)):
        compiled = home
        chosen = file_form.pop("items", None)
        if file_form:
            raise TypeError(f"unexpected arguments {sorted(file_form)}")
        speed = getattr(compiled, "speed_mps", None)
        whole = chosen is None or tuple(chosen) == tuple(compiled.items)
        # a part's item numbers are not the whole mission's: only the whole mission carries the patterns
        text = write_plan(list(chosen if chosen is not None else compiled.items), compiled.home,
                          firmware=compiled.firmware, vehicle=getattr(compiled, "frame", None),
                          cruise_speed=speed, hover_speed=speed, fence=list(getattr(compiled, "fence", ())),
                          patterns=getattr(compiled, "patterns", ()) if whole else (),
                          payloads=getattr(compiled, "payloads", ()),
                          corridor_scan=getattr(compiled, "corridor_scan", False))
        atomic_write(Path(items), text)
        return text
    if file_form:
        raise TypeError(f"unexpected arguments {sorted(file_form)}")
    doc = plan_document(items, home, firmware=firmware, vehicle=vehicle, fence=fence, rally=rally,
                        cruise_speed=cruise_speed, hover_speed=hover_speed, patterns=patterns, payloads=payloads,
                        corridor_scan=corridor_scan)
    text = json.dumps(doc, indent=4, sort_keys=True, allow_nan=False) + "\n"
    if len(text) > MAX_PLAN_BYTES:  # only a vehicle's hostile fence or rally list gets here
        raise PlanError(f"the .plan would be {len(text) / 2**20:.0f} MB, more than the {MAX_PLAN_BYTES // 2**20} MB "
                        "this tool reads back", hint="save the mission alone as .waypoints")
    return text
