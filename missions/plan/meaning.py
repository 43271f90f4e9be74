"""The plan's third pass: what a schema cannot say. Payload and camera names, settings against the camera
catalogue (`missions.plan.settings`), component ids, altitude_m xor gsd_cm, overlap, hover on a plane, area
files that exist.

    resolved = check_meaning(data, yaml_doc, base_dir)   # problems go to yaml_doc.problems

Every check reads the values defensively (the schema pass may have found them of the wrong type): a wrong
type is the schema's finding and is not reported twice. What the pass decides for the user (a component id
the plan leaves out) comes back in `Resolved`.
"""

from __future__ import annotations

from dataclasses import dataclass
import difflib
import math
from pathlib import Path
from typing import Any, Callable, Mapping, NamedTuple

from cdf.catalogue import catalogue
from cdf.errors import ECHO_CHARS, CdfError, clip, shown
from cdf.userfile import not_a_file
from missions.plan.schema import COMPONENT_IDS, MAX_AGL_M, MAX_ALTITUDE_M, MIN_ALTITUDE_M, ZONE_KINDS
from missions.plan.settings import check_settings
from missions.plan.thermal_keys import check_thermal_keys
from missions.plan.yaml_reader import PositionedYaml

# Above this the front overlap puts photos closer than a consumer GNSS receiver's position noise
# (missions.geometry.footprint.MAX_OVERLAP_PCT gives the same limit to the geometry).
MAX_OVERLAP_PCT = 95.0

# The RedEdge answers only on component 100 (MAV_COMP_ID_CAMERA) or 0 (rededge serial API); a WIRIS that
# the plan leaves unplaced is moved to the first free id of 101..105 instead (reported as a note).
REDEDGE_COMPONENT = 100


class Resolved(NamedTuple):
    """What the loader decided for the user."""

    component_ids: dict[str, int]    # by payload name, given or chosen
    notes: list[str]                 # each choice the user should know of (and mirror in the camera's menu)


def check_meaning(data: dict, doc: PositionedYaml, base_dir: Path) -> Resolved:
    """Checks beyond the schema, each problem reported to `doc`; area paths resolve against `base_dir`."""
    payloads = data.get("payloads") if isinstance(data.get("payloads"), dict) else {}
    cameras = _payload_cameras(payloads, doc)
    # settings, per payload; the state carries across in-flight changes for `when` checks
    states: dict[str, dict] = {}
    for name, cam in cameras.items():
        states[name] = {}
        check_settings(cam, payloads[name].get("settings"), ("payloads", name, "settings"), doc, states[name])
    resolved = _component_ids(payloads, cameras, doc)
    vehicle = data["vehicle"] if isinstance(data.get("vehicle"), dict) else {}
    _check_steps(data, _Written(doc, payloads, cameras, states, vehicle.get("frame"), base_dir,
                                altitude_ceiling(vehicle)))
    check_thermal_keys(data, doc)
    _check_terrain(data, doc, base_dir)
    return resolved


def _check_terrain(data: dict, doc: PositionedYaml, base_dir: Path) -> None:
    """Home's elevation comes from the plan or from the DEM; the DEM files exist (their contents are read by
    the compiler, missions.terrain.dem)."""
    terrain = data.get("terrain") if isinstance(data.get("terrain"), dict) else None
    home = data.get("home") if isinstance(data.get("home"), dict) else None
    if home is not None and "alt_amsl_m" not in home and terrain is None:
        doc.report(("home",), "home needs alt_amsl_m (no terrain.dem to take it from)",
                   "give home's elevation above mean sea level, e.g. alt_amsl_m: 312, or a DEM: terrain: {dem: FILE}")
    dem = terrain.get("dem") if terrain is not None else None
    files = [dem] if isinstance(dem, str) else dem if isinstance(dem, list) else []
    for j, src in enumerate(files):
        if isinstance(src, str) and src:
            p = Path(src) if Path(src).is_absolute() else base_dir / src
            found, why = _is_file(p)
            if not found:
                at = ("terrain", "dem") if isinstance(dem, str) else ("terrain", "dem", j)
                doc.report(at, f"DEM file {shown(src)} {why} (looked at {clip(str(p), 2 * ECHO_CHARS)})",
                           "paths in a plan are relative to the plan file; give a GeoTIFF (.tif) or SRTM .hgt")


