"""The JSON Schema of capture-plan format version 1 (`wiris mission schema` prints it for editors).

The schema is the structural contract: names, types, units, ranges an editor can check while typing.
What a schema cannot say well (a setting against the camera catalogue, a payload name defined elsewhere in
the plan, altitude_m xor gsd_cm with a useful message) is checked by `missions.plan.meaning` after it, with the
same file:line:col locations.

Keys carry their unit (`altitude_m`, `speed_mps`, `gsd_cm`, `hold_s`, `angle_deg`); `x-hint` on a property
is our extension: the loader prints it with a range error (JSON Schema ignores unknown keywords).
"""

from __future__ import annotations

import copy
import functools
from typing import Any

FORMAT_VERSION = 1
SCHEMA_ID = "https://wiris-tools.invalid/schema/capture-plan-1.json"

# A copter below 2 m is in ground effect and its barometer noise (~1 m) is half the altitude; above 500 m
# no photogrammetry of a ground target makes sense and every civil drone rulebook is far exceeded (above
# MAX_AGL_M, the common regulatory ceiling, a plan needs vehicle.max_altitude_m: missions.plan.meaning).
MIN_ALTITUDE_M = 2.0
MAX_ALTITUDE_M = 500.0
# Most of the world's drone rules (EU 2019/947 open category, FAA part 107) cap flights at 120 m / 400 ft above
# ground without a permit: above it a plan is refused unless it states a permit's ceiling
# (vehicle.max_altitude_m); 400 there is most often feet written as metres.
MAX_AGL_M = 120.0
# Plausible survey speeds per airframe, m/s, as (lowest, highest). A copter slower than 0.5 m/s hardly moves
# (1e-9 m/s would be a flight of days); ArduCopter's WPNAV_SPEED and PX4's MPC_XY_VEL_MAX stop at 20 m/s
# and the fastest survey copters fly about 23. A plane, and a VTOL (which flies the mission in fixed-wing
# flight), below 8 m/s is under ArduPlane's default minimum airspeed (9 m/s), near stall for small survey
# planes; above 40 m/s is beyond their cruise.
SPEED_RANGE_MPS = {"copter": (0.5, 25.0), "plane": (8.0, 40.0), "vtol": (8.0, 40.0)}
COMPONENT_IDS = (100, 101, 102, 103, 104, 105)   # MAV_COMP_ID_CAMERA..CAMERA6 (common.xml)

_LAT, _LON = "latitude, WGS84 degrees", "longitude, WGS84 degrees"
_ALT_HINT = f"altitudes are metres above home, {MIN_ALTITUDE_M:g} to {MAX_ALTITUDE_M:g} m"


def _num(minimum: float | None = None, maximum: float | None = None, *, exclusive_min: float | None = None,
         exclusive_max: float | None = None, desc: str = "", hint: str = "", integer: bool = False) -> dict:
    s: dict[str, Any] = {"type": "integer" if integer else "number"}
    if minimum is not None:
        s["minimum"] = minimum
    if maximum is not None:
        s["maximum"] = maximum
    if exclusive_min is not None:
        s["exclusiveMinimum"] = exclusive_min
    if exclusive_max is not None:
        s["exclusiveMaximum"] = exclusive_max
    if desc:
        s["description"] = desc
    if hint:
        s["x-hint"] = hint
    return s


def _obj(properties: dict, required: tuple[str, ...] = (), desc: str = "", nullable: bool = False) -> dict:
    s: dict[str, Any] = {"type": ["object", "null"] if nullable else "object", "properties": properties,
                         "additionalProperties": False}
    if required:
        s["required"] = list(required)
    if desc:
        s["description"] = desc
    return s


LATLON = {"type": "array", "minItems": 2, "maxItems": 2, "description": "[lat, lon] in WGS84 degrees",
          "prefixItems": [_num(-90, 90, desc="latitude, degrees"), _num(-180, 180, desc="longitude, degrees")]}
POLYGON = {"type": "array", "minItems": 3, "items": LATLON,
           "description": "inline polygon: a list of [lat, lon] points (closing point optional)"}
AREA = {"description": "a KML or GeoJSON file (relative to the plan) or an inline list of [lat, lon] points",
        "anyOf": [{"type": "string", "minLength": 1}, POLYGON]}
