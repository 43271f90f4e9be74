"""`QGC WPL 110` waypoint files (Mission Planner, MAVProxy `wp load/save`, pymavlink mavwp): pure.

    text = write_wpl(items, (lat, lon, alt_amsl))          # home row + items
    items, home = read_wpl(text, "survey.waypoints")

Format (mavlink.io file_formats): the line `QGC WPL 110`, then one tab-separated row per item:
INDEX CURRENT FRAME COMMAND P1 P2 P3 P4 X/LAT Y/LON Z/ALT AUTOCONTINUE.

Home row: ArduPilot keeps home as mission item 0, so Mission Planner and MAVProxy files for it
carry home in row 0 (frame 0 = absolute altitude) and the mission from row 1. `write_wpl` always
writes that row (home, or 0/0/0 when unknown - ArduPilot overwrites item 0 with its own home on
upload); `read_wpl` takes row 0 as home when it looks like one (NAV_WAYPOINT - or command 0, an
old Mission Planner quirk pymavlink also accepts - in frame 0), else every row is a mission item.
Pass `home_row=True/False` to decide explicitly.

Numbering, read as pymavlink's MAVWPLoader reads it (mavwp.py add(): a row's seq is its position), with a
ReadNote for each repair (`read_wpl_file(...).notes`):
  * a gap (0, 1, 2, 4: ArduPilot's autotest `inf_loop.txt`) is renumbered; a DO_JUMP to a renumbered row
    follows it;
  * rows from 1 with no row 0 (DroneKit's save_mission wrote them so, skipping home) are the mission's items
    1.. with home unknown;
  * a duplicated or decreasing index is ambiguous (which row is meant?) and refused at its line.
Fence and rally files: a file whose rows are all NAV_FENCE_* commands (5000-5004, as Mission Planner and
MAVProxy save a fence) is a fence, all NAV_RALLY_POINT (5100) a rally list; `mission_type` says which, and
there is no home row. A file that mixes them with mission items is refused. `fence_wpl_text` writes one.

Numbers: latitude/longitude with exactly 7 decimals (the wire's degE7, so nothing is lost;
pymavlink's own writer keeps only 6, ~0.1 m), other values in the shortest form that reads back to
the same double, NaN as `NaN` (pymavlink and Mission Planner both parse it). Reading accepts any
whitespace between fields (as pymavlink does), `#` comment lines and blank lines.
"""

from __future__ import annotations

import math
import os
from decimal import ROUND_HALF_UP, Decimal, InvalidOperation
from pathlib import Path
from typing import NamedTuple

from cdf.userfile import UserFile, read_user_file
from missions.errors import PlanError
from missions.formats.itemcheck import check_items, command_label, home_problem, item_problem
from missions.emit.items import (FRAME_GLOBAL, MISSION_TYPE_FENCE, MISSION_TYPE_MISSION, MISSION_TYPE_RALLY,
                                 MissionItem, deg_to_e7, mavlink)
from missions.formats.readnote import ReadNote
from missions.formats.planfile import (FLOAT32_MAX, MAX_ITEMS, READ_HINT, _scale, atomic_write, capped_text,
                                      check_finite, xy_hint)

Home = tuple[float, float, float]

HEADER = "QGC WPL 110"
# A full 65535-item file is about 6 MB, up to 12 MB with every float at its longest: wpl_text writes
# nothing this tool could not read again.
MAX_WPL_BYTES = 16 * 1024 * 1024
SIZE_HINT = "a waypoint file of 65535 items is about 6 MB, at most 12 MB: is this the right file?"
# Old Mission Planner files write the home row as command 0, which is no MAV_CMD; pymavlink's mavwp reads it
# as home too.
OLD_MP_HOME_COMMAND = 0

FENCE_COMMANDS = frozenset({mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT, mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                            mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
                            mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION})
RALLY_COMMANDS = frozenset({mavlink.MAV_CMD_NAV_RALLY_POINT})
_POLYGON_COMMANDS = frozenset({mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                               mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION})
LIST_NAMES = {MISSION_TYPE_MISSION: "mission", MISSION_TYPE_FENCE: "fence", MISSION_TYPE_RALLY: "rally"}


