"""The plan's last pass: validated plan values -> the frozen `Plan` (missions.plan.types).

    plan = build_plan(data, resolved, "survey.yaml", base_dir, locations)

Only called once the schema and meaning passes found nothing: every key read here is there and of its type,
so a KeyError or TypeError is a gap between the schema and this builder (parse_plan reports it as a bug).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Callable, Collection, Mapping

from cdf.catalogue import catalogue
from missions.plan.meaning import Resolved
from missions.plan.schema import ZONE_KINDS
from missions.plan.types import (CameraStep, CorridorStep, Home, LandStep, Payload, Plan, RtlStep, Step, SurveyStep,
                                 TakeoffStep, Target, Timing, Vehicle, WaypointStep)
from missions.thermal.blur import DEFAULT_BLUR_PX
from missions.thermal.pv import pv_profile
from missions.thermal.when import parse_when


def build_plan(data: dict, resolved: Resolved, path: str, base_dir: Path, locations: Mapping, *,
               skip_payloads: Collection[str] = (), skip_steps: Collection[int] = ()) -> Plan:
    """The plan; without the payloads and steps named to skip (ones with problems, for the later stages to
    check the rest). A kept step keeps its index in the mission list, so its locations stay right."""
    cat = catalogue()
    kept = {name: p for name, p in data["payloads"].items() if name not in skip_payloads}
    cameras = {name: cat.get(p["camera"]) for name, p in kept.items()}
    payloads = tuple(_payload(name, p, cameras[name], resolved.component_ids[name]) for name, p in kept.items())
    steps: list[Step] = []
    for i, step in enumerate(data["mission"]):
        if i in skip_steps:
            continue
        kind, body = next(iter(step.items()))
        build = _STEP_BUILDERS.get(kind)
        if build is not None:
            steps.append(build(i, body or {}, cameras))
    v, h = data["vehicle"], data["home"]
    return Plan(
        version=int(data["version"]), name=data.get("name") or _default_name(path),
        vehicle=Vehicle(v["firmware"], v["frame"], None if v["speed_mps"] == "auto" else float(v["speed_mps"]),
                        v.get("max_mission_items"), max_speed_mps=_float_or_none(v, "max_speed_mps"),
                        max_altitude_m=_float_or_none(v, "max_altitude_m"), firmware_version=_version_or_none(v)),
        home=Home(float(h["lat"]), float(h["lon"]), float(h["alt_amsl_m"])),
        payloads=payloads, mission=tuple(steps), path=path, base_dir=str(base_dir), notes=tuple(resolved.notes),
        timing=_timing(data), locations=locations, fence_margin_m=_fence_margin(data),
        corridor_scan=bool((data.get("qgc") or {}).get("corridor_scan", False)))


def _timing(body: Mapping[str, Any]) -> Timing:
    """`when` (checked by the meaning pass) and `when_wind_mps` of a plan or step."""
    when = body.get("when")
    return Timing(parse_when(when) if when else None, _float_or_none(body, "when_wind_mps"))


def _fence_margin(data: dict) -> float | None:
    fence = data.get("fence")
    return None if fence is None else float(fence["margin_m"])


def _default_name(path: str) -> str:
    """The plan file's name without .yaml, made file-name safe: outputs are named after it."""
    stem = Path(path).name
    for suffix in (".yaml", ".yml"):
        if stem.lower().endswith(suffix):
            stem = stem[: -len(suffix)]
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", stem).lstrip(".-_") or "plan"
    return stem[:64]


def _as_written(camera: Any, settings: Mapping[str, Any]) -> tuple[tuple[str, Any], ...]:
    """Each setting's value as written, by its plan name (the plan may write the PARAM_EXT name)."""
    return tuple((camera.setting_named(k).key, tuple(x) if isinstance(x, list) else x) for k, x in settings.items())


def _wire_values(camera: Any, settings: Mapping[str, Any]) -> tuple[tuple[str, float | int], ...]:
    """Each setting by its plan name (a plan may write the PARAM_EXT name, any case) with its wire value."""
    named = ((camera.setting_named(k), val) for k, val in settings.items())
    return tuple((s.key, s.check(val)) for s, val in named)


