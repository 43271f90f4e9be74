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
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
import tempfile
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path
from typing import Any, Iterator, NamedTuple

from cdf.float32 import FLOAT32_MAX  # params 1-4 and z travel as float32
from cdf.userfile import UserFile, read_user_file
from missions.errors import PlanError
from missions.formats.readnote import ReadNote
from missions.formats.itemcheck import GLOBAL_FRAMES, check_items, command_label, home_problem, item_problem
from missions.emit.items import (FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, MISSION_TYPE_FENCE,
                            MISSION_TYPE_MISSION, MISSION_TYPE_RALLY, MissionItem, mavlink)

Home = tuple[float, float, float]

# A 2000-item survey plan is about 1 MB; a vehicle can hold 65535 mission items (ArduPilot with its mission on
# the SD card), and their .plan as write_plan writes it is up to about 45 MB with every float at its longest.
# write_plan refuses anything larger, so every file this tool writes it can read again (a download too).
MAX_PLAN_BYTES = 64 * 1024 * 1024
MAX_ITEMS = 65535                     # MISSION_COUNT is 16 bits

# The fence and rally commands a .plan keeps in its geoFence and rallyPoints sections.
CMD_FENCE_RETURN_POINT = mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT
CMD_FENCE_POLYGON_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
CMD_FENCE_POLYGON_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
CMD_FENCE_CIRCLE_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
CMD_FENCE_CIRCLE_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
CMD_RALLY_POINT = mavlink.MAV_CMD_NAV_RALLY_POINT

# MAV_AUTOPILOT: what QGC writes as firmwareType (generic when the caller names none).
FIRMWARE_TYPES = {"generic": mavlink.MAV_AUTOPILOT_GENERIC, "ardupilot": mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                  "px4": mavlink.MAV_AUTOPILOT_PX4}
# MAV_TYPE: what QGC writes as vehicleType (generic when the caller names none).
VEHICLE_TYPES = {"generic": mavlink.MAV_TYPE_GENERIC, "fixedwing": mavlink.MAV_TYPE_FIXED_WING,
                 "plane": mavlink.MAV_TYPE_FIXED_WING, "copter": mavlink.MAV_TYPE_QUADROTOR,
                 "multirotor": mavlink.MAV_TYPE_QUADROTOR, "quadrotor": mavlink.MAV_TYPE_QUADROTOR,
                 "helicopter": mavlink.MAV_TYPE_HELICOPTER, "rover": mavlink.MAV_TYPE_GROUND_ROVER,
                 "boat": mavlink.MAV_TYPE_SURFACE_BOAT, "sub": mavlink.MAV_TYPE_SUBMARINE,
                 "hexarotor": mavlink.MAV_TYPE_HEXAROTOR, "octorotor": mavlink.MAV_TYPE_OCTOROTOR,
                 "vtol": mavlink.MAV_TYPE_VTOL_TILTROTOR}  # QGC treats every VTOL type alike

# QGC's AltMode enum (QGroundControlQmlGlobal.h) for globalPlanAltitudeMode / AltitudeMode.
ALT_MODE_MIXED, ALT_MODE_RELATIVE, ALT_MODE_ABSOLUTE, ALT_MODE_TERRAIN_FRAME = 0, 1, 2, 4
_FRAME_ALT_MODE = {FRAME_GLOBAL_RELATIVE_ALT: ALT_MODE_RELATIVE, FRAME_GLOBAL: ALT_MODE_ABSOLUTE,
                   FRAME_GLOBAL_TERRAIN_ALT: ALT_MODE_TERRAIN_FRAME}

# How MISSION_ITEM_INT carries x/y per MAV_FRAME (common.xml): global frames (itemcheck.GLOBAL_FRAMES) as
# degE7, local frames as metres * 1e4, anything else (MAV_FRAME_MISSION, BODY_FRD) as a plain integer.
# 22 and 23 are no MAV_FRAME (common.xml's end at 21, LOCAL_FLU): a file's item in them has its x/y read as
# a local frame's, then is refused by item_problem.
_LOCAL_FRAMES = frozenset({mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_LOCAL_ENU,
                           mavlink.MAV_FRAME_LOCAL_OFFSET_NED, mavlink.MAV_FRAME_BODY_NED,
                           mavlink.MAV_FRAME_BODY_OFFSET_NED, mavlink.MAV_FRAME_LOCAL_FRD, mavlink.MAV_FRAME_LOCAL_FLU,
                           22, 23})

