"""Convert a mission file between the forms ground stations save (pure but for reading and writing the files).

    result = convert_file("survey.plan", "survey.waypoints", only="mission")

Read: a QGroundControl `.plan` (mission, fence, rally) or a WPL 110 file (`.waypoints`, `.wpl`, `.txt`: a
mission, or a fence or rally list as Mission Planner saves one), by the same readers upload uses, with their
repair notes. Written, atomically and only when everything fits:
  * `.plan`: everything (the input's firmwareType, or `firmware`);
  * `.waypoints` / `.wpl` / `.txt`: one list, as the format holds one: the mission with its home row 0, or
    the fence or rally rows without one. A file with more than one list is refused unless `only` names the
    one to write (nothing is dropped silently);
  * `.geojson` / `.kml`: home, the mission's path and waypoints, fence polygons and circles (a circle as a
    72-sided polygon, its radius in the properties), the fence return point and rally points.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

from missions.emit.items import (FRAME_GLOBAL, MISSION_TYPE_FENCE, MISSION_TYPE_MISSION, MISSION_TYPE_RALLY,
                                 MissionItem, mavlink)
from missions.errors import PlanError
from missions.formats import kml, planfile, wpl
from missions.formats.geojson import dumps_collection
from missions.formats.itemcheck import GLOBAL_FRAMES, command_label, takes_of
from missions.formats.readnote import ReadNote

PLAN_SUFFIXES = (".plan",)
WPL_SUFFIXES = (".waypoints", ".wpl", ".txt")
MAP_SUFFIXES = (".geojson", ".kml")
LISTS = {"mission": MISSION_TYPE_MISSION, "fence": MISSION_TYPE_FENCE, "rally": MISSION_TYPE_RALLY}
CIRCLE_SIDES = 72
EARTH_RADIUS_M = 6371008.8     # mean radius: a fence circle's outline, drawn, not flown
_FENCE_CIRCLES = {mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION: True, mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION: False}
_FENCE_POLYGONS = {mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION: True,
                   mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION: False}
Home = tuple[float, float, float]


class MissionFile(NamedTuple):
    """Everything a .plan or WPL file holds, whichever it was."""

    items: list[MissionItem]
    fence: list[MissionItem]
    rally: list[MissionItem]
    home: Home | None
    firmware: int | None       # MAV_AUTOPILOT the file names (None: WPL, which names none)
    vehicle: int | None        # MAV_TYPE likewise
    notes: tuple[ReadNote, ...]

    def lists(self) -> dict[str, list[MissionItem]]:
        return {"mission": self.items, "fence": self.fence, "rally": self.rally}


class Converted(NamedTuple):
    out: Path
    counts: dict[str, int]          # items written per list
    notes: tuple[ReadNote, ...]     # what the reader repaired or skipped


def read_mission_file(path: str | Path) -> MissionFile:
    """A .plan or WPL 110 file, read as upload reads it; PlanError for anything else."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in PLAN_SUFFIXES:
        r = planfile.load_plan_file(p)
        return MissionFile(r.items, r.fence, r.rally, r.home, r.firmware, r.vehicle, r.notes)
    if suffix in WPL_SUFFIXES:
        w = wpl.load_wpl_file(p)
        lists = {MISSION_TYPE_MISSION: [], MISSION_TYPE_FENCE: [], MISSION_TYPE_RALLY: []}
        lists[w.mission_type] = w.items
        return MissionFile(lists[MISSION_TYPE_MISSION], lists[MISSION_TYPE_FENCE], lists[MISSION_TYPE_RALLY], w.home,
                           None, None, w.notes)
    hint = ("compile a capture plan with `wiris mission compile`" if suffix in (".yaml", ".yml") else
            "convert a .plan (QGroundControl) or a .waypoints / .txt (QGC WPL 110) file")
    raise PlanError(f"cannot convert a {suffix or '(no suffix)'!r} file", where=str(p), hint=hint)