class WplFile(NamedTuple):
    """What read_wpl_file read: one list's items (no home row), the file's home, which list the rows are
    (MISSION_TYPE_MISSION, _FENCE or _RALLY) and a note for each repair."""

    items: list[MissionItem]
    home: Home | None
    mission_type: int
    notes: tuple[ReadNote, ...]


def _num(v: float) -> str:
    if math.isnan(v):
        return "NaN"
    if math.isinf(v):
        # wpl_text's check_finite refuses every infinite field of the items and home first
        raise PlanError(f"an infinite value ({v}) cannot be written to a waypoint file",
                        hint="a bug in wiris-tools: please report it")
    if float(v).is_integer() and abs(v) < 2**53:
        return str(int(v))
    return repr(float(v))


def _fixed(v: int, frame: int) -> str:
    s = _scale(frame)
    if s == 1:
        return str(int(v))
    digits = len(str(s)) - 1
    sign = "-" if v < 0 else ""
    whole, frac = divmod(abs(int(v)), s)
    return f"{sign}{whole}.{frac:0{digits}d}"


def _row(index: int, it: MissionItem, current: int) -> str:
    return "\t".join((str(index), str(current), str(it.frame), str(it.command), _num(it.param1), _num(it.param2),
                      _num(it.param3), _num(it.param4), _fixed(it.x, it.frame), _fixed(it.y, it.frame),
                      _num(it.z), str(it.autocontinue)))


def _home_item(home: Home | None) -> MissionItem:
    lat, lon, alt = home if home is not None else (0.0, 0.0, 0.0)
    return MissionItem(command=mavlink.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL, x=deg_to_e7(lat), y=deg_to_e7(lon),
                       z=float(alt))


def wpl_text(items, home: Home | None = None) -> str:
    items = list(items)
    if len(items) + 1 > MAX_ITEMS:
        raise PlanError(f"{len(items)} items do not fit a MAVLink mission (at most {MAX_ITEMS - 1} plus home)",
                        hint="save a .plan instead (it keeps home apart: 65535 items fit), or split the mission")
    check_finite("a waypoint", home, items)
    check_items("a waypoint", home, items)   # what this writes, read_wpl reads
    lines = [HEADER, _row(0, _home_item(home), 1)]
    lines += [_row(i + 1, it, 0) for i, it in enumerate(items)]
    return "\n".join(lines) + "\n"


def fence_wpl_text(items) -> str:
    """WPL 110 text of a fence or rally list as Mission Planner saves one: its rows from 0, no home row."""
    items = list(items)
    check_finite("a waypoint", None, fence=items)
    check_items("a waypoint", None, fence=items)
    return "\n".join([HEADER] + [_row(i, it, 0) for i, it in enumerate(items)]) + "\n"


def write_wpl(items, /, *args, home: Home | None = None, firmware: str | None = None) -> str:
    """WPL 110 text: home row 0, then `items` (which never contain a home row) from row 1.

    `write_wpl(items, home)` returns the text. File form, used by missions.formats.outputs:
    `write_wpl(path, items, home=..., firmware=...)` also writes it to `path` atomically.
    `firmware` is accepted for symmetry with write_plan; the file is the same for both stacks: row 0 is home
    in the format (Mission Planner writes it so, QGroundControl reads it so for either stack). MAVSDK's
    importer (MissionImport::parse_mission_planner) does not: it uploads row 0 as a mission item (and for
    ArduPilot puts another home in front), so MAVSDK users load NAME.plan instead (README, limitations).
    """
    if isinstance(items, (str, os.PathLike)):
        if len(args) != 1:
            raise TypeError("write_wpl(path, items, home=...) takes the items after the path")
        text = wpl_text(args[0], home)
        atomic_write(Path(items), text)
        return text
    if args:
        if len(args) > 1 or home is not None:
            raise TypeError("write_wpl(items, home) takes at most one positional home")
        home = args[0]
    return wpl_text(items, home)


def _decimal(field: str, where: str, what: str) -> Decimal:
    try:
        d = Decimal(field)
    except InvalidOperation:
        raise PlanError(f"{what} {field!r} is not a number", where=where,
                        hint="every field of a row is a number, e.g. 16, -35.3632621 or NaN (an unset param)") from None
    return d