# ------------------------------------------------------------------------------------------------ payloads

def _is_rededge(camera: Any) -> bool:
    return camera.protocol == "rededge-serial"


def _payload_cameras(payloads: Mapping[str, Any], doc: PositionedYaml) -> dict[str, Any]:
    """The catalogue camera of each payload that names one the catalogue has; its imager and component id
    checked against the camera."""
    cat = catalogue()
    cameras: dict[str, Any] = {}
    for name, p in payloads.items():
        if not isinstance(p, dict) or not isinstance(p.get("camera"), str):
            continue
        try:
            cam = cat.get(p["camera"])
        except CdfError as e:
            doc.report(("payloads", name, "camera"), f"payload {name}: {e.message}",
                       f"{e.hint} (cameras: {', '.join(cat.ids)})")
            continue
        cameras[name] = cam
        _check_camera_fit(name, p, cam, doc)
    return cameras


def _check_camera_fit(name: str, payload: dict, cam: Any, doc: PositionedYaml) -> None:
    """The payload's imager and component id are ones its camera has."""
    imager = payload.get("imager")
    if isinstance(imager, str) and cam.imager(imager) is None:
        doc.report(("payloads", name, "imager"), f"{cam.id} has no imager {shown(imager)}",
                   "imagers: " + ", ".join(i.id for i in cam.imagers))
    cid = payload.get("component_id")
    # an id outside 100..105 is the schema's finding (once, with its hint): only a camera id this camera
    # cannot take is reported here
    if isinstance(cid, int) and not isinstance(cid, bool) and cid in COMPONENT_IDS and cid not in cam.component_ids:
        doc.report(("payloads", name, "component_id"), f"{cam.model} cannot use component id {cid}",
                   f"allowed: {', '.join(map(str, cam.component_ids))}"
                   + (" (the RedEdge answers only on 100)" if _is_rededge(cam) else ""))


# ------------------------------------------------------------------------------------------- component ids

def _component_ids(payloads: Mapping[str, Any], cameras: Mapping[str, Any], doc: PositionedYaml) -> Resolved:
    """Each payload's component id: the ones the plan gives first, then the others filled in."""
    comp, taken = _given_components(payloads, cameras, doc)
    notes = _choose_components(cameras, doc, comp, taken)
    return Resolved(comp, notes)


def _given_components(payloads: Mapping[str, Any], cameras: Mapping[str, Any],
                      doc: PositionedYaml) -> tuple[dict[str, int], dict[int, str]]:
    """(component id by payload, first payload by component id) of the valid ids the plan gives; clashes
    reported."""
    comp: dict[str, int] = {}
    taken: dict[int, str] = {}
    for name in cameras:
        cid = payloads[name].get("component_id")
        if not (isinstance(cid, int) and not isinstance(cid, bool) and cid in COMPONENT_IDS):
            continue
        if cid in taken:
            _report_clash(name, taken[cid], cid, cameras, doc)
        else:
            taken[cid] = name
        comp[name] = cid
    return comp, taken


def _report_clash(name: str, other: str, cid: int, cameras: Mapping[str, Any], doc: PositionedYaml) -> None:
    red = [n for n in (name, other) if _is_rededge(cameras[n])]
    wiris = [n for n in (name, other) if not _is_rededge(cameras[n])]
    if red and wiris:
        msg = (f"payloads {other} and {name} are both on component {cid}: the RedEdge ({red[0]}) "
               f"is fixed at {REDEDGE_COMPONENT}")
        hint = f"set the WIRIS ({wiris[0]}) to a free id of 101..105 in its menu and here"
    else:
        msg = f"payloads {other} and {name} are both on component {cid}"
        hint = "each camera needs its own component id 100..105"
    doc.report(("payloads", name, "component_id"), msg, hint)