PAYLOAD_LIST = {"type": "array", "minItems": 1, "uniqueItems": True, "items": {"type": "string"},
                "description": "payload names; the first one's footprint sets the lines, the others trigger alongside"}
ALTITUDE = _num(MIN_ALTITUDE_M, MAX_ALTITUDE_M, desc="flight altitude above home, metres (survey and corridor: above "
                  "the ground below with terrain.dem)", hint=_ALT_HINT)
GSD = _num(exclusive_min=0, maximum=1000, desc="ground sample distance of the first payload, cm/pixel",
           hint="GSD in centimetres per pixel, e.g. 3.5")
OVERLAP = _obj({
    "front": _num(0, exclusive_max=100, desc="along-track overlap, percent",
                  hint="overlap in percent below 100, e.g. front: 80"),
    "side": _num(0, exclusive_max=100, desc="across-track overlap, percent",
                 hint="overlap in percent below 100, e.g. side: 70"),
}, required=("front", "side"), desc="photo overlap in percent")
TRIGGER = {"enum": ["distance", "interval", "hover"], "default": "distance",
           "description": "distance: DO_SET_CAM_TRIGG_DIST; interval: timed (PX4 only); hover: stop and shoot"}
TURNAROUND = _num(0, 500, desc="straight run-in/out beyond each line end, metres (default 10 copter; a plane: 30 or "
               "its turn radius, on ArduPilot plus one L1 period of flight)")
# The kinds of zone, by their key in a survey or corridor step (missions.geometry.zones says what each keeps out).
ZONE_KINDS = ("no_fly", "no_photo", "exclude")
# Zones a survey or corridor keeps clear of (missions.geometry.zones): every zone of the plan holds for the whole
# flight, whichever step declares it.
ZONES = {
    "exclude": {"type": "array", "items": AREA,
                "description": "zones not to fly over or photograph (no_fly and no_photo at once)"},
    "no_fly": {"type": "array", "items": AREA,
               "description": "zones the path stays out of (lines, turnarounds and transits); photos may see them"},
    "no_photo": {"type": "array", "items": AREA,
                 "description": "zones no photo footprint touches (the camera is off near them); may be flown over"},
    "zone_margin_m": _num(0, 100, desc="position error the zones are kept clear by, metres (default 2)",
                          hint="metres of margin around every zone, e.g. zone_margin_m: 2"),
}

SETTINGS = {"type": "object", "minProperties": 1,
            "description": "camera settings, checked against the camera catalogue: each by its plan name or its "
                           "PARAM_EXT name (`wiris cdf models --settings MODEL` lists both), an option by its "
                           "name or label",
            "additionalProperties": {"type": ["string", "number", "array"], "items": {"type": "string"}}}

# Thermal-aware planning (missions.thermal): when the flight happens, the wind then, the blur budget, the
# modules' plane and the PV inspection profile with its overridable numbers (missions.thermal.pv.PvProfile).
WHEN = {"type": "string", "minLength": 1,
        "description": "when it is flown: ISO 8601 date and time with UTC offset, e.g. 2026-06-14T11:30+02:00",
        "x-hint": "e.g. when: 2026-06-14T11:30+02:00"}
WHEN_WIND = _num(0, 60, desc="wind expected during the flight, m/s (checked against the profile)",
                 hint="wind speed in m/s, e.g. 3")
BLUR_PX = _num(exclusive_min=0, maximum=10, desc="blur budget: ground pixels the image may smear during the "
               "thermal imager's time constant (default 1)", hint="pixels of motion blur, e.g. 1.0")
TARGET = _obj({
    "tilt_deg": _num(0, 90, desc="module tilt from horizontal, degrees", hint="0 (flat) to 90 (vertical)"),
    "azimuth_deg": _num(0, 360, desc="direction the modules face, degrees clockwise from north (180 = south)",
                        hint="0 to 360, 180 = facing south"),
}, required=("tilt_deg", "azimuth_deg"), desc="the surface inspected: PV module plane")
CAMERA_PITCH = _num(0, 90, desc="camera pitch off nadir towards the modules' face, degrees (0 = straight down)",
                    hint="0 (nadir) to 90 degrees")


