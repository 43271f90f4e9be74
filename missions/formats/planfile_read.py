"""QGroundControl `.plan` files read (read_plan, read_plan_file, load_plan, load_plan_file) as QGC reads them:
strict about versions, sections and keys, QGC 3.x's skipped sections noted, complex items' stored items taken;
see missions.formats.planfile.
"""

from __future__ import annotations

import json
import math
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path
from typing import Any, NamedTuple

from cdf.float32 import FLOAT32_MAX  # params 1-4 and z travel as float32
from cdf.userfile import UserFile, read_user_file
from missions.errors import PlanError
from missions.formats.readnote import ReadNote
from missions.formats.itemcheck import command_label, home_problem, item_problem
from missions.emit.items import (FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, MISSION_TYPE_FENCE, MISSION_TYPE_MISSION,
                                 MISSION_TYPE_RALLY, MissionItem)
from missions.formats.planfile_common import (CMD_FENCE_CIRCLE_EXCLUSION, CMD_FENCE_CIRCLE_INCLUSION,
                                              CMD_FENCE_POLYGON_EXCLUSION, CMD_FENCE_POLYGON_INCLUSION,
                                              CMD_FENCE_RETURN_POINT, CMD_RALLY_POINT, FIRMWARE_TYPES, FLOAT32_HINT,
                                              FLOAT32_METRES_HINT, Home, MAX_ITEMS, MAX_PLAN_BYTES, READ_HINT,
                                              SIZE_HINT, VEHICLE_TYPES, _scale, xy_hint)


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
