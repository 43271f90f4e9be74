"""The survey speed: what limits it (each camera's minimum capture interval, each thermal imager's blur budget,
the vehicle's maximum), the speed `vehicle.speed_mps: auto` chooses, and the check of an explicit speed.

    limits = line_limits(step_label, where, lead_trigger_m, payloads_in_step, altitude_m, blur_px, moving=True)
    chosen = choose_speed(limits, cap)            # Chosen(speed_mps, limit): the tightest limit, floored to 0.1
    check_sharp(limits, 6.0, where)               # PlanError naming the fastest sharp speed

Speeds are floored to 0.1 m/s, the precision a pilot sets them with, so the chosen speed always keeps every limit.
"""

from __future__ import annotations

import math
from typing import Iterable, NamedTuple, Sequence

from missions.compiled import PayloadInfo
from missions.errors import PlanError
from missions.thermal.blur import blur_px, sharp_speed_mps


class SpeedLimit(NamedTuple):
    """One upper bound on the survey speed and why."""

    speed_mps: float
    kind: str          # "interval" | "blur" | "vehicle"
    why: str           # for the pilot: what sets it, at which step
    where: str         # file:line:col of what the user would change


class Chosen(NamedTuple):
    speed_mps: float
    limit: SpeedLimit


def floor_tenth(v: float) -> float:
    return math.floor(v * 10.0 + 1e-9) / 10.0


def line_limits(label: str, where: str, trigger_m: float, payloads: Sequence[PayloadInfo], altitude_m: float,
                blur_budget_px: float, moving: bool, triggered: Iterable[str]) -> list[SpeedLimit]:
    """The limits one survey or corridor puts on the speed: `triggered` payloads keep their minimum interval at
    the lead's trigger distance, thermal payloads their blur budget at their own GSD. A hover survey photographs
    standing: neither applies."""
    if not moving:
        return []
    out: list[SpeedLimit] = []
    shot = set(triggered)
    for info in payloads:
        if info.name in shot and info.min_interval_s:
            out.append(SpeedLimit(trigger_m / info.min_interval_s, "interval",
                                  f"{info.name} takes a photo every {trigger_m:.1f} m and needs "
                                  f"{info.min_interval_s:g} s between photos ({label})", where))
        if info.time_constant_ms:
            gsd = info.gsd_cm(altitude_m)
            assumed = ", assumed" if info.time_constant_assumed else ""
            out.append(SpeedLimit(sharp_speed_mps(gsd, info.time_constant_ms, blur_budget_px), "blur",
                                  f"{info.name}'s {info.time_constant_ms:g} ms time constant{assumed} may smear "
                                  f"{blur_budget_px:g} px of {gsd:.2f} cm ({label})", where))
    return out


def choose_speed(limits: Sequence[SpeedLimit], cap: SpeedLimit) -> Chosen:
    """The fastest speed within every limit and the cap; the limit that sets it."""
    tightest = min([*limits, cap], key=lambda lim: lim.speed_mps)
    return Chosen(floor_tenth(tightest.speed_mps), tightest)


def check_sharp(limits: Sequence[SpeedLimit], speed_mps: float, where: str) -> None:
    """An explicit speed faster than a blur budget allows is an error naming the fastest sharp speed."""
    for lim in limits:
        if lim.kind == "blur" and speed_mps > lim.speed_mps + 1e-9:
            fastest = floor_tenth(lim.speed_mps)
            raise PlanError(f"at {speed_mps:g} m/s the thermal images smear: {lim.why}, so the fastest sharp "
                            f"speed is {fastest:g} m/s", where=where,
                            hint=f"fly at {fastest:g} m/s or slower (or speed_mps: auto), fly higher for a coarser "
                                 f"GSD, or allow more blur with blur_px at {lim.where}")


def smear_px(speed_mps: float, info: PayloadInfo, altitude_m: float) -> float | None:
    """Pixels `info` smears at `speed_mps` (None: not a thermal imager)."""
    if not info.time_constant_ms:
        return None
    return blur_px(speed_mps, info.gsd_cm(altitude_m), info.time_constant_ms)