QGC_DEFAULT_CRUISE_SPEED = 15.0   # QGC's application defaults, written when the caller gives none
QGC_DEFAULT_HOVER_SPEED = 5.0


def _scale(frame: int) -> int:
    if frame in GLOBAL_FRAMES:
        return 10**7
    if frame in _LOCAL_FRAMES:
        return 10**4
    return 1


def xy_hint(frame: int) -> str:
    """What x/y may hold in `frame` (the hint of a value that does not fit MISSION_ITEM_INT)."""
    s = _scale(frame)
    if s == 10**7:
        return "global frames carry lat/lon in degrees: latitude -90..90, longitude -180..180"
    if s == 10**4:
        return "local frames carry metres, at most ±214748 m (x/y travel as metres × 1e4 in 32 bits)"
    return f"frame {frame} carries x/y as 32-bit whole numbers (±2147483647)"


SIZE_HINT = "a 2000-item .plan is about 1 MB, a full 65535-item one up to 45 MB: is this the right file?"
READ_HINT = "check the path and that you may read the file"
FLOAT32_HINT = "params 1-4 and altitude travel as float32 (at most ±3.4e38); null means unset"
FLOAT32_METRES_HINT = "radii and altitudes travel as float32 (at most ±3.4e38): write the value in metres"


# -- writing ---------------------------------------------------------------------------------------

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


def _temp_beside(path: Path) -> tuple[int, str]:
    # its name is the target's and a few more characters: where it can be made, the target can be too
    return tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)


def _cannot_write(path: Path, err: OSError, what: str = "the file") -> PlanError:
    return PlanError(f"cannot write {what}: {err.strerror or err}", where=str(path),
                     hint="the directory must exist and be writable, the name at most 240 bytes")


def check_writable(path: str | Path) -> None:
    """Raise PlanError unless atomic_write(path, ...) can make its temporary file: asked before a long
    operation (a download) so that its result is not lost at the last step."""
    path = Path(path)
    try:
        fd, tmp = _temp_beside(path)
    except OSError as err:
        if not os.path.isdir(path.parent):  # isdir() answers False for any error
            raise PlanError("the output directory does not exist", where=str(path.parent),
                            hint="create it first") from None
        raise _cannot_write(path, err) from None
    os.close(fd)
    os.unlink(tmp)


def new_file_mode() -> int:
    """The permissions a new file gets here (0666 less the umask): mkstemp's temporary files are 0600."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _mode_for(path: Path) -> int:
    try:
        return stat.S_IMODE(os.stat(path).st_mode)  # a file replaced keeps its permissions
    except OSError:
        return new_file_mode()


@contextlib.contextmanager
def replacing(path: Path, what: str = "the file") -> Iterator[Path]:
    """A temporary file beside `path` to write, renamed onto `path` when the block ends; on any error it is
    removed and an existing file at `path` stays unchanged. An OSError becomes a PlanError naming `what`.
    The result has the replaced file's permissions, or a new file's (not the temporary file's 0600)."""
    try:
        fd, tmp = _temp_beside(path)
    except OSError as err:
        raise _cannot_write(path, err, what) from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _mode_for(path))
        os.replace(tmp, path)
    except BaseException as err:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(err, OSError):
            raise _cannot_write(path, err, what) from None
        raise


def atomic_write(path: Path, text: str) -> None:
    """Write `text` to `path` via a temporary file in the same directory and a rename; PlanError when
    that fails (nothing is left behind, an existing file at `path` is unchanged)."""
    with replacing(Path(path)) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="\n")


# -- reading ---------------------------------------------------------------------------------------

class PlanFile(NamedTuple):
    """What read_plan_file read from a .plan."""

    items: list[MissionItem]
    fence: list[MissionItem]
    rally: list[MissionItem]
    home: Home | None
    firmware: int          # mission.firmwareType: a MAV_AUTOPILOT (0, generic, when the file names none)
    vehicle: int           # mission.vehicleType: a MAV_TYPE
    notes: tuple[ReadNote, ...]