def _choose_components(cameras: Mapping[str, Any], doc: PositionedYaml, comp: dict[str, int],
                       taken: dict[int, str]) -> list[str]:
    """Add an id to `comp` (and `taken`) for each payload the plan leaves without one; the notes of choices."""
    notes: list[str] = []
    has_rededge = any(_is_rededge(c) for c in cameras.values())
    for name, cam in cameras.items():
        if name in comp:
            continue
        if _is_rededge(cam):
            cid = REDEDGE_COMPONENT
            if cid in taken and taken[cid] != name:
                doc.report(("payloads", taken[cid], "component_id"),
                           f"payload {taken[cid]} is on component {cid}, where the RedEdge ({name}) is fixed",
                           "move the WIRIS to a free id of 101..105 in its menu and here")
        else:
            free = _free_component(name, cam, taken, has_rededge, doc)
            if free is None:
                continue
            cid = free
            if has_rededge or cid != cam.default_component_id:
                notes.append(f"payload {name}: component_id not given, using {cid}"
                             + (" (100 is the RedEdge's)" if has_rededge else "")
                             + "; set the same id in the camera's menu")
        comp[name] = cid
        taken.setdefault(cid, name)
    return notes


def _free_component(name: str, cam: Any, taken: Mapping[int, str], has_rededge: bool,
                    doc: PositionedYaml) -> int | None:
    """The first id the camera can use that no payload has (never the RedEdge's beside one); None: none left."""
    free = [c for c in cam.component_ids if c not in taken]
    if has_rededge:
        free = [c for c in free if c != REDEDGE_COMPONENT]
    if not free:
        doc.report(("payloads", name), f"no free component id for {name}",
                   f"ids 100..105 are all taken; {cam.model} can use {', '.join(map(str, cam.component_ids))}")
        return None
    return free[0]


# --------------------------------------------------------------------------------------------------- steps

class Ceiling(NamedTuple):
    """The highest altitude above home a plan may fly: the common rule's, or the permit the plan states."""

    limit_m: float
    waiver: bool             # True: vehicle.max_altitude_m states a permit


def altitude_ceiling(vehicle: Mapping[str, Any]) -> Ceiling:
    """The ceiling of a plan's `vehicle` mapping as written (a wrong type is the schema's finding)."""
    given = vehicle.get("max_altitude_m")
    if given is None:
        return Ceiling(MAX_AGL_M, False)
    # a ceiling the schema refuses is its finding; judged by none, the altitudes get no second one
    return Ceiling(float(given), True) if _in_altitude_range(given) else Ceiling(MAX_ALTITUDE_M, True)


def _in_altitude_range(v: Any) -> bool:
    """A number the schema takes as an altitude (outside that range it reports the value itself)."""
    return _num(v) and MIN_ALTITUDE_M <= v <= MAX_ALTITUDE_M


def ceiling_problem(altitude_m: float, what: str, ceiling: Ceiling,
                    lower: str | None = None) -> tuple[str, str] | None:
    """(message, hint) when `altitude_m` is above the ceiling; None when it may be flown. `lower` says how to
    fly lower when the altitude follows from another value (a GSD); without it the altitude is as written."""
    if altitude_m <= ceiling.limit_m:
        return None
    alt = f"{altitude_m:.1f}".removesuffix(".0")
    fix = lower or f"altitudes are metres ({alt} ft would be {altitude_m * 0.3048:.0f} m)"
    if ceiling.waiver:
        return (f"{what}: {alt} m above home is above the plan's vehicle.max_altitude_m of {ceiling.limit_m:g} m",
                f"{fix}; or raise vehicle.max_altitude_m to what your permit allows")
    return (f"{what}: {alt} m above home is more than the {MAX_AGL_M:g} m most rules allow without a "
            f"permit (EU open category, FAA part 107; the ground is taken as flat at home's height)",
            f"{fix}; with a permit for more, state its ceiling: vehicle: {{max_altitude_m: {math.ceil(altitude_m)}}}")


