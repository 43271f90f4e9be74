"""The mission's speed: the plan's, checked against every survey's and corridor's limits (interval and blur), or
the fastest that `speed_mps: auto` finds every camera allows.
"""

from __future__ import annotations

from missions.compiled import PayloadInfo, PlanWarning
from missions.errors import PlanError
from missions.geometry import optics
from missions.plan.load import CorridorStep, Plan, SurveyStep
from missions.plan.schema import SPEED_RANGE_MPS
from missions.thermal.speed import SpeedLimit, choose_speed, line_limits
from missions.compiler.context import CompileState, NEAR_MIN_INTERVAL, Payloads
from missions.compiler.payloads import lead_optics, line_altitude


def _speed_limits(plan: Plan, payloads: Payloads) -> list[SpeedLimit]:
    """Every survey's and corridor's limits on the speed (interval and blur), from the same optics, altitude and
    trigger distance the steps plan with."""
    limits: list[SpeedLimit] = []
    for step in plan.mission:
        if not isinstance(step, (SurveyStep, CorridorStep)):
            continue
        kind = "survey" if isinstance(step, SurveyStep) else "corridor"
        try:
            lead = lead_optics(plan, payloads, step, kind)
            alt = line_altitude(plan, step, lead)
        except PlanError:
            continue                 # the step's own pass reports it, in mission order
        limits += step_limits(plan, payloads, step, lead, alt)
    return limits


def step_limits(plan: Plan, payloads: Payloads, step: SurveyStep | CorridorStep, lead: PayloadInfo,
                alt: float) -> list[SpeedLimit]:
    kind = "survey" if isinstance(step, SurveyStep) else "corridor"
    infos = [payloads.optics[n] for n in step.payloads if n in payloads.optics]
    triggered = [n for n in step.payloads if not payloads.is_rededge(n)]
    return line_limits(f"{kind} at {plan.step_where(step)}", plan.step_where(step, "blur_px"),
                       optics.trigger_m(lead, alt, step.front_pct), infos, alt, step.blur_px,
                       moving=step.trigger != "hover", triggered=triggered)


def mission_speed(plan: Plan, payloads: Payloads, state: CompileState) -> float:
    """The plan's speed, checked against the blur budgets and vehicle.max_speed_mps; or, for `auto`, the
    fastest speed every camera allows (capped by vehicle.max_speed_mps or the frame's plausible maximum)."""
    v = plan.vehicle
    where = plan.where("vehicle", "speed_mps")
    limits = _speed_limits(plan, payloads)
    low, high = SPEED_RANGE_MPS[v.frame]
    if v.speed_mps is not None:
        if v.max_speed_mps is not None and v.speed_mps > v.max_speed_mps:
            raise PlanError(f"speed_mps {v.speed_mps:g} is above vehicle.max_speed_mps {v.max_speed_mps:g}",
                            where=where, hint=f"fly at {v.max_speed_mps:g} m/s or slower, or speed_mps: auto")
        return v.speed_mps          # each step checks it against its limits (`_check_sharp`)
    if v.max_speed_mps is not None:
        cap = SpeedLimit(v.max_speed_mps, "vehicle", "vehicle.max_speed_mps", plan.where("vehicle", "max_speed_mps"))
    elif limits:
        cap = SpeedLimit(high, "vehicle", f"the fastest plausible {v.frame} survey speed", where)
    else:
        raise PlanError("speed_mps: auto sizes the speed from the surveys and corridors, and this plan has none",
                        where=where, hint="give a number, e.g. speed_mps: 5, or vehicle.max_speed_mps")
    # auto keeps the interval NEAR_MIN_INTERVAL above the camera's minimum: a gust of tail wind loses no photo
    chosen = choose_speed([lim._replace(speed_mps=lim.speed_mps / NEAR_MIN_INTERVAL,
                                        why=lim.why + f" with a {NEAR_MIN_INTERVAL - 1:.0%} margin")
                           if lim.kind == "interval" else lim for lim in limits], cap)
    if chosen.speed_mps < low:
        raise PlanError(f"speed_mps: auto finds no speed a {v.frame} can fly: {chosen.limit.why} allows at most "
                        f"{chosen.speed_mps:g} m/s, below the {low:g} m/s minimum", where=chosen.limit.where,
                        hint="fly higher (coarser GSD, longer trigger distance), lower the front overlap, or "
                             "raise blur_px")
    state.warnings.append(PlanWarning("speed_auto", f"speed_mps: auto chose {chosen.speed_mps:g} m/s, the fastest "
                                      f"at which {chosen.limit.why}"))
    return chosen.speed_mps