class _Reader:
    def __init__(self, name: str) -> None:
        self.name = name
        self.notes: list[ReadNote] = []

    def note(self, path: str, message: str) -> None:
        self.notes.append(ReadNote(f"{self.name}: {path}" if path else self.name, message))

    def err(self, path: str, message: str, hint: str) -> PlanError:
        return PlanError(message, where=f"{self.name}: {path}" if path else self.name, hint=hint)

    def obj(self, value: Any, path: str) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise self.err(path, f"expected a JSON object, found {_kind(value)}",
                           "write a JSON object { ... } here, as QGroundControl saves it" if path else
                           'a .plan file is one JSON object: {"fileType": "Plan", "mission": ...}')
        return value

    def key(self, obj: dict[str, Any], key: str, path: str, hint: str | None = None) -> Any:
        if key not in obj:
            raise self.err(path, f"missing key {key!r}",
                           hint or f"add {key!r} as QGroundControl writes it, or save the plan again in QGC")
        return obj[key]

    def version(self, obj: dict[str, Any], path: str, allowed: tuple[int, ...], what: str) -> int:
        v = self.key(obj, "version", path)
        if isinstance(v, bool) or not isinstance(v, (int, Decimal)) or v not in allowed:
            raise self.err(f"{path}.version" if path else "version",
                           f"{what} version {_show(v)} is not supported (QGroundControl writes "
                           f"{' or '.join(map(str, allowed))})",
                           "save the plan again with a current QGroundControl")
        return int(v)

    def number(self, value: Any, path: str, *, null_ok: bool = False) -> Decimal | None:
        if value is None and null_ok:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float, Decimal)):
            raise self.err(path, f"expected a number, found {_kind(value)}",
                           "write a JSON number without quotes, e.g. 47.3977507"
                           + (" (null for unset)" if null_ok else ""))
        d = Decimal(value) if not isinstance(value, Decimal) else value
        if not d.is_finite():
            return None if null_ok else self._nonfinite(path)
        return d

    def _nonfinite(self, path: str):
        raise self.err(path, "expected a finite number", "write a finite number here: NaN and Infinity are refused")

    def integer(self, value: Any, path: str, lo: int, hi: int, hint: str) -> int:
        d = self.number(value, path)
        if d is None or d != d.to_integral_value() or not lo <= d <= hi:
            raise self.err(path, f"expected a whole number in {lo}..{hi}, found {_show(value)}", hint)
        return int(d)

    def fixed(self, value: Any, path: str, frame: int) -> int:
        """x/y as MISSION_ITEM_INT carries them (null, as QGC writes NaN, becomes 0)."""
        d = self.number(value, path, null_ok=True)
        if d is None:
            return 0
        v = int((d * _scale(frame)).to_integral_value(rounding=ROUND_HALF_UP))
        if not -2**31 <= v < 2**31:
            raise self.err(path, f"{_show(value)} does not fit MISSION_ITEM_INT's 32-bit x/y for frame {frame}",
                           xy_hint(frame))
        return v

    def latlon(self, value: Any, path: str) -> tuple[int, int]:
        if not isinstance(value, list) or len(value) < 2:
            raise self.err(path, f"expected [lat, lon], found {_kind(value)}",
                           "write [latitude, longitude] in degrees, e.g. [47.3977507, 8.5456075]")
        lat = self.number(value[0], f"{path}[0]")
        lon = self.number(value[1], f"{path}[1]")
        assert lat is not None and lon is not None
        if not (-90 <= lat <= 90 and -180 <= lon <= 180):
            raise self.err(path, f"latitude {lat} / longitude {lon} out of range",
                           "check the order, [latitude, longitude]: latitude -90..90, longitude -180..180")
        return self.fixed(lat, f"{path}[0]", FRAME_GLOBAL), self.fixed(lon, f"{path}[1]", FRAME_GLOBAL)


def _kind(v: Any) -> str:
    return {dict: "an object", list: "an array", str: "a string", bool: "a boolean", type(None): "null"}.get(
        type(v), "a number")


def _show(v: Any) -> str:
    return json.dumps(v, default=str) if not isinstance(v, Decimal) else str(v)


def _f(d: Decimal | None) -> float:
    return math.nan if d is None else float(d)


def _float32(r: _Reader, d: Decimal | None, path: str, hint: str = FLOAT32_METRES_HINT) -> Decimal | None:
    """`d` unchanged if MISSION_ITEM_INT's float32 can carry it: a larger number would stop an upload
    half-way (on ArduPilot after MISSION_COUNT has cut the vehicle's list), so it is refused here."""
    if d is not None and abs(float(d)) > FLOAT32_MAX:
        raise r.err(path, f"{d} is beyond the float32 range MISSION_ITEM_INT carries", hint)
    return d