def _payload(name: str, p: dict, camera: Any, component_id: int) -> Payload:
    settings = p.get("settings") or {}
    return Payload(
        name=name, camera=camera.id, imager=p.get("imager"), lens_mm=_float_or_none(p, "lens_mm"),
        component_id=component_id, component_given="component_id" in p, autopilot_serial=p.get("autopilot_serial"),
        landscape=p.get("orientation", "landscape") == "landscape",
        settings=_as_written(camera, settings), values=_wire_values(camera, settings))


def _version_or_none(vehicle: Mapping[str, Any]) -> str | None:
    v = vehicle.get("firmware_version")
    return None if v is None else str(v)


def _float_or_none(body: Mapping[str, Any], key: str) -> float | None:
    return float(body[key]) if key in body else None


def _pairs(points: Any) -> tuple[tuple[float, float], ...]:
    return tuple((float(p[0]), float(p[1])) for p in points)


def _area_value(v: Any) -> Any:
    return v if isinstance(v, str) else _pairs(v)


def _takeoff(i: int, b: dict, cameras: Mapping[str, Any]) -> TakeoffStep:
    return TakeoffStep(i, float(b["alt_m"]))


def _survey(i: int, b: dict, cameras: Mapping[str, Any]) -> SurveyStep:
    ov = b["overlap"]
    angle = b.get("angle_deg", "auto")
    return SurveyStep(
        i, _area_value(b["area"]), tuple(b["payloads"]), float(ov["front"]), float(ov["side"]),
        altitude_m=_float_or_none(b, "altitude_m"), gsd_cm=_float_or_none(b, "gsd_cm"),
        angle_deg=angle if angle == "auto" else float(angle),
        trigger=b.get("trigger", "distance"), turnaround_m=_float_or_none(b, "turnaround_m"),
        refly_90=bool(b.get("refly_90", False)), blur_px=float(b.get("blur_px", DEFAULT_BLUR_PX)), timing=_timing(b),
        target=Target(float(b["target"]["tilt_deg"]), float(b["target"]["azimuth_deg"])) if "target" in b else None,
        camera_pitch_deg=float(b.get("camera_pitch_deg", 0.0)),
        profile=pv_profile(b["profile"]) if "profile" in b else None, **_zone_fields(b))


def _zone_fields(b: dict) -> dict[str, Any]:
    """A survey's or corridor's zones (missions.geometry.zones) as the step's fields."""
    out: dict[str, Any] = {k: tuple(_area_value(x) for x in b.get(k, ())) for k in ZONE_KINDS}
    out["zone_margin_m"] = _float_or_none(b, "zone_margin_m")
    return out


def _corridor(i: int, b: dict, cameras: Mapping[str, Any]) -> CorridorStep:
    ov = b["overlap"]
    return CorridorStep(
        i, _pairs(b["line"]), float(b["width_m"]), tuple(b["payloads"]), float(ov["front"]), float(ov["side"]),
        altitude_m=_float_or_none(b, "altitude_m"), gsd_cm=_float_or_none(b, "gsd_cm"),
        trigger=b.get("trigger", "distance"), turnaround_m=_float_or_none(b, "turnaround_m"),
        blur_px=float(b.get("blur_px", DEFAULT_BLUR_PX)), timing=_timing(b), **_zone_fields(b))


def _waypoint(i: int, b: dict, cameras: Mapping[str, Any]) -> WaypointStep:
    return WaypointStep(i, float(b["lat"]), float(b["lon"]), float(b["alt_m"]), float(b.get("hold_s", 0.0)),
                        b.get("capture"))


def _camera(i: int, b: dict, cameras: Mapping[str, Any]) -> CameraStep:
    camera = cameras[b["payload"]]
    return CameraStep(i, b["payload"], _as_written(camera, b["settings"]), _wire_values(camera, b["settings"]))


def _rtl(i: int, b: dict, cameras: Mapping[str, Any]) -> RtlStep:
    return RtlStep(i)


def _land(i: int, b: dict, cameras: Mapping[str, Any]) -> LandStep:
    return LandStep(i, b.get("lat"), b.get("lon"))


# Each mission step's builder by its name in the plan: (index in the mission, its body, cameras by payload).
_STEP_BUILDERS: dict[str, Callable[[int, dict, Mapping[str, Any]], Step]] = {
    "takeoff": _takeoff, "survey": _survey, "corridor": _corridor, "waypoint": _waypoint, "camera": _camera,
    "rtl": _rtl, "land": _land,
}