def convert_file(src: str | Path, out: str | Path, *, only: str | None = None,
                 firmware: str | None = None) -> Converted:
    """Write `src`'s mission, fence and rally to `out` in the form its suffix names (module docstring);
    PlanError, and nothing written, when `src` is unreadable or `out` cannot hold what it would have to."""
    src, out = Path(src), Path(out)
    out_suffix = out.suffix.lower()
    if out_suffix not in PLAN_SUFFIXES + WPL_SUFFIXES + MAP_SUFFIXES:
        raise PlanError(f"cannot write a {out_suffix or '(no suffix)'!r} file", where=str(out),
                        hint="write .plan, .waypoints (or .wpl/.txt), .geojson or .kml")
    if out.exists() and src.exists() and out.resolve() == src.resolve():
        raise PlanError("the output is the input file", where=str(out),
                        hint="write the converted file under another name")
    mf = read_mission_file(src)
    if only is not None:
        mf = _only(mf, only, src)
    if not any(mf.lists().values()):
        raise PlanError("the file holds no mission, fence or rally items", where=str(src),
                        hint="there is nothing to convert: check the file (an empty plan?)")
    text, counts = _text_for(mf, out, out_suffix, firmware)
    planfile.atomic_write(out, text)
    return Converted(out, counts, mf.notes)


def _only(mf: MissionFile, only: str, src: Path) -> MissionFile:
    chosen = mf.lists()[only]
    if not chosen:
        held = ", ".join(f"{len(v)} {k}" for k, v in mf.lists().items() if v) or "nothing"
        raise PlanError(f"the file holds no {only} items (it holds {held})", where=str(src),
                        hint="give --type for a list the file holds, or leave it out")
    return mf._replace(**{k if k != "mission" else "items": (v if k == only else [])
                          for k, v in mf.lists().items()})


def _text_for(mf: MissionFile, out: Path, suffix: str, firmware: str | None) -> tuple[str, dict[str, int]]:
    counts = {k: len(v) for k, v in mf.lists().items() if v}
    if suffix in PLAN_SUFFIXES:
        fw = firmware if firmware is not None else mf.firmware
        return planfile.write_plan(mf.items, mf.home, firmware=fw, vehicle=mf.vehicle, fence=mf.fence,
                                   rally=mf.rally), counts
    if suffix in WPL_SUFFIXES:
        return _wpl_text(mf, out, counts), counts
    fc = feature_collection(mf, out.stem)
    return (dumps_collection(fc) if suffix == ".geojson" else kml.render_kml(fc)), counts


def _wpl_text(mf: MissionFile, out: Path, counts: dict[str, int]) -> str:
    """One list as WPL 110: refused when the file holds more than one (the format holds one)."""
    if len(counts) > 1:
        held = ", ".join(f"{n} {k}" for k, n in counts.items())
        raise PlanError(f"a WPL 110 file holds one list, and this file holds {held} items", where=str(out),
                        hint="write a .plan to keep them together, or choose one with --type mission|fence|rally "
                             "(one file per list, as Mission Planner saves them)")
    if mf.items:
        return wpl.write_wpl(mf.items, mf.home)
    return wpl.fence_wpl_text(mf.fence or mf.rally)


# -- GeoJSON / KML ---------------------------------------------------------------------------------------------

def _lonlat(it: MissionItem) -> list[float]:
    return [round(it.y / 1e7, 7), round(it.x / 1e7, 7)]


def _has_place(it: MissionItem) -> bool:
    takes = takes_of(it)
    return takes is not None and takes.latlon and it.frame in GLOBAL_FRAMES and (it.x, it.y) != (0, 0)


def _altitude_amsl(it: MissionItem, home: Home | None) -> float | None:
    """The item's altitude above mean sea level where the file says it: absolute frames as written, frames
    relative to home when home is known; terrain frames not (the ground is not known here)."""
    if it.frame in (FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT):
        return it.z
    if it.frame in (mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT) and home:
        return home[2] + it.z
    return None