def read_wpl(text: str | bytes, name: str = "<waypoints>", *,
             home_row: bool | None = None) -> tuple[list[MissionItem], Home | None]:
    """(items, home) from WPL 110 text; PlanError with NAME:LINE otherwise (read_wpl_file: also the kind of
    list and the repair notes)."""
    read = read_wpl_file(text, name, home_row=home_row)
    return read.items, read.home


def read_wpl_file(text: str | bytes, name: str = "<waypoints>", *, home_row: bool | None = None) -> WplFile:
    """The items, home, list kind and repair notes of WPL 110 text; PlanError with NAME:LINE otherwise."""
    lines = _decoded(text, name).splitlines()
    if not lines or lines[0].strip() != HEADER:
        first = lines[0].strip()[:40] if lines else ""
        raise PlanError(f"the first line is {first!r}, not {HEADER!r}", where=f"{name}:1",
                        hint="only QGC WPL 110 is read (Mission Planner and MAVProxy save it)")
    notes: list[ReadNote] = []
    rows = _renumbered(_read_rows(lines[1:], name), notes)
    kind = _list_kind(rows)
    if kind != MISSION_TYPE_MISSION:
        return _other_list(rows, kind, notes)
    if home_row is None:
        home_row = bool(rows) and rows[0].index == 0 and _looks_like_home(rows[0].item)
    home: Home | None = None
    items = [row.item for row in rows]
    if home_row and items:
        items.pop(0)
        home = _home_of(rows[0])
        _check_row(rows[0], home_problem(home))
    for row in rows[1:] if home_row else rows:
        _check_row(row, item_problem(row.item, unset=row.unset))
    return WplFile(items, home, MISSION_TYPE_MISSION, tuple(notes))


def _renumbered(rows: list[_Row], notes: list[ReadNote]) -> list[_Row]:
    """The rows numbered by their position, as MAVWPLoader numbers them: a note for each gap, and
    DO_JUMP targets moved with the rows they name. Rows from 1 (no home row 0) keep their numbers, which
    already count home as 0. PlanError at a duplicated or decreasing index: which row is meant is unclear."""
    if not rows:
        return rows
    first = 1 if rows[0].index == 1 else 0
    if rows[0].index == 1:
        notes.append(ReadNote(rows[0].where, "rows start at index 1 and there is no home row 0 (DroneKit's "
                                             "save_mission writes files so): read as mission items 1.., home unknown"))
    renumber: dict[int, int] = {}
    seen: dict[int, str] = {}
    previous = -1
    for pos, row in enumerate(rows, start=first):
        if row.index in seen:
            raise PlanError(f"row index {row.index} appears twice (first at {seen[row.index]})", where=row.where,
                            hint="which of the two rows is meant cannot be told: give every row its own index, "
                                 "numbered 0, 1, 2, ... in file order")
        if row.index < previous:
            raise PlanError(f"row index {row.index} comes after {previous}", where=row.where,
                            hint="whether file order or index order is meant cannot be told: number the rows "
                                 "0, 1, 2, ... in the order they are flown")
        seen[row.index] = row.where
        previous = row.index
        if row.index != pos:
            notes.append(ReadNote(row.where, f"row index {row.index} read as {pos} (the rows before it end at "
                                             f"{pos - 1}), as pymavlink's MAVWPLoader renumbers"))
            renumber[row.index] = pos
    return [_jump_followed(row, renumber, seen, notes) for row in rows] if renumber else rows


def _jump_followed(row: _Row, renumber: dict[int, int], present: dict[int, str], notes: list[ReadNote]) -> _Row:
    """`row`, a DO_JUMP to a renumbered row pointed at that row's new number."""
    it = row.item
    if it.command != mavlink.MAV_CMD_DO_JUMP or not float(it.param1).is_integer():
        return row
    target = int(it.param1)
    if target not in present:
        raise PlanError(f"DO_JUMP to row {target}, which the file does not have, in a file renumbered to close "
                        "its gaps", where=row.where,
                        hint="number the rows 0, 1, 2, ... and point the jump at the row it should repeat from")
    if target not in renumber:
        return row
    notes.append(ReadNote(row.where, f"DO_JUMP to row {target} follows it to its new number {renumber[target]}"))
    return row._replace(item=it.with_(param1=float(renumber[target])))