def _check_ceiling(plan: _Written, at: tuple, value: Any) -> None:
    if _in_altitude_range(value):
        found = ceiling_problem(float(value), at[-1], plan.ceiling)
        if found is not None:
            plan.doc.report(at, *found)


@dataclass(frozen=True)
class _Written:
    """What the step checks look at: the plan as written and what the payload checks found."""

    doc: PositionedYaml
    payloads: Mapping[str, Any]      # as written, by name
    cameras: Mapping[str, Any]       # the catalogue camera of each payload that names a known one
    states: Mapping[str, dict]       # each payload's settings so far; camera steps update them in order
    frame: str | None                # vehicle.frame as written
    base_dir: Path                   # area paths are relative to it
    ceiling: Ceiling                 # the highest altitude above home the plan may fly


def _check_steps(data: dict, plan: _Written) -> None:
    mission = data.get("mission") if isinstance(data.get("mission"), list) else []
    for i, step in enumerate(mission):
        if not isinstance(step, dict) or len(step) != 1:
            continue
        kind, body = next(iter(step.items()))
        if not isinstance(body, dict):
            continue
        check = _STEP_CHECKS.get(kind)
        if check is not None:
            check(plan, ("mission", i, kind), body)


def _check_payload_ref(plan: _Written, ref: Any, path: tuple) -> None:
    if isinstance(ref, str) and ref not in plan.payloads:
        defined = sorted(plan.payloads)
        close = difflib.get_close_matches(ref, defined, n=1)
        plan.doc.report(path, f"unknown payload {shown(ref)}", (f"did you mean {close[0]!r}? " if close else "")
                        + f"payloads defined: {', '.join(defined) or 'none'}")


def _check_flown_area(plan: _Written, base: tuple, body: dict) -> None:
    """A survey or a corridor: its payloads, its height, overlap and trigger."""
    refs = body.get("payloads") if isinstance(body.get("payloads"), list) else []
    for j, ref in enumerate(refs):
        _check_payload_ref(plan, ref, base + ("payloads", j))
    _check_height(plan, base, body)
    _check_ceiling(plan, base + ("altitude_m",), body.get("altitude_m"))
    _check_overlap(plan, base, body)
    if body.get("trigger") == "hover" and plan.frame in ("plane", "vtol"):
        # a VTOL flies the mission in fixed-wing flight after NAV_VTOL_TAKEOFF (the compiler emits no
        # transition back to multicopter): ArduPlane drops NAV_WAYPOINT's hold time, PX4 flies through
        plan.doc.report(base + ("trigger",), "a plane cannot hover" if plan.frame == "plane" else
                        "a VTOL flies the mission in fixed-wing flight and cannot hover there",
                        "use trigger: distance")


def _check_height(plan: _Written, base: tuple, body: dict) -> None:
    kind = base[-1]
    has_alt, has_gsd = "altitude_m" in body, "gsd_cm" in body
    if has_alt and has_gsd:
        plan.doc.report(base + ("gsd_cm",), f"{kind} gives both altitude_m and gsd_cm",
                        "give exactly one: the other follows from the first payload's optics", key=True)
    elif not has_alt and not has_gsd:
        plan.doc.report(base, f"{kind} needs altitude_m or gsd_cm", "e.g. altitude_m: 40, or gsd_cm: 3.5")


def _num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _percent_of(fraction: float) -> str:
    """0.8 -> "80": a fraction as the percent it meant, without float noise (0.7 * 100 = 70.00000000000001)."""
    return f"{round(fraction * 100, 6):g}"