def capped_text(text: str | bytes, name: str, cap: int, utf8_hint: str, size_hint: str = SIZE_HINT) -> str:
    """A mission file's text, at most `cap` long; bytes decoded as UTF-8 (a byte order mark dropped)."""
    if isinstance(text, bytes):
        if len(text) > cap:
            raise PlanError(f"the file is larger than {cap // 2**20} MB", where=name, hint=size_hint)
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError as err:
            raise PlanError(f"not UTF-8 text (byte {err.start})", where=name, hint=utf8_hint) from None
    if len(text) > cap:
        raise PlanError(f"the file is larger than {cap // 2**20} MB", where=name, hint=size_hint)
    return text


def _parse_json(text: str | bytes, name: str) -> Any:
    text = capped_text(text, name, MAX_PLAN_BYTES, "a .plan file is JSON in UTF-8")
    try:
        return json.loads(text, parse_float=Decimal, parse_int=Decimal)
    except json.JSONDecodeError as err:
        raise PlanError(f"not valid JSON: {err.msg}", where=f"{name}:{err.lineno}:{err.colno}",
                        hint="a .plan file is the JSON QGroundControl saves") from None
    except RecursionError:
        raise PlanError("JSON nested too deeply", where=name,
                        hint="a .plan saved by QGroundControl nests about 8 levels: is this the right file?") from None


def _params_of(r: _Reader, it: dict[str, Any], path: str) -> Any:
    """An item's 7 params; a QGC 3.x item's 4 params and its "coordinate" [lat, lon, alt] joined into them, as
    QGC's MissionItem::_convertJsonV2ToV3 joins them."""
    params = r.key(it, "params", path)
    if "coordinate" not in it:
        return params
    coordinate = it["coordinate"]
    if not isinstance(coordinate, list) or len(coordinate) != 3:
        raise r.err(f"{path}.coordinate", f"expected [lat, lon, altitude], found {_kind(coordinate)}",
                    "a QGroundControl 3.x item keeps its position as [latitude, longitude, altitude]")
    if not isinstance(params, list) or len(params) != 4:
        raise r.err(f"{path}.params", "an item with a \"coordinate\" has 4 params (QGroundControl 3.x)",
                    "write params as [p1, p2, p3, p4] beside the coordinate, or 7 params without it")
    return params + coordinate


def _simple(r: _Reader, raw: Any, path: str, mission_type: int) -> MissionItem:
    it = r.obj(raw, path)
    command = r.integer(r.key(it, "command", path), f"{path}.command", 0, 65535,
                        "write the MAV_CMD number without quotes, e.g. 16 (NAV_WAYPOINT)")
    frame = r.integer(r.key(it, "frame", path), f"{path}.frame", 0, 255,
                      "write the MAV_FRAME number without quotes, e.g. 3 (GLOBAL_RELATIVE_ALT)")
    params = _params_of(r, it, path)
    if not isinstance(params, list) or len(params) != 7:
        raise r.err(f"{path}.params", f"expected an array of 7 numbers (null for NaN), found {_kind(params)}"
                    + (f" of {len(params)}" if isinstance(params, list) else ""),
                    "params is [p1, p2, p3, p4, lat/x, lon/y, alt/z], null for an unset value")
    auto = r.key(it, "autoContinue", path)
    if not isinstance(auto, bool):
        raise r.err(f"{path}.autoContinue", f"expected true or false, found {_kind(auto)}",
                    "write true or false without quotes")
    p = [r.number(v, f"{path}.params[{k}]", null_ok=True) for k, v in enumerate(params)]
    for k in (0, 1, 2, 3, 6):
        _float32(r, p[k], f"{path}.params[{k}]", FLOAT32_HINT)
    item = MissionItem(command=command, frame=frame, param1=_f(p[0]), param2=_f(p[1]), param3=_f(p[2]),
                       param4=_f(p[3]), x=r.fixed(params[4], f"{path}.params[4]", frame),
                       y=r.fixed(params[5], f"{path}.params[5]", frame), z=_f(p[6]), autocontinue=int(auto),
                       mission_type=mission_type)
    _check_item(r, item, path, unset=frozenset(f for f, v in (("x", p[4]), ("y", p[5])) if v is None))
    return item