def _profile_schema() -> dict:
    from missions.thermal.pv import PROFILE_NAMES, PvProfile, override_schema

    name = {"enum": list(PROFILE_NAMES), "description": "inspection profile: " + ", ".join(PROFILE_NAMES)}
    return {"description": "inspection profile: a name, or {name, level, and any of its numbers to override}",
            "anyOf": [name, _obj({"name": name, "level": {"enum": list(PvProfile.LEVELS),
                                                          "description": "module or cell level (default module)"},
                                  **override_schema()}, required=("name",))]}


STEPS: dict[str, dict] = {
    "takeoff": _obj({"alt_m": ALTITUDE}, required=("alt_m",), desc="take off to alt_m above home"),
    "survey": _obj({
        "area": AREA,
        **ZONES,
        "payloads": PAYLOAD_LIST,
        "altitude_m": ALTITUDE,
        "gsd_cm": GSD,
        "overlap": OVERLAP,
        "angle_deg": {"anyOf": [{"const": "auto"}, _num(-360, 360)], "default": "auto",
                      "description": "line direction, degrees clockwise from north (0 = north-south lines) or auto"},
        "trigger": TRIGGER,
        "turnaround_m": TURNAROUND,
        "refly_90": {"type": "boolean", "default": False, "description": "fly a second pass at +90 degrees"},
        "blur_px": BLUR_PX, "when": WHEN, "when_wind_mps": WHEN_WIND, "target": TARGET,
        "camera_pitch_deg": CAMERA_PITCH, "profile": _profile_schema(),
    }, required=("area", "payloads", "overlap"), desc="area survey (exactly one of altitude_m and gsd_cm)"),
    "corridor": _obj({
        "line": {"type": "array", "minItems": 2, "items": LATLON, "description": "centre line, [lat, lon] points"},
        "width_m": _num(1, 5000, desc="corridor width, metres",
                        hint="the width of the strip photographed along the line, 1 to 5000 m"),
        "payloads": PAYLOAD_LIST,
        "altitude_m": ALTITUDE,
        "gsd_cm": GSD,
        "overlap": OVERLAP,
        "trigger": TRIGGER,
        "turnaround_m": TURNAROUND,
        "blur_px": BLUR_PX, "when": WHEN, "when_wind_mps": WHEN_WIND,
        **ZONES,
    }, required=("line", "width_m", "payloads", "overlap"), desc="corridor along a line"),
    "waypoint": _obj({
        "lat": _num(-90, 90, desc=_LAT), "lon": _num(-180, 180, desc=_LON), "alt_m": ALTITUDE,
        "hold_s": _num(0, 3600, desc="hold time at the waypoint, seconds"),
        "capture": {"type": "string", "description": "payload that takes one photo here"},
    }, required=("lat", "lon", "alt_m"), desc="fly to a point, optionally hold and take one photo"),
    "camera": _obj({"payload": {"type": "string", "description": "name of the payload to change (from payloads)"},
                    "settings": SETTINGS},
                   required=("payload", "settings"), desc="change camera settings in flight"),
    "rtl": _obj({}, desc="return to launch", nullable=True),
    "land": _obj({"lat": _num(-90, 90, desc=_LAT), "lon": _num(-180, 180, desc=_LON)},
                 desc="land (here, or at lat/lon)", nullable=True),
}

PAYLOAD = _obj({
    "camera": {"type": "string", "description": "catalogue id (`wiris cdf models`)"},
    "imager": {"type": "string", "description": "which imager sets the footprint (default: the first with known optics)"},
    "lens_mm": _num(exclusive_min=0, maximum=1000, desc="focal length of the fitted lens, mm"),
    "component_id": {"type": "integer", "enum": list(COMPONENT_IDS),
                     "description": "MAVLink component id 100..105 (RedEdge is fixed at 100)",
                     "x-hint": "a camera's component id is 100 to 105 (MAV_COMP_ID_CAMERA..CAMERA6), the one set "
                               "in the camera's menu; a RedEdge answers only on 100"},
    "autopilot_serial": _num(1, 9, integer=True,
                             desc="the autopilot serial port the camera is wired to: ArduPilot SERIALn, PX4 "
                                  "TELEM n, 1..4 (default: TELEM2, then the next free port)"),
    "orientation": {"enum": ["landscape", "portrait"], "default": "landscape",
                    "description": "landscape: the long image side across the flight line"},
    "settings": SETTINGS,
}, required=("camera",), desc="a camera on board (camera ids: `wiris cdf models`)")