def _check_overlap(plan: _Written, base: tuple, body: dict) -> None:
    ov = body.get("overlap") if isinstance(body.get("overlap"), dict) else {}
    for side in ("front", "side"):
        v = ov.get(side)
        if _num(v) and 0 < v < 1:
            # 0.8 is a fraction written where percent belongs: 0.8 % overlap leaves gaps between every photo
            plan.doc.report(base + ("overlap", side), f"{side} overlap {v:g} is below 1: overlaps are percent, "
                            f"so this asks for {v:g} %", f"write percent: {_percent_of(v)}")
        elif _num(v) and MAX_OVERLAP_PCT < v < 100:
            plan.doc.report(base + ("overlap", side), f"{side} overlap {v} % is above the {MAX_OVERLAP_PCT:g} % "
                            "this planner accepts", "photos would be closer than GNSS position noise; "
                            "thermal mapping usually flies 90/80")


def _check_survey(plan: _Written, base: tuple, body: dict) -> None:
    _check_flown_area(plan, base, body)
    _check_area_files(plan, base, [(("area",), body.get("area"))])
    _check_zone_files(plan, base, body)


def _check_corridor(plan: _Written, base: tuple, body: dict) -> None:
    _check_flown_area(plan, base, body)
    _check_zone_files(plan, base, body)


def _check_zone_files(plan: _Written, base: tuple, body: dict) -> None:
    """The zone files of a survey or corridor (exclude, no_fly, no_photo) must be there."""
    # a wrong type (exclude: 5) is the schema's finding: only strings are looked up here
    _check_area_files(plan, base, [((kind, j), src) for kind in ZONE_KINDS
                                   if isinstance(body.get(kind), list) for j, src in enumerate(body[kind])])


def _check_area_files(plan: _Written, base: tuple, sources: list[tuple[tuple, Any]]) -> None:
    for at, src in sources:
        if isinstance(src, str) and src:
            p = Path(src) if Path(src).is_absolute() else plan.base_dir / src
            found, why = _is_file(p)
            if not found:
                plan.doc.report(base + at, f"area file {shown(src)} {why} (looked at {clip(str(p), 2 * ECHO_CHARS)})",
                                "paths in a plan are relative to the plan file")


def _is_file(p: Path) -> tuple[bool, str]:
    """Whether p is a regular file, and if not, why in a few words. Path.is_file() raises for a name the
    system refuses (longer than NAME_MAX, a NUL byte) instead of answering False."""
    try:
        other = not_a_file(p.stat().st_mode)
    except FileNotFoundError:
        return False, "not found"
    except (OSError, ValueError) as e:
        return False, f"cannot be looked up ({getattr(e, 'strerror', None) or e})"
    return (False, f"{other}, not a file") if other else (True, "")


def _check_waypoint(plan: _Written, base: tuple, body: dict) -> None:
    _check_payload_ref(plan, body.get("capture"), base + ("capture",))
    _check_ceiling(plan, base + ("alt_m",), body.get("alt_m"))


def _check_takeoff(plan: _Written, base: tuple, body: dict) -> None:
    _check_ceiling(plan, base + ("alt_m",), body.get("alt_m"))


def _check_land(plan: _Written, base: tuple, body: dict) -> None:
    if ("lat" in body) != ("lon" in body):
        plan.doc.report(base, "land needs both lat and lon, or neither (land where it is)",
                        "give the landing point as lat and lon, or remove both")


def _check_camera(plan: _Written, base: tuple, body: dict) -> None:
    ref = body.get("payload")
    _check_payload_ref(plan, ref, base + ("payload",))
    if isinstance(ref, str) and ref in plan.cameras:
        check_settings(plan.cameras[ref], body.get("settings"), base + ("settings",), plan.doc, plan.states[ref])


# The steps with meaning to check (rtl has none beyond the schema), by their name in the plan.
_STEP_CHECKS: dict[str, Callable[[_Written, tuple, dict], None]] = {
    "takeoff": _check_takeoff, "survey": _check_survey, "corridor": _check_corridor, "waypoint": _check_waypoint,
    "land": _check_land,
    "camera": _check_camera,
}
