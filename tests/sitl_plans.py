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

STEPS = {
    "survey": """\
  - takeoff: {{alt_m: 40}}
  - survey:
      area: {field}
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 75, side: 60}}
      trigger: distance
  - rtl: {{}}
""",
    "interval": """\
  - takeoff: {{alt_m: 40}}
  - survey:
      area: {field}
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 75, side: 60}}
      trigger: interval
  - rtl: {{}}
""",
    "corridor": """\
  - takeoff: {{alt_m: 40}}
  - corridor:
      line: [[50.0805, 14.4205], [50.0815, 14.4225], [50.0820, 14.4245]]
      width_m: 40
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 70, side: 50}}
      trigger: distance
  - land: {{}}
""",
    "waypoints": """\
  - takeoff: {{alt_m: 30}}
  - waypoint: {{lat: 50.0805, lon: 14.4205, alt_m: 30, hold_s: 3, capture: thermal}}
  - waypoint: {{lat: 50.0808, lon: 14.4212, alt_m: 35, capture: thermal}}
  - waypoint: {{lat: 50.0803, lon: 14.4215, alt_m: 30, hold_s: 2, capture: thermal}}
  - rtl: {{}}
""",
    "hover": """\
  - takeoff: {{alt_m: 40}}
  - survey:
      area: {field}
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 70, side: 60}}
      trigger: hover
  - rtl: {{}}
""",
    "camera_change": """\
  - takeoff: {{alt_m: 40}}
  - survey:
      area: {field}
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 75, side: 60}}
      trigger: distance
  - camera: {{payload: thermal, settings: {{range_mode: auto}}}}
  - waypoint: {{lat: 50.0805, lon: 14.4205, alt_m: 30, hold_s: 2, capture: thermal}}
  - rtl: {{}}
""",
    "two_payloads": """\
  - takeoff: {{alt_m: 40}}
  - survey:
      area: {field}
      payloads: [thermal, wide]
      altitude_m: 40
      overlap: {{front: 70, side: 60}}
      trigger: hover          # ArduPilot distance-triggers its primary camera only
  - waypoint: {{lat: 50.0805, lon: 14.4205, alt_m: 30, hold_s: 2, capture: wide}}
  - rtl: {{}}
""",
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
    return text + "mission:\n" + STEPS[kind].format(field=FIELD)


def write_plan(directory: Path, kind: str, **kw) -> Path:
    path = Path(directory) / f"{kw.get('name') or kind.replace('_', '-')}.yaml"
    path.write_text(plan_text(kind, **kw), encoding="utf-8")
    return path
