"""Before the steps: each payload's catalogue camera, ArduPilot camera instance and optics, the emitter they
drive, and the optics and altitude a survey's or corridor's first payload sets.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink

from cdf.catalogue import catalogue
from missions.compiled import PayloadInfo
from missions.emit.emitter import Emitter
from missions.emit.firmware import FirmwareProfile
from missions.errors import PlanError
from missions.geometry import optics
from missions.plan.load import CorridorStep, Plan, SurveyStep
from missions.plan.meaning import Ceiling, ceiling_problem
from missions.plan.schema import MAX_AGL_M, MAX_ALTITUDE_M, MIN_ALTITUDE_M
from missions.compiler.context import CompileState, Payloads


def resolve_payloads(plan: Plan, prof: FirmwareProfile, state: CompileState) -> Payloads:
    """Each payload's catalogue camera, ArduPilot instance and optics (their warnings go to `state`)."""
    cat = catalogue()
    cameras = {p.name: cat.get(p.camera) for p in plan.payloads}
    # ArduPilot drives each WIRIS as an AP_Camera instance (CAMn_TYPE 6); the RedEdge is not one (it triggers
    # itself). PX4 addresses cameras by component id instead.
    wiris = [p.name for p in plan.payloads if cameras[p.name].protocol != "rededge-serial"]
    if len(wiris) > prof.max_camera_instances:
        raise PlanError(f"{prof.title} drives at most {prof.max_camera_instances} MAVLink cameras (CAM1..CAM"
                        f"{prof.max_camera_instances}); the plan has {len(wiris)}", where=plan.where("payloads"),
                        hint="fly fewer WIRIS payloads")
    known: dict[str, PayloadInfo] = {}
    unknown: dict[str, PlanError] = {}
    for p in plan.payloads:
        try:
            info, warn = optics.payload_info(p, cameras[p.name], where=plan.where("payloads", p.name))
            known[p.name] = info
            state.warnings.extend(warn)
        except PlanError as e:
            unknown[p.name] = e
    return Payloads(cameras, _camera_instances(plan, prof, wiris), known, unknown)


def _camera_instances(plan: Plan, prof: FirmwareProfile, wiris: list[str]) -> dict[str, int]:
    """Each WIRIS payload's ArduPilot camera instance (CAMn). ArduPilot's MAVLinkCamV2 backend looks for
    instance n at component 100 + n - 1 only (AP_Camera_MAVLinkCamV2::find_camera), so the instance follows
    from the component id; a camera at a component no instance looks at would never be found and would take
    no photo, silently: refused. PX4 addresses cameras by component id (the numbers are only an order)."""
    if prof.camera_target != "instance":
        return {name: i + 1 for i, name in enumerate(wiris)}
    out: dict[str, int] = {}
    for name in wiris:
        component = plan.payload(name).component_id
        instance = component - mavlink.MAV_COMP_ID_CAMERA + 1
        if not 1 <= instance <= prof.max_camera_instances:
            last = mavlink.MAV_COMP_ID_CAMERA + prof.max_camera_instances - 1
            raise PlanError(f"{prof.title} would never find {name} at component {component}: its MAVLinkCamV2 "
                            f"backend looks for camera instance n at component 100 + n - 1 only, and it has "
                            f"CAM1..CAM{prof.max_camera_instances} (components 100..{last})",
                            where=plan.where("payloads", name, "component_id"),
                            hint=f"set the camera's MAVLink id (camera menu) to one of 100..{last} and "
                                 "component_id to the same")
        out[name] = instance
    return out


def emitter_for(plan: Plan, prof: FirmwareProfile, payloads: Payloads, speed_mps: float) -> Emitter:
    return Emitter(prof, plan.vehicle.frame, speed_mps, (plan.home.lat, plan.home.lon),
                   payloads.cameras, {p.name: p.component_id for p in plan.payloads}, payloads.instances,
                   {p.name: dict(p.values) for p in plan.payloads})


def lead_optics(plan: Plan, payloads: Payloads, step: SurveyStep | CorridorStep, kind: str) -> PayloadInfo:
    """The optics of the step's first payload, which sets the lines: without them there is no footprint."""
    lead = step.payloads[0]
    if lead in payloads.optics_errors:
        e = payloads.optics_errors[lead]
        raise PlanError(f"{kind} lines need {lead}'s footprint: {e.message}",
                        where=plan.step_where(step, "payloads", 0), hint=e.hint)
    return payloads.optics[lead]


def line_altitude(plan: Plan, step: SurveyStep | CorridorStep, lead: PayloadInfo) -> float:
    """The step's altitude, or the one at which the lead payload images with the step's GSD."""
    if step.altitude_m is not None:
        return step.altitude_m
    alt = optics.altitude_for_gsd(lead, step.gsd_cm)
    if not MIN_ALTITUDE_M <= alt <= MAX_ALTITUDE_M:
        raise PlanError(f"gsd_cm {step.gsd_cm:g} needs {alt:.1f} m above ground with {lead.name}'s optics, "
                        f"outside {MIN_ALTITUDE_M:g}..{MAX_ALTITUDE_M:g} m",
                        where=plan.step_where(step, "gsd_cm"), hint="choose another GSD")
    too_high = ceiling_problem(alt, f"gsd_cm {step.gsd_cm:g} with {lead.name}'s optics", _ceiling(plan),
                               lower="a smaller gsd_cm (finer detail) flies lower")
    if too_high is not None:
        raise PlanError(too_high[0], where=plan.step_where(step, "gsd_cm"), hint=too_high[1])
    return alt


def _ceiling(plan: Plan) -> Ceiling:
    given = plan.vehicle.max_altitude_m
    return Ceiling(given, True) if given is not None else Ceiling(MAX_AGL_M, False)