def _point(lonlat: list[float], alt: float | None) -> dict:
    return {"type": "Point", "coordinates": lonlat + ([round(alt, 2)] if alt is not None and math.isfinite(alt)
                                                      else [])}


def _circle(it: MissionItem) -> list[list[float]]:
    """A fence circle's outline: CIRCLE_SIDES vertices on the sphere at param1 metres from its centre."""
    lat, lon = math.radians(it.x / 1e7), math.radians(it.y / 1e7)
    d = it.param1 / EARTH_RADIUS_M
    ring = []
    for k in range(CIRCLE_SIDES + 1):
        b = 2 * math.pi * k / CIRCLE_SIDES
        lat2 = math.asin(math.sin(lat) * math.cos(d) + math.cos(lat) * math.sin(d) * math.cos(b))
        lon2 = lon + math.atan2(math.sin(b) * math.sin(d) * math.cos(lat), math.cos(d) - math.sin(lat) * math.sin(lat2))
        ring.append([round(math.degrees(lon2), 7), round(math.degrees(lat2), 7)])
    return ring


def _mission_features(mf: MissionFile) -> list[dict]:
    feats: list[dict] = []
    path: list[list[float]] = []
    if mf.home is not None:
        home = [round(mf.home[1], 7), round(mf.home[0], 7)]
        feats.append({"type": "Feature", "properties": {"kind": "home", "alt_amsl_m": mf.home[2]},
                      "geometry": _point(home, mf.home[2])})
        path.append(home + [mf.home[2]])
    for seq, it in enumerate(mf.items, start=1):
        if not _has_place(it):
            continue
        alt = _altitude_amsl(it, mf.home)
        feats.append({"type": "Feature",
                      "properties": {"kind": "waypoint", "seq": seq, "command": command_label(it.command),
                                     "frame": it.frame, "z": it.z},
                      "geometry": _point(_lonlat(it), alt)})
        path.append(_lonlat(it) + [alt if alt is not None else it.z])
    if len(path) > 1:
        feats.append({"type": "Feature", "properties": {"kind": "path"},
                      "geometry": {"type": "LineString", "coordinates": path}})
    return feats


def _fence_features(mf: MissionFile) -> list[dict]:
    feats: list[dict] = []
    i = 0
    fence = mf.fence
    while i < len(fence):
        it = fence[i]
        if it.command in _FENCE_POLYGONS:
            n = int(it.param1)
            ring = [_lonlat(v) for v in fence[i:i + n]]
            feats.append({"type": "Feature", "properties": {"kind": "fence", "inclusion": _FENCE_POLYGONS[it.command],
                                                            "vertices": n},
                          "geometry": {"type": "Polygon", "coordinates": [ring + ring[:1]]}})
            i += max(n, 1)
            continue
        if it.command in _FENCE_CIRCLES:
            feats.append({"type": "Feature", "properties": {"kind": "fence", "inclusion": _FENCE_CIRCLES[it.command],
                                                            "radius_m": it.param1, "center": _lonlat(it)},
                          "geometry": {"type": "Polygon", "coordinates": [_circle(it)]}})
        elif it.command == mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT:
            feats.append({"type": "Feature", "properties": {"kind": "fence_return", "z": it.z},
                          "geometry": _point(_lonlat(it), _altitude_amsl(it, mf.home))})
        i += 1
    for k, it in enumerate(mf.rally):
        feats.append({"type": "Feature", "properties": {"kind": "rally", "index": k, "z": it.z},
                      "geometry": _point(_lonlat(it), _altitude_amsl(it, mf.home))})
    return feats


def feature_collection(mf: MissionFile, name: str) -> dict:
    """The file's home, path, waypoints, fence and rally points as a GeoJSON FeatureCollection."""
    alts = "metres AMSL where the file says (absolute frames, or relative ones with a home)" if mf.home else \
        "metres as the file gives them (no home: relative altitudes cannot be placed above sea level)"
    return {"type": "FeatureCollection", "properties": {"plan": name, "generator": "wiris-tools", "altitudes": alts},
            "features": _mission_features(mf) + _fence_features(mf)}
