"""The meaning pass for the thermal-planning keys (missions.thermal): `when` values that name a moment, a PV
profile that knows its modules' plane, overrides that make sense together. Problems go to the plan's document
with their file:line:col, like every other meaning check (missions.plan.meaning calls `check_thermal_keys`)."""

from __future__ import annotations

from typing import Any

from missions.plan.yaml_reader import PositionedYaml
from missions.thermal.pv import PvProfile
from missions.thermal.when import WhenError, parse_when

_TIMED_STEPS = ("survey", "corridor")


def check_thermal_keys(data: dict, doc: PositionedYaml) -> None:
    _check_when(data.get("when"), ("when",), doc)
    mission = data.get("mission") if isinstance(data.get("mission"), list) else []
    for i, step in enumerate(mission):
        if not isinstance(step, dict) or len(step) != 1:
            continue
        kind, body = next(iter(step.items()))
        if kind not in _TIMED_STEPS or not isinstance(body, dict):
            continue
        base = ("mission", i, kind)
        _check_when(body.get("when"), base + ("when",), doc)
        if kind == "survey":
            _check_profile(body, base, doc)


def _check_when(value: Any, path: tuple, doc: PositionedYaml) -> None:
    if not isinstance(value, str) or not value:
        return                      # absent, or the schema's finding
    try:
        parse_when(value)
    except WhenError as e:
        doc.report(path, str(e), e.hint)


def _check_profile(body: dict, base: tuple, doc: PositionedYaml) -> None:
    profile = body.get("profile")
    if profile is None:
        return
    name = profile if isinstance(profile, str) else profile.get("name") if isinstance(profile, dict) else None
    if name != "pv-inspection":
        return                      # the schema reports an unknown profile
    if not isinstance(body.get("target"), dict):
        doc.report(base + ("profile",), "the pv-inspection profile needs the modules' plane to judge the viewing "
                   "angle, the irradiance and glare", "add target: {tilt_deg: 25, azimuth_deg: 180} to this survey")
    if isinstance(profile, dict):
        _check_pairs(profile, base + ("profile",), doc)


def _check_pairs(profile: dict, path: tuple, doc: PositionedYaml) -> None:
    for low, high, what in (("solar_time_from_h", "solar_time_to_h", "solar-time window"),
                            ("emissivity_min", "emissivity_max", "emissivity range")):
        lo, hi = profile.get(low, getattr(PvProfile(), low)), profile.get(high, getattr(PvProfile(), high))
        if (low in profile or high in profile) and _number(lo) and _number(hi) and lo > hi:
            at = low if low in profile else high
            doc.report(path + (at,), f"profile {what}: {low} {lo:g} is above {high} {hi:g}",
                       f"give {low} below {high} (defaults {getattr(PvProfile(), low):g} and "
                       f"{getattr(PvProfile(), high):g})")
    for key in ("solar_time_from_h", "solar_time_to_h"):
        v = profile.get(key)
        if _number(v) and v > 24:
            doc.report(path + (key,), f"profile {key} {v:g} is not an hour of the day", "0 to 24, e.g. 10")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)