# Where item_problem's fields are in a .plan SimpleItem.
_PLAN_FIELDS = {"x": ".params[4]", "y": ".params[5]", "z": ".params[6]", "frame": ".frame",
                "autocontinue": ".autoContinue", "command": ".command"}


def _check_item(r: _Reader, item: MissionItem, path: str, unset: frozenset[str] = frozenset(),
                fields: dict[str, str] = _PLAN_FIELDS) -> None:
    """PlanError at the item's field when it is no real position or holds what no vehicle takes."""
    problem = item_problem(item, unset=unset)
    if problem is not None:
        raise r.err(path + fields.get(problem.field, ""), f"{command_label(item.command)}: {problem.message}",
                    problem.hint)


def _complex(r: _Reader, it: dict[str, Any], path: str) -> list[MissionItem]:
    kind = r.key(it, "complexItemType", path)
    if kind in ("survey", "CorridorScan"):
        if kind == "survey":
            # Versions 4 and 5 keep the generated items under TransectStyleComplexItem (the older
            # v2/v3 layout is only readable by QGC itself); 5 is what QGC writes today.
            r.version(it, path, (4, 5), "survey")
        transect = r.obj(r.key(it, "TransectStyleComplexItem", path,
                               "a survey stores its generated items under TransectStyleComplexItem.Items"),
                         f"{path}.TransectStyleComplexItem")
        tpath = f"{path}.TransectStyleComplexItem"
        inner = transect.get("Items")
        if not isinstance(inner, list) or not inner:
            raise r.err(f"{tpath}.Items", f"the {kind} has no stored mission items",
                        "open the plan in QGroundControl and save it again: QGC stores the generated items")
        return [_simple(r, x, f"{tpath}.Items[{k}]", MISSION_TYPE_MISSION) for k, x in enumerate(inner)]
    if kind == "StructureScan":
        raise r.err(f"{path}.complexItemType", "a StructureScan stores no mission items in the file (QGC "
                    "computes them when it loads the plan)",
                    "upload it from QGroundControl, or replace it with waypoints or a capture plan")
    raise r.err(f"{path}.complexItemType", f"complex item type {_show(kind)} is not supported",
                "supported: survey, CorridorScan (their stored Items)")


def _mission(r: _Reader, mission: dict[str, Any]) -> tuple[list[MissionItem], Home | None]:
    r.version(mission, "mission", (2,), "mission")
    raw_items = r.key(mission, "items", "mission")
    if not isinstance(raw_items, list):
        raise r.err("mission.items", f"expected an array, found {_kind(raw_items)}",
                    'write "items": [ ... ], as QGroundControl does ([] for an empty mission)')
    items: list[MissionItem] = []
    for k, raw in enumerate(raw_items):
        path = f"mission.items[{k}]"
        it = r.obj(raw, path)
        kind = r.key(it, "type", path)
        if kind == "SimpleItem":
            items.append(_simple(r, it, path, MISSION_TYPE_MISSION))
        elif kind == "ComplexItem":
            items.extend(_complex(r, it, path))
        else:
            raise r.err(f"{path}.type", f"item type {_show(kind)} is not SimpleItem or ComplexItem",
                        'QGroundControl writes "type": "SimpleItem" or "ComplexItem"; use one of them')
        if len(items) > MAX_ITEMS:
            raise r.err(path, f"more than {MAX_ITEMS} mission items",
                        f"a MAVLink mission holds at most {MAX_ITEMS} items: split the plan")
    home: Home | None = None
    raw_home = mission.get("plannedHomePosition")
    if raw_home is not None:
        if not isinstance(raw_home, list) or len(raw_home) != 3:
            raise r.err("mission.plannedHomePosition", "expected [lat, lon, altitude AMSL]",
                        "write it as [latitude, longitude, altitude AMSL], e.g. [47.3977507, 8.5456075, 488]")
        x, y = r.latlon(raw_home, "mission.plannedHomePosition")
        # ArduPilot's item 0 on upload: its altitude travels as float32 too
        alt = _float32(r, r.number(raw_home[2], "mission.plannedHomePosition[2]", null_ok=True),
                       "mission.plannedHomePosition[2]")
        home = (x / 1e7, y / 1e7, 0.0 if alt is None else float(alt))
        problem = home_problem(home)   # latlon() judged the position: only its altitude is left
        if problem is not None:
            raise r.err("mission.plannedHomePosition[2]", problem.message, problem.hint)
    return items, home