def _row_kind(row: _Row) -> int:
    command = row.item.command
    return (MISSION_TYPE_FENCE if command in FENCE_COMMANDS else MISSION_TYPE_RALLY if command in RALLY_COMMANDS
            else MISSION_TYPE_MISSION)


def _list_kind(rows: list[_Row]) -> int:
    """Which list the rows are, by the first row: fence commands a fence, rally points a rally list, else a
    mission; PlanError at the first row of another kind (a file holds one list)."""
    if not rows:
        return MISSION_TYPE_MISSION
    kind = _row_kind(rows[0])
    for r in rows[1:]:
        if _row_kind(r) != kind:
            raise PlanError(f"{command_label(r.item.command)} in a file of {LIST_NAMES[kind]} rows "
                            f"(the first row is {command_label(rows[0].item.command)})", where=r.where,
                            hint="a fence (or rally) file holds only NAV_FENCE_* (or NAV_RALLY_POINT) rows, a "
                                 "mission none: save the fence and the mission as separate files, or as one .plan")
    return kind


def _other_list(rows: list[_Row], kind: int, notes: list[ReadNote]) -> WplFile:
    """A fence or rally file's items (there is no home row); fence polygons checked vertex by vertex."""
    items = [r.item.with_(mission_type=kind) for r in rows]
    for r, it in zip(rows, items):
        _check_row(r, item_problem(it, unset=r.unset))
    if kind == MISSION_TYPE_FENCE:
        _check_polygons(rows)
    return WplFile(items, None, kind, tuple(notes))


def _check_polygons(rows: list[_Row]) -> None:
    """PlanError at the first polygon vertex whose polygon is not param1 = N consecutive rows of one command."""
    i = 0
    while i < len(rows):
        it = rows[i].item
        if it.command not in _POLYGON_COMMANDS:
            i += 1
            continue
        n = int(it.param1) if math.isfinite(it.param1) and float(it.param1).is_integer() else 0
        group = rows[i:i + n]
        if n < 3 or len(group) < n or any(g.item.command != it.command or g.item.param1 != it.param1 for g in group):
            raise PlanError(f"a fence polygon of {it.param1:g} vertices needs that many consecutive "
                            f"{command_label(it.command)} rows with param1 = {it.param1:g}", where=rows[i].where,
                            hint="param1 of every vertex is the polygon's vertex count (at least 3), and its "
                                 "vertices follow each other")
        i += n


def _decoded(text: str | bytes, name: str) -> str:
    return capped_text(text, name, MAX_WPL_BYTES,
                       "save the file as UTF-8 (a comment in another encoding?) or export it again", SIZE_HINT)


class _Row(NamedTuple):
    where: str                 # NAME:LINE
    index: int                 # the row's INDEX field, as the file numbers it
    item: MissionItem
    unset: frozenset[str]      # "x"/"y" written as NaN (read as 0)


class _WholeFields(NamedTuple):
    """The fields of a row that are whole numbers."""

    index: int
    current: int
    frame: int
    command: int
    autocontinue: int


# (field number, name in messages, largest value) of each of _WholeFields, in its order.
_WHOLE_FIELDS = ((0, "index", 65535), (1, "current", 1), (2, "frame", 255), (3, "command", 65535),
                 (11, "autocontinue", 1))


def _read_rows(lines: list[str], name: str) -> list[_Row]:
    """Each row after the header line (blank and `#` lines skipped), its values checked as they are read."""
    rows: list[_Row] = []
    for lineno, line in enumerate(lines, start=2):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        where = f"{name}:{lineno}"
        rows.append(_read_row(stripped.split(), where))
        if len(rows) > MAX_ITEMS:
            raise PlanError(f"more than {MAX_ITEMS} rows", where=where,
                            hint=f"a MAVLink mission holds at most {MAX_ITEMS} items, home included: split the file")
    return rows