# Terrain following (missions.terrain): a DEM makes survey and corridor altitudes heights above the ground.
CLIMB_DESC = "climb rate the lines may ask for, m/s (default: 2.5 copter, 5 plane/VTOL)"
DESCENT_DESC = "descent rate the lines may ask for, m/s (default: 1.5 copter, 5 plane/VTOL)"
CLIMB_HINT = "a vertical speed in m/s, e.g. 2.5 (ArduCopter's WPNAV_SPEED_UP is 2.5, WPNAV_SPEED_DN 1.5)"
_DEM_FILE = {"type": "string", "minLength": 1, "description": "GeoTIFF (any CRS) or SRTM .hgt, relative to the plan"}
TERRAIN = _obj({
    "dem": {"anyOf": [_DEM_FILE, {"type": "array", "minItems": 1, "maxItems": 64, "items": _DEM_FILE}],
            "description": "DEM file or list of files (mosaicked, the first with a height wins)"},
    "frame": {"enum": ["amsl", "terrain"], "default": "amsl",
              "description": "amsl: line waypoints above mean sea level from the DEM; terrain: ArduPilot's "
                             "terrain frame (MAV_FRAME_GLOBAL_TERRAIN_ALT, TERRAIN_ENABLE=1)"},
    "tolerance_m": _num(exclusive_min=0, maximum=500, desc="how far above the target height above ground the "
                        "lines may fly (default 10 % of the altitude)", hint="metres, e.g. tolerance_m: 5"),
    "clearance_m": _num(0, 500, desc="least height above the DEM of every metre of the path (default 20)",
                        hint="metres, e.g. clearance_m: 20"),
    "vertical": {"enum": ["auto", "egm96", "ellipsoid"], "default": "auto",
                 "description": "what the DEM's heights are above: auto (as the file says; SRTM and files that do "
                                "not say: mean sea level), egm96, or ellipsoid (WGS84)"},
}, required=("dem",), desc="ground model: survey and corridor altitudes become heights above the ground")


_FRAME_NAMES = {"copter": "copter", "plane": "plane", "vtol": "VTOL"}
_SPEEDS_TEXT = ", ".join(f"{lo:g} to {hi:g} for a {_FRAME_NAMES[f]}" for f, (lo, hi) in SPEED_RANGE_MPS.items())


def _speed_ranges() -> list[dict]:
    """speed_mps's range for each frame, as JSON Schema if/then (editors check it while typing)."""
    return [{"if": {"properties": {"frame": {"const": frame}}, "required": ["frame"]},
             "then": {"properties": {
                 "speed_mps": {"anyOf": [{"const": "auto"}, _num(lo, hi, hint=f"a {_FRAME_NAMES[frame]} surveys at "
                                                                              f"{lo:g} to {hi:g} m/s")]},
                 "max_speed_mps": _num(lo, hi, hint=f"a {_FRAME_NAMES[frame]} flies {lo:g} to {hi:g} m/s")}}}
            for frame, (lo, hi) in SPEED_RANGE_MPS.items()]