def _skipped_as_qgc_skips(r: _Reader, section: dict[str, Any], path: str, *, unversioned: bool) -> bool:
    """True when QGroundControl skips this geoFence/rallyPoints section of a 3.x save: version 1 (and, for
    geoFence, no version). The skip gets a note: the vehicle would keep whatever fence or rally it holds."""
    v = section.get("version")
    if v is None and unversioned:
        r.note(path, "no version: an early QGroundControl 3.x section, skipped as QGroundControl skips it "
                     "(nothing of it is read)")
        return True
    if not isinstance(v, bool) and isinstance(v, (int, Decimal)) and v == 1:
        r.note(path, "version 1 (QGroundControl 3.x), skipped as QGroundControl skips it (nothing of it is "
                     "read)")
        return True
    return False


def _fence(r: _Reader, fence: dict[str, Any]) -> list[MissionItem]:
    if _skipped_as_qgc_skips(r, fence, "geoFence", unversioned=True):
        return []
    r.version(fence, "geoFence", (2,), "geoFence")
    out: list[MissionItem] = []
    polygons = fence.get("polygons", [])
    circles = fence.get("circles", [])
    for name, value in (("polygons", polygons), ("circles", circles)):
        if not isinstance(value, list):
            raise r.err(f"geoFence.{name}", f"expected an array, found {_kind(value)}",
                        f'write "{name}": [ ... ] ([] for none)')
    for k, raw in enumerate(polygons):
        path = f"geoFence.polygons[{k}]"
        poly = r.obj(raw, path)
        inclusion = r.key(poly, "inclusion", path)
        vertices = r.key(poly, "polygon", path)
        if not isinstance(inclusion, bool) or not isinstance(vertices, list) or len(vertices) < 3:
            raise r.err(path, "a fence polygon needs \"inclusion\": true/false and at least 3 [lat, lon] vertices",
                        'e.g. {"inclusion": true, "polygon": [[47.1, 8.1], [47.2, 8.1], [47.2, 8.2]], "version": 1}')
        cmd = CMD_FENCE_POLYGON_INCLUSION if inclusion else CMD_FENCE_POLYGON_EXCLUSION
        for j, v in enumerate(vertices):
            x, y = r.latlon(v, f"{path}.polygon[{j}]")
            out.append(MissionItem(command=cmd, frame=FRAME_GLOBAL, param1=float(len(vertices)), x=x, y=y,
                                   mission_type=MISSION_TYPE_FENCE))
    for k, raw in enumerate(circles):
        path = f"geoFence.circles[{k}]"
        c = r.obj(raw, path)
        inclusion = r.key(c, "inclusion", path)
        circle = r.obj(r.key(c, "circle", path), f"{path}.circle")
        x, y = r.latlon(r.key(circle, "center", f"{path}.circle"), f"{path}.circle.center")
        radius = _float32(r, r.number(r.key(circle, "radius", f"{path}.circle"), f"{path}.circle.radius"),
                          f"{path}.circle.radius")
        if not isinstance(inclusion, bool) or radius is None or radius <= 0:
            raise r.err(path, "a fence circle needs \"inclusion\": true/false and a positive radius",
                        'e.g. {"circle": {"center": [47.1, 8.1], "radius": 50}, "inclusion": true} (radius in m)')
        out.append(MissionItem(command=CMD_FENCE_CIRCLE_INCLUSION if inclusion else CMD_FENCE_CIRCLE_EXCLUSION,
                               frame=FRAME_GLOBAL, param1=float(radius), x=x, y=y, mission_type=MISSION_TYPE_FENCE))
    ret = fence.get("breachReturn")
    if isinstance(ret, list) and len(ret) == 3:
        x, y = r.latlon(ret, "geoFence.breachReturn")
        if (x, y) != (0, 0):
            alt = _float32(r, r.number(ret[2], "geoFence.breachReturn[2]", null_ok=True), "geoFence.breachReturn[2]")
            out.append(MissionItem(command=CMD_FENCE_RETURN_POINT, frame=FRAME_GLOBAL_RELATIVE_ALT, x=x, y=y,
                                   z=0.0 if alt is None else float(alt), mission_type=MISSION_TYPE_FENCE))
            _check_item(r, out[-1], "geoFence.breachReturn", fields={"z": "[2]"})
    return out


