"""Capture plans for the SITL tests: small, fast to fly at the SITL's home (50.08, 14.42), each a different
kind of mission (survey, corridor, waypoint captures with hover, two payloads, an in-flight camera change,
a plan split into parts)."""

from __future__ import annotations

from pathlib import Path

HOME = (50.08, 14.42, 262.0)

HEAD = """\
version: 1
name: {name}
vehicle: {{firmware: {firmware}, frame: {frame}, speed_mps: {speed}{extra_vehicle}}}
home: {{lat: 50.08, lon: 14.42, alt_amsl_m: 262}}
payloads:
  thermal:
    camera: wiris-pro
    imager: thermal
    lens_mm: 13
    component_id: {component}{serial}
    settings: {{range_mode: manual, range_min_c: 10, range_max_c: 60}}
"""

SECOND = """\
  wide:
    camera: wiris-pro
    imager: thermal
    lens_mm: 9
    component_id: 101
"""

# a 100 m x 80 m field 100 m north-east of home
FIELD = "[[50.0810, 14.4210], [50.0810, 14.4224], [50.0817, 14.4224], [50.0817, 14.4210]]"

WAYPOINT_START = (50.0805, 14.4205)   # the first waypoint of the waypoint missions, south-west of the field


def _takeoff(alt_m: int) -> str:
    return f"  - takeoff: {{alt_m: {alt_m}}}\n"


def _survey(*, front: int, trigger: str, payloads: str = "thermal", note: str = "") -> str:
    """A survey of FIELD at 40 m with side overlap 60 %; `note` a YAML comment after the trigger."""
    return ("  - survey:\n"
            f"      area: {FIELD}\n"
            f"      payloads: [{payloads}]\n"
            "      altitude_m: 40\n"
            f"      overlap: {{front: {front}, side: 60}}\n"
            f"      trigger: {trigger}{note}\n")


def _waypoint(lat: float, lon: float, alt_m: int, *, hold_s: int | None = None, capture: str = "thermal") -> str:
    hold = f", hold_s: {hold_s}" if hold_s is not None else ""
    return f"  - waypoint: {{lat: {lat}, lon: {lon}, alt_m: {alt_m}{hold}, capture: {capture}}}\n"


CORRIDOR = """\
  - corridor:
      line: [[50.0805, 14.4205], [50.0815, 14.4225], [50.0820, 14.4245]]
      width_m: 40
      payloads: [thermal]
      altitude_m: 40
      overlap: {front: 70, side: 50}
      trigger: distance
"""

RTL = "  - rtl: {}\n"

# kinds only PX4 flies: ArduPilot's missions take no DO_SET_CAM_TRIGG_INTERVAL (the compiler refuses them)
PX4_ONLY = frozenset({"interval"})

# each kind's mission steps
STEPS = {
    "survey": _takeoff(40) + _survey(front=75, trigger="distance") + RTL,
    "interval": _takeoff(40) + _survey(front=75, trigger="interval") + RTL,
    "corridor": _takeoff(40) + CORRIDOR + "  - land: {}\n",
    "waypoints": (_takeoff(30) + _waypoint(*WAYPOINT_START, 30, hold_s=3) + _waypoint(50.0808, 14.4212, 35)
                  + _waypoint(50.0803, 14.4215, 30, hold_s=2) + RTL),
    "hover": _takeoff(40) + _survey(front=70, trigger="hover") + RTL,
    "camera_change": (_takeoff(40) + _survey(front=75, trigger="distance")
                      + "  - camera: {payload: thermal, settings: {range_mode: auto}}\n"
                      + _waypoint(*WAYPOINT_START, 30, hold_s=2) + RTL),
    "two_payloads": (_takeoff(40)
                     + _survey(front=70, trigger="hover", payloads="thermal, wide",
                               note="          # ArduPilot distance-triggers its primary camera only")
                     + _waypoint(*WAYPOINT_START, 30, hold_s=2, capture="wide") + RTL),
}


def plan_text(kind: str, *, name: str | None = None, frame: str = "copter", speed: float = 5,
              component: int = 100, autopilot_serial: int | None = None, limit: int | None = None,
              firmware: str = "ardupilot") -> str:
    extra = f", max_mission_items: {limit}" if limit else ""
    serial = f"\n    autopilot_serial: {autopilot_serial}" if autopilot_serial is not None else ""
    text = HEAD.format(name=name or kind.replace("_", "-"), firmware=firmware, frame=frame, speed=speed,
                       extra_vehicle=extra,
                       component=component, serial=serial)
    if kind == "two_payloads":
        text += SECOND
    return text + "mission:\n" + STEPS[kind]


def write_plan(directory: Path, kind: str, **kw) -> Path:
    path = Path(directory) / f"{kw.get('name') or kind.replace('_', '-')}.yaml"
    path.write_text(plan_text(kind, **kw), encoding="utf-8")
    return path