def _read_row(fields: list[str], where: str) -> _Row:
    """One row from its whitespace-separated fields (its index is judged with the others: _renumbered)."""
    if len(fields) != 12:
        raise PlanError(f"expected 12 fields, found {len(fields)}", where=where,
                        hint="INDEX CURRENT FRAME COMMAND P1 P2 P3 P4 LAT LON ALT AUTOCONTINUE")
    whole = _whole_fields(fields, where)
    params = [float(_decimal(fields[k], where, f"param{k - 3}")) for k in range(4, 8)]
    z = float(_decimal(fields[10], where, "altitude/z"))
    if any(abs(v) > FLOAT32_MAX for v in (*params, z) if not math.isnan(v)):
        raise PlanError("a value is beyond the float32 range MISSION_ITEM_INT carries", where=where,
                        hint="params 1-4 and altitude travel as float32 (at most ±3.4e38); NaN means unset")
    (x, y), unset = _position_fields(fields, whole.frame, where)
    item = MissionItem(command=whole.command, frame=whole.frame, param1=params[0], param2=params[1],
                       param3=params[2], param4=params[3], x=x, y=y, z=z, autocontinue=whole.autocontinue,
                       current=whole.current, mission_type=MISSION_TYPE_MISSION)
    return _Row(where, whole.index, item, unset)


def _whole_fields(fields: list[str], where: str) -> _WholeFields:
    values = []
    for k, what, hi in _WHOLE_FIELDS:
        d = _decimal(fields[k], where, what)
        if not d.is_finite() or d != d.to_integral_value():
            raise PlanError(f"{what} {fields[k]!r} is not a whole number", where=where,
                            hint="write it without decimals, e.g. 16; current and autocontinue are 0 or 1")
        if not 0 <= d <= hi:
            raise PlanError(f"{what} {int(d)} is outside 0..{hi}", where=where,
                            hint="current and autocontinue are 0 or 1" if hi == 1 else
                            f"{what} is a number from 0 to {hi}")
        values.append(int(d))
    return _WholeFields(*values)


def _position_fields(fields: list[str], frame: int, where: str) -> tuple[tuple[int, int], frozenset[str]]:
    """x/y as MISSION_ITEM_INT carries them in `frame`, and which of them the row left NaN (read as 0)."""
    xy = []
    unset = set()
    for k, what in ((8, "latitude/x"), (9, "longitude/y")):
        d = _decimal(fields[k], where, what)
        if not d.is_finite():
            xy.append(0)
            unset.add("xy"[k - 8])
            continue
        v = int((d * _scale(frame)).to_integral_value(rounding=ROUND_HALF_UP))
        if not -2**31 <= v < 2**31:
            raise PlanError(f"{what} {fields[k]} does not fit MISSION_ITEM_INT for frame {frame}", where=where,
                            hint=xy_hint(frame))
        xy.append(v)
    return (xy[0], xy[1]), frozenset(unset)


def _looks_like_home(item: MissionItem) -> bool:
    """Row 0 as Mission Planner and MAVProxy write home for ArduPilot: a NAV_WAYPOINT (or command 0) in
    absolute altitude."""
    return item.command in (mavlink.MAV_CMD_NAV_WAYPOINT, OLD_MP_HOME_COMMAND) and item.frame == FRAME_GLOBAL


def _home_of(row: _Row) -> Home:
    """Home from its row: a NaN latitude or longitude stays NaN (home_problem refuses it)."""
    h = row.item
    return (math.nan if "x" in row.unset else h.x / 1e7, math.nan if "y" in row.unset else h.y / 1e7, h.z)


def _check_row(row: _Row, problem) -> None:
    """PlanError at the row when item_problem/home_problem found one."""
    if problem is not None:
        raise PlanError(f"{command_label(row.item.command)}: {problem.message}", where=row.where, hint=problem.hint)


def load_wpl(path: str | Path, *, home_row: bool | None = None) -> tuple[list[MissionItem], Home | None]:
    read = load_wpl_file(path, home_row=home_row)
    return read.items, read.home


def load_wpl_file(path: str | Path, *, home_row: bool | None = None) -> WplFile:
    """read_wpl_file on a file, reading at most the size limit of it."""
    data = read_user_file(path, UserFile("waypoint file", MAX_WPL_BYTES, PlanError, READ_HINT, SIZE_HINT))
    from missions.formats.outputs import check_output   # not at the top: outputs imports this module
    check_output(path)       # a compiled NAME.waypoints: only the last complete compile's
    return read_wpl_file(data, str(path), home_row=home_row)