def _rally(r: _Reader, rally: dict[str, Any]) -> list[MissionItem]:
    # RallyPointController::load skips version 1 only; without a version its key check fails.
    if _skipped_as_qgc_skips(r, rally, "rallyPoints", unversioned=False):
        return []
    r.version(rally, "rallyPoints", (2,), "rallyPoints")
    points = rally.get("points", [])
    if not isinstance(points, list):
        raise r.err("rallyPoints.points", f"expected an array, found {_kind(points)}",
                    'write "points": [[latitude, longitude, altitude], ...] ([] for none)')
    out = []
    for k, p in enumerate(points):
        path = f"rallyPoints.points[{k}]"
        if not isinstance(p, list) or len(p) != 3:
            raise r.err(path, "expected [lat, lon, altitude]",
                        "write the point as [latitude, longitude, altitude], e.g. [47.3977507, 8.5456075, 30]")
        x, y = r.latlon(p, path)
        alt = _float32(r, r.number(p[2], f"{path}[2]"), f"{path}[2]")
        out.append(MissionItem(command=CMD_RALLY_POINT, frame=FRAME_GLOBAL_RELATIVE_ALT, x=x, y=y, z=float(alt),
                               mission_type=MISSION_TYPE_RALLY))
        _check_item(r, out[-1], path, fields={"z": "[2]"})
    return out


def read_plan(text: str | bytes, name: str = "<plan>") -> tuple[list[MissionItem], list[MissionItem],
                                                                  list[MissionItem], Home | None]:
    """(mission items, fence items, rally items, home) from .plan text; PlanError with a location."""
    read = read_plan_file(text, name)
    return read.items, read.fence, read.rally, read.home


def read_plan_file(text: str | bytes, name: str = "<plan>") -> PlanFile:
    """Everything read_plan reads, and the plan's firmware and vehicle types and the notes of what was skipped."""
    doc = _parse_json(text, name)
    r = _Reader(name)
    top = r.obj(doc, "")
    file_type = top.get("fileType")
    if file_type != "Plan":
        raise r.err("fileType", f"fileType is {_show(file_type)}, not \"Plan\"",
                    "this is not a QGroundControl plan file (a .mission or fence/rally file?)")
    r.version(top, "", (1,), "plan file")
    mission = r.obj(r.key(top, "mission", "", "the plan has no mission section"), "mission")
    items, home = _mission(r, mission)
    # QGC writes both sections; MAVSDK's importer fails without them, so a file lacking one is broken.
    fence = _fence(r, r.obj(r.key(top, "geoFence", "", "QGroundControl always writes a geoFence section"),
                            "geoFence"))
    rally = _rally(r, r.obj(r.key(top, "rallyPoints", "", "QGroundControl always writes a rallyPoints section"),
                            "rallyPoints"))
    firmware = _type_code(r, mission, "firmwareType", FIRMWARE_TYPES["generic"])
    vehicle = _type_code(r, mission, "vehicleType", VEHICLE_TYPES["generic"])
    return PlanFile(items, fence, rally, home, firmware, vehicle, tuple(r.notes))


def _type_code(r: _Reader, mission: dict[str, Any], key: str, default: int) -> int:
    """mission.firmwareType / vehicleType (a MAV_AUTOPILOT / MAV_TYPE number), `default` when absent."""
    if key not in mission:
        return default
    return r.integer(mission[key], f"mission.{key}", 0, 255,
                     "write the MAV_AUTOPILOT (firmwareType: 3 ArduPilot, 12 PX4) or MAV_TYPE number, as QGC does")


def load_plan(path: str | Path) -> tuple[list[MissionItem], list[MissionItem], list[MissionItem], Home | None]:
    """read_plan on a file, reading at most the size limit of it."""
    read = load_plan_file(path)
    return read.items, read.fence, read.rally, read.home


def load_plan_file(path: str | Path) -> PlanFile:
    """read_plan_file on a file, reading at most the size limit of it."""
    data = read_user_file(path, UserFile(".plan file", MAX_PLAN_BYTES, PlanError, READ_HINT, SIZE_HINT))
    from missions.formats.outputs import check_output   # not at the top: outputs imports this module
    check_output(path)       # a compiled NAME.plan: only the last complete compile's
    return read_plan_file(data, str(path))
