"""The compiled surveys and corridors as QGroundControl pattern items (ComplexItem) in a .plan (pure).

    items_json = mission_items_json(compiled.items, compiled.patterns, compiled.payloads, corridor_scan=False)

Each survey becomes a ComplexItem `complexItemType: "survey"` (version 5, what QGC's SurveyComplexItem saves
and the only one MAVSDK's import_qgroundcontrol_mission reads), each corridor a `CorridorScan` (version 2) when
asked for (MAVSDK 4.1 refuses a whole .plan that holds one: its importer knows "survey" only). The items before,
between and after them (take-off, speed changes, camera set-up, Lua bridge calls, landing) stay SimpleItems.

What is written is what QGC's load code reads (SurveyComplexItem::_loadV4V5, TransectStyleComplexItem::_load,
CameraCalc::load, CorridorScanComplexItem::_loadWorker), with every key those mark required:
  * the pattern: polygon (survey) or polyline and CorridorWidth (corridor), angle, entryLocation / EntryPoint,
    flyAlternateTransects, splitConcavePolygons;
  * TransectStyleComplexItem version 2: TurnAroundDistance, CameraTriggerInTurnAround (false: the compiler turns
    the camera off at each line's exit), HoverAndCapture, Refly90Degrees, CameraShots, VisualTransectPoints
    (the waypoints in flight order) and Items: the compiled items of the pattern, flattened, exactly as emitted;
  * CameraCalc version 2 from the payload's optics as a "Custom Camera": SensorWidth/Height (mm), ImageWidth/
    Height (px), FocalLength (mm), Landscape, ImageDensity (GSD cm/px), overlaps (%), DistanceToSurface with
    DistanceMode 1 (relative to home), and AdjustedFootprintSide / AdjustedFootprintFrontal: the compiled line
    spacing and trigger distance (QGC loads them with its recalculation switched off).

QGC loads the pattern with its recalculation off and then appends the stored Items as they are
(TransectStyleComplexItem::appendMissionItems uses _loadedMissionItems while it has them). It throws them away and
builds its own lines from the polygon, angle and camera numbers as soon as it rebuilds the pattern: on any edit of
the pattern, and when the flight speed in force at the pattern is not the 5 m/s it starts each loaded pattern with
(TransectStyleComplexItem::setMissionFlightStatus rebuilds on a speed change). Its own lines have no holes for
exclusion zones, other turnarounds and, for hover capture, other photo points.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Iterable, Sequence

from missions.compiled import PayloadInfo, TransectPattern
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem, mavlink
from missions.formats.planfile import ALT_MODE_RELATIVE   # the compiler flies altitudes above home
from missions.geometry.geo import great_circle_m

SURVEY_VERSION = 5              # SurveyComplexItem::_saveCommon; MAVSDK's importer reads exactly this one
CORRIDOR_VERSION = 2            # CorridorScanComplexItem::_saveCommon
TRANSECT_VERSION = 2            # TransectStyleComplexItem::_save
CAMERA_CALC_VERSION = 2         # CameraCalc::save
CUSTOM_CAMERA = "Custom Camera"  # CameraCalc::canonicalCustomCameraName: camera numbers stored in the file

# What a pattern's stored Items may be: waypoints and the camera commands the emitter puts on a line.
_TRANSECT_COMMANDS = frozenset({mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
                                mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, mavlink.MAV_CMD_DO_TRIGGER_CONTROL,
                                mavlink.MAV_CMD_IMAGE_START_CAPTURE})


_CAMERA_COMMANDS = _TRANSECT_COMMANDS - {mavlink.MAV_CMD_NAV_WAYPOINT}


def transect_start(items: Sequence[MissionItem], first: int, end: int) -> int:
    """The first item of a step's [first, end) that belongs to its lines: its first waypoint (a speed change the
    step emitted before it stays a SimpleItem)."""
    for i in range(first, end):
        if items[i].command == mavlink.MAV_CMD_NAV_WAYPOINT:
            return i
    return end


SimpleItemWriter = Callable[[MissionItem, int], dict]


def mission_items_json(items: Sequence[MissionItem], patterns: Iterable[TransectPattern],
                       payloads: Iterable[PayloadInfo], simple_item: SimpleItemWriter, *,
                       corridor_scan: bool = False, spacing: Callable[[float], float] = lambda d: d) -> list[dict]:
    """The .plan's mission.items for `items`: SimpleItems, and one ComplexItem per pattern (a corridor only with
    `corridor_scan`). `simple_item(item, jump_id)` writes one SimpleItem (planfile's); doJumpId counts every
    flattened item from 1, as QGC numbers them. `spacing(d)` is the spacing the firmware's distance trigger flies
    for a commanded d (CameraShots counts what it fires)."""
    optics = {p.name: p for p in payloads}
    chosen = sorted((p for p in patterns if _writable(p, items, corridor_scan)), key=lambda p: p.items[0])
    out: list[dict] = []
    i = 0
    for pat in chosen:
        start, end = pat.items
        out.extend(simple_item(items[k], k + 1) for k in range(i, start))
        inner = [_inner_item(simple_item(items[k], k + 1)) for k in range(start, end)]
        out.append(_complex_item(pat, items[start:end], inner, optics.get(pat.payload), spacing))
        i = end
    out.extend(simple_item(items[k], k + 1) for k in range(i, len(items)))
    return out


def _writable(p: TransectPattern, items: Sequence[MissionItem], corridor_scan: bool) -> bool:
    start, end = p.items
    if p.kind == "corridor" and not corridor_scan:
        return False
    if not (0 <= start < end <= len(items) and all(it.command in _TRANSECT_COMMANDS for it in items[start:end])):
        return False
    # Lines that follow a DEM (AMSL or terrain frame) stay SimpleItems: QGC's survey keeps one altitude above
    # home for the whole pattern and would rebuild them flat the first time it regenerates the pattern.
    return all(it.frame in (FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION) for it in items[start:end])


def _inner_item(simple: dict) -> dict:
    """A stored pattern item as MissionItem::save writes it: no SimpleMissionItem altitude keys."""
    return {k: v for k, v in simple.items() if k not in ("AMSLAltAboveTerrain", "Altitude", "AltitudeMode")}


def _complex_item(p: TransectPattern, items: Sequence[MissionItem], inner: list[dict],
                  optics: PayloadInfo | None, spacing: Callable[[float], float]) -> dict[str, Any]:
    transect = {
        "CameraCalc": camera_calc(p, optics, any(it.command in _CAMERA_COMMANDS for it in items)),
        "CameraShots": camera_shots(items, spacing) if p.trigger_distance_m > 0 else 0,
        "CameraTriggerInTurnAround": False,
        "HoverAndCapture": p.hover,
        "Items": inner,
        "Refly90Degrees": p.refly_90,
        "TurnAroundDistance": _num(p.turnaround_m),
        "VisualTransectPoints": [[it.lat, it.lon] for it in items if it.command == mavlink.MAV_CMD_NAV_WAYPOINT],
        "version": TRANSECT_VERSION,
    }
    if p.kind == "corridor":
        return {"CorridorWidth": _num(p.width_m), "EntryPoint": 0, "TransectStyleComplexItem": transect,
                "complexItemType": "CorridorScan", "polyline": [list(pt) for pt in p.line], "type": "ComplexItem",
                "version": CORRIDOR_VERSION}
    return {"TransectStyleComplexItem": transect, "angle": _num(round(p.angle_deg % 360.0, 6)),
            "complexItemType": "survey", "entryLocation": 0, "flyAlternateTransects": False,
            "polygon": [list(pt) for pt in p.polygon], "splitConcavePolygons": False, "type": "ComplexItem",
            "version": SURVEY_VERSION}


def camera_calc(p: TransectPattern, optics: PayloadInfo | None, triggered: bool = True) -> dict[str, Any]:
    """CameraCalc v2 from the lead payload's optics. The footprints QGC would compute from them are the
    compiled ones, except that the compiler may have narrowed the spacing to fit a whole number of lines.
    `triggered` False (lines only RedEdges fly: they capture themselves) stores no trigger distance, so lines
    QGC rebuilds carry no camera commands either (TransectStyleComplexItem::triggerCamera)."""
    calc: dict[str, Any] = {
        "AdjustedFootprintFrontal": _num(p.trigger_distance_m if triggered else 0.0),
        "AdjustedFootprintSide": _num(p.spacing_m),
        "CameraName": CUSTOM_CAMERA, "DistanceMode": ALT_MODE_RELATIVE, "DistanceToSurface": _num(p.altitude_m),
        "version": CAMERA_CALC_VERSION}
    if optics is None:         # a payload without known optics cannot lead a pattern; kept whole regardless
        calc["CameraName"] = "Manual (no camera specs)"
        return calc
    w_mm, h_mm = optics.sensor_mm
    w_px, h_px = optics.resolution_px
    calc.update({"FixedOrientation": False, "FocalLength": _num(optics.focal_mm), "FrontalOverlap": _num(p.front_pct),
                 "ImageDensity": _num(round(optics.gsd_cm(p.altitude_m), 4)), "ImageHeight": int(h_px),
                 "ImageWidth": int(w_px), "Landscape": bool(optics.landscape),
                 "MinTriggerInterval": _num(optics.min_interval_s or 0.0), "SensorHeight": _num(h_mm),
                 "SensorWidth": _num(w_mm), "SideOverlap": _num(p.side_pct), "ValueSetIsDistance": True})
    return calc


def camera_shots(items: Sequence[MissionItem], spacing: Callable[[float], float] = lambda d: d) -> int:
    """The photos the pattern's items take: one per IMAGE_START_CAPTURE, and along each distance-triggered stretch
    one at its start (DO_SET_CAM_TRIGG_DIST param3 = 1 shoots at once) and one per `spacing(param1)` flown."""
    shots = 0
    step = 0.0                      # the spacing of the trigger now on; 0: off
    flown = 0.0
    last: MissionItem | None = None
    for it in items:
        if it.command == mavlink.MAV_CMD_IMAGE_START_CAPTURE:
            shots += 1
        elif it.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
            if step > 0:
                shots += int(flown // step)
            step, flown = (spacing(it.param1) if it.param1 > 0 else 0.0), 0.0
            shots += 1 if step > 0 and it.param3 == 1 else 0
        elif it.frame != FRAME_MISSION:
            if step > 0 and last is not None:
                flown += great_circle_m(last.lat, last.lon, it.lat, it.lon)
            last = it
    if step > 0:
        shots += int(flown // step)
    return shots


def _num(v: float) -> float | int:
    v = float(v)
    return int(v) if v.is_integer() and abs(v) < 2**53 else v


__all__ = ["mission_items_json", "transect_start", "camera_calc", "camera_shots"]
