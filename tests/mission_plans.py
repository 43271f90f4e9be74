"""Small capture plans written on the fly for the output, preview and CLI tests (fast to compile)."""

from __future__ import annotations

from pathlib import Path

SMALL = """\
version: 1
name: {name}
vehicle: {{firmware: {firmware}, frame: copter, speed_mps: 4, max_mission_items: {limit}}}
home: {{lat: 50.1102, lon: 14.5031, alt_amsl_m: 262}}
payloads:
  thermal:
    camera: wiris-pro
    imager: thermal
    lens_mm: 13
    component_id: 100
    settings: {{range_mode: manual, range_min_c: 10, range_max_c: 60}}
mission:
  - takeoff: {{alt_m: 40}}
  - survey:
      area: [[50.1110, 14.5040], [50.1110, 14.5060], [50.1120, 14.5060], [50.1120, 14.5040]]
      payloads: [thermal]
      altitude_m: 40
      overlap: {{front: 75, side: 60}}
  - waypoint: {{lat: 50.1105, lon: 14.5035, alt_m: 30, hold_s: 3, capture: thermal}}
  - camera: {{payload: thermal, settings: {{range_mode: auto}}}}
  - rtl: {{}}
"""


def small_plan(directory: Path, name: str = "small", firmware: str = "ardupilot", limit: int = 700,
               camera_change: bool = True) -> Path:
    """A 1.6 ha survey, a hover capture, an in-flight camera change (unless camera_change=False), RTL."""
    path = Path(directory) / f"{name}.yaml"
    text = SMALL.format(name=name, firmware=firmware, limit=limit)
    if not camera_change:
        text = text.replace("  - camera: {payload: thermal, settings: {range_mode: auto}}\n", "")
    path.write_text(text, encoding="utf-8")
    return path


# Each: (file name, text, a fragment the error message must contain). All must fail to compile.
BAD_PLANS = {
    "self_intersecting": (SMALL.replace(
        "[[50.1110, 14.5040], [50.1110, 14.5060], [50.1120, 14.5060], [50.1120, 14.5040]]",
        "[[50.1110, 14.5040], [50.1120, 14.5060], [50.1110, 14.5060], [50.1120, 14.5040]]"), "intersects itself"),
    "unknown_payload": (SMALL.replace("payloads: [thermal]", "payloads: [thermall]"), "thermall"),
    "unknown_camera": (SMALL.replace("camera: wiris-pro", "camera: wiris-pr0"), "wiris-pr0"),
    "both_on_100": (SMALL.replace("""    settings: {{range_mode: manual, range_min_c: 10, range_max_c: 60}}
""", """    settings: {{range_mode: manual, range_min_c: 10, range_max_c: 60}}
  multispectral:
    camera: rededge-mx
    component_id: 100
"""), "100"),
    "bad_setting": (SMALL.replace("range_min_c: 10,", "range_min_c: hot,"), "range_min_c"),
    "yaml_syntax": (SMALL.replace("  - rtl: {{}}", "  - rtl: {{"), ""),
}


def bad_plan(directory: Path, key: str) -> tuple[Path, str]:
    text, fragment = BAD_PLANS[key]
    path = Path(directory) / f"{key}.yaml"
    path.write_text(text.format(name=key, firmware="ardupilot", limit=700), encoding="utf-8")
    return path, fragment