def _build() -> dict:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "wiris-tools capture plan, format version 1",
        "type": "object",
        "additionalProperties": False,
        "required": ["version", "vehicle", "home", "payloads", "mission"],
        "properties": {
            "version": {"const": FORMAT_VERSION, "description": "capture-plan format version"},
            "name": {"type": "string", "pattern": "^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$",
                     "description": "output file names derive from it (default: the plan file's name)"},
            "when": WHEN,
            "when_wind_mps": WHEN_WIND,
            "vehicle": _obj({
                "firmware": {"enum": ["ardupilot", "px4"], "description": "autopilot firmware: ardupilot or px4"},
                "frame": {"enum": ["copter", "plane", "vtol"], "description": "airframe: copter, plane or vtol"},
                "speed_mps": {"anyOf": [{"const": "auto"}, _num()],
                              "description": "ground speed while surveying, m/s: " + _SPEEDS_TEXT + "; or auto: the "
                              "fastest at which every camera keeps its minimum capture interval and blur budget"},
                "max_speed_mps": _num(desc="the fastest the vehicle may fly, m/s (caps speed_mps: auto)"),
                "max_mission_items": _num(10, 65535, integer=True,
                                          desc="item limit of the vehicle (default per firmware)"),
                "max_altitude_m": _num(MIN_ALTITUDE_M, MAX_ALTITUDE_M,
                                       desc=f"the highest altitude above home your permit allows, metres; "
                                            f"without it no step may fly above {MAX_AGL_M:g} m",
                                       hint=f"a permit's ceiling above home, {MIN_ALTITUDE_M:g} to "
                                            f"{MAX_ALTITUDE_M:g} m"),
                "climb_mps": _num(exclusive_min=0, maximum=30, desc=CLIMB_DESC, hint=CLIMB_HINT),
                "descent_mps": _num(exclusive_min=0, maximum=30, desc=DESCENT_DESC, hint=CLIMB_HINT),
                "firmware_version": {"type": ["string", "number"], "pattern": r"^[0-9]+\.[0-9]+(\.[0-9]+)?$",
                                     "description": "firmware release, e.g. \"4.6\" (ArduPilot) or \"1.15\" (PX4): "
                                                    "NAME.params names parameters as that release does (default: "
                                                    "every name each supported release uses)"},
                "endurance_min": _num(1, 1440, desc="minutes in the air on one battery at survey speed: a longer "
                                      "flight is split into sorties (missions.sorties)"),
                "reserve_pct": _num(0, 90, desc="share of the endurance kept in reserve, % (default 20)"),
                "turn_radius_m": _num(1, 2000, desc="a plane's or VTOL's turn radius, m (default: from speed "
                                      "and max_bank_deg)"),
                "max_bank_deg": _num(5, 60, desc="a plane's or VTOL's bank angle in turns, degrees (default 30)"),
            }, required=("firmware", "frame", "speed_mps"), desc="the aircraft") | {"allOf": _speed_ranges()},
            "home": _obj({"lat": _num(-90, 90, desc=_LAT), "lon": _num(-180, 180, desc=_LON),
                          "alt_amsl_m": _num(-500, 9000, desc="home altitude above mean sea level")},
                         required=("lat", "lon"),
                         desc="the take-off point, alt_amsl_m its elevation (from terrain.dem when left out)"),
            "terrain": TERRAIN,
            "payloads": {"type": "object", "minProperties": 1,
                         "propertyNames": {"pattern": "^[A-Za-z_][A-Za-z0-9_-]{0,31}$"},
                         "additionalProperties": PAYLOAD,
                         "description": "the cameras on board, each under a name of yours, e.g. thermal: "
                                        "{camera: wiris-pro}"},
            "mission": {"type": "array", "minItems": 1,
                        "description": "the steps in flight order, one `- step: {...}` each: " + ", ".join(STEPS),
                        "items": {"type": "object", "minProperties": 1, "maxProperties": 1,
                                  "properties": STEPS, "additionalProperties": False,
                                  "description": "one step: " + ", ".join(STEPS)}},
            "fence": _obj({"margin_m": _num(5, 5000, desc="distance of the inclusion fence from everything the "
                                                            "mission flies, m")},
                          required=("margin_m",),
                          desc="an inclusion fence around the whole flight, in the .plan's geoFence (exclusion "
                               "zones go there whether or not this is given)"),
            "qgc": _obj({"corridor_scan": {"type": "boolean", "default": False,
                                           "description": "write corridors into the .plan as QGroundControl "
                                                          "CorridorScan items (MAVSDK 4.1's importer then refuses "
                                                          "the file)"}},
                        desc="how the .plan presents the mission to QGroundControl"),
        },
    }


@functools.lru_cache(maxsize=1)
def _schema() -> dict:
    return _build()


def plan_schema() -> dict:
    """The JSON Schema (draft 2020-12) of capture-plan format version 1, as a fresh dict."""
    return copy.deepcopy(_schema())
