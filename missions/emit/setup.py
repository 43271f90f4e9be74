"""Camera settings -> commands, and the pre-flight command sequence (`NAME.setup.json`).

A plan's payload settings reach the camera on the ground, before take-off, as COMMAND_LONGs from the ground
station or a companion (`wiris camera apply NAME.setup.json`): most of them (USER_1/2, SET_CAMERA_MODE on
ArduPilot, DO_DIGICAM_CONFIGURE on PX4) can never travel in a mission (reference autopilots-and-cameras §7,
"practical conclusion"). Each setting's catalogue `command` slot says which MAV_CMD and param carries it:

- settings of one command are merged into one COMMAND_LONG, each in its slot, the slot's `offset` applied
  ("Layout increased by 1", manual §6.3.2.5);
- every other param is None, written as NaN: "NaN can be used to ignore any parameters (keep previously set
  value)" (manual §6.3; COMMAND_LONG params are floats, so NaN is legal in all seven);
- a slot with `when` carries its setting only while the other setting holds that value (range_max_c/
  range_min_c are USER_1 p3/p4 only with range_mode manual; span_half_c/span_center_c share those slots
  with range_mode span) — the loader already refused a setting whose `when` is not met;
- params that are not settings but the command's own meaning are fixed and documented below.

RedEdge settings are classic PARAM_SET (its serial API; MAVLink 1). For a RedEdge flown in a survey the
sequence also puts it in its own overlap capture mode (autoCapMode 2), the mode MicaSense recommends
(reference §5.2), with operatingAlt/overlapAlongTrk/overlapCrossTrk from the plan. Its exposure settings
travel in one DIGICAM_CONFIGURE message (154) for all imagers (extra_param 255, "Set to 255 for all"), the
fields the API ignores set to 0 as it asks; the RedEdge answers that message with nothing, so the step is
sent, not acknowledged (the plan loader has already required shutter and gain with manual mode: a message
has no "keep" value).

JSON: {"format": "wiris-setup", "version": 1, "plan": NAME, "steps": [SetupStep.to_json(), ...]}.
"""

from __future__ import annotations

from dataclasses import dataclass
import json
import math
from typing import Any, Iterable, Mapping

from missions.compiled import SetupStep
from missions.errors import PlanError
from missions.emit.items import mavlink

SETUP_FORMAT = "wiris-setup"
SETUP_VERSION = 1

# Order on the wire: mode/layout first (it changes what the HDMI shows while the rest is set), the thermal
# and alarm settings, the visible camera, and last the test shot that also sets image formats and storage.
COMMAND_ORDER = ("MAV_CMD_SET_CAMERA_MODE", "MAV_CMD_USER_1", "MAV_CMD_USER_2", "MAV_CMD_DO_DIGICAM_CONFIGURE",
                 "MAV_CMD_DO_DIGICAM_CONTROL", "MAV_CMD_IMAGE_START_CAPTURE", "MAV_CMD_VIDEO_START_CAPTURE")

# Params a command needs that are not settings (index 1..7 -> value).
FIXED_PARAMS: dict[str, dict[int, float]] = {
    # p1 target camera id 0 = every sensor of the camera that receives it (common.xml); p2 the standard
    # CAMERA_MODE, image for a capture plan (Workswell's p2 "Camera mode", manual §6.3.2.5).
    "MAV_CMD_SET_CAMERA_MODE": {1: 0.0, 2: float(mavlink.CAMERA_MODE_IMAGE)},
    # One picture (p3 = 1, p2 interval 0): IMAGE_START_CAPTURE is the only command carrying the image
    # formats (p5) and storage (p6) (manual §6.3.2.6), so applying them takes a test shot on the ground.
    "MAV_CMD_IMAGE_START_CAPTURE": {1: 0.0, 2: 0.0, 3: 1.0, 4: 0.0},
    # p5 shoot = 0: change the zoom without taking a picture (manual §6.3.2.2).
    "MAV_CMD_DO_DIGICAM_CONTROL": {5: 0.0},
}


@dataclass(frozen=True)
class CameraCommand:
    """One camera command built from settings: 7 params, None = NaN (keep)."""

    command: str                              # MAV_CMD_* name
    params: tuple[float | None, ...]
    keys: tuple[str, ...]                     # the settings it carries

    @property
    def command_id(self) -> int:
        return int(getattr(mavlink, self.command))


def commands_for(camera: Any, values: Iterable[tuple[str, float | int]],
                 state: Mapping[str, float | int] | None = None) -> list[CameraCommand]:
    """Merge checked setting values into camera commands, slots and offsets applied, `when` respected
    against `state` (settings already on the camera) updated by `values`."""
    values = list(values)
    merged = {**(state or {}), **dict(values)}
    slots: dict[str, list[float | None]] = {}
    keys: dict[str, list[str]] = {}
    for key, value in values:
        s = camera.setting(key)
        slot = s.command if s is not None else None
        if slot is None or slot.cmd is None:
            continue
        if any(merged.get(k) != v for k, v in slot.when):
            continue
        params = slots.setdefault(slot.cmd, [None] * 7)
        if params[slot.param - 1] is not None:
            other = next(k for k in keys[slot.cmd] if camera.setting(k).command.param == slot.param)
            raise PlanError(f"{key} and {other} both need {slot.cmd} param {slot.param}",
                            hint="set only one of them")
        params[slot.param - 1] = slot.encode(value)
        keys.setdefault(slot.cmd, []).append(key)
    out = []
    for cmd in sorted(slots, key=lambda c: COMMAND_ORDER.index(c) if c in COMMAND_ORDER else len(COMMAND_ORDER)):
        params = slots[cmd]
        for idx, v in FIXED_PARAMS.get(cmd, {}).items():
            if params[idx - 1] is None:
                params[idx - 1] = v
        out.append(CameraCommand(cmd, tuple(params), tuple(keys[cmd])))
    return out


def message_settings(camera: Any, values: Iterable[tuple[str, Any]]) -> list[tuple[str, Any, Any]]:
    """(key, value, setting) of settings that travel as messages (RedEdge PARAM_SET / DIGICAM_CONFIGURE)."""
    out = []
    for key, value in values:
        s = camera.setting(key)
        if s is not None and s.command is not None and s.command.message:
            out.append((key, value, s))
    return out


def _describe(cmd: CameraCommand, camera: Any, values: Mapping[str, Any]) -> str:
    parts = []
    for k in cmd.keys:
        v = values[k]
        shown = v if not isinstance(v, (list, tuple)) else "+".join(map(str, v))
        parts.append(f"{k}={shown}")
    extra = " (takes one test photo)" if cmd.command == "MAV_CMD_IMAGE_START_CAPTURE" else ""
    return f"{cmd.command.removeprefix('MAV_CMD_')}: {', '.join(parts)}{extra}"


@dataclass(frozen=True)
class RedEdgeSurvey:
    """What the RedEdge overlap mode needs from the plan, as the camera's integer parameters hold it: it
    captures whenever it is at least altitude_m - altitude_tolerance_m above the ground (serial API
    opAltTolerance: "distance below the operating altitude to enable automatic capture modes")."""

    altitude_m: int
    altitude_tolerance_m: int
    front_pct: int
    side_pct: int


def setup_steps(payloads: Iterable[Any], cameras: Mapping[str, Any],
                rededge: Mapping[str, RedEdgeSurvey] | None = None) -> tuple[SetupStep, ...]:
    """The pre-flight sequence for plan payloads (missions.plan.Payload), cameras by payload name."""
    steps: list[SetupStep] = []
    rededge = rededge or {}
    for p in payloads:
        cam = cameras[p.name]
        raw = dict(p.settings)
        if cam.protocol == "rededge-serial":
            steps.extend(_rededge_steps(p, cam, rededge.get(p.name)))
            continue
        steps.append(SetupStep(
            description=f"identify the camera: request CAMERA_INFORMATION from component {p.component_id}",
            target_component=p.component_id, kind="command_long", command="MAV_CMD_REQUEST_MESSAGE",
            params=(float(mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            payload=p.name))
        for cmd in commands_for(cam, p.values):
            if cmd.command == "MAV_CMD_VIDEO_START_CAPTURE":
                raise PlanError(f"payload {p.name}: the video setting is applied by VIDEO_START_CAPTURE, which "
                                "starts recording on the ground", hint="remove `video` from the plan's settings; "
                                "plans do not record video yet")
            steps.append(SetupStep(description=_describe(cmd, cam, raw), target_component=p.component_id,
                                   kind="command_long", command=cmd.command, params=cmd.params, payload=p.name))
    return tuple(steps)


def _param_step(p: Any, s: Any, value: float | int, why: str) -> SetupStep:
    """A classic PARAM_SET of catalogue setting `s`, typed as the camera's parameter is (the camera reads the
    value's bytes as that type: `wiris camera apply` packs them so)."""
    value = s.check(value)
    ptype = "MAV_PARAM_TYPE_" + ("REAL32" if s.type == "float" else s.type.upper())
    return SetupStep(description=why, target_component=p.component_id, kind="param_set", param_id=s.param,
                     value=value, type=ptype, expect="PARAM_VALUE", payload=p.name)


# DIGICAM_CONFIGURE's value for "every imager" in its extra_param field (serial API: "Set to 255 for all")
ALL_IMAGERS = 255


def _rededge_steps(p: Any, cam: Any, survey: RedEdgeSurvey | None) -> list[SetupStep]:
    steps = []
    user, written = dict(p.values), dict(p.settings)
    param_sets: list[SetupStep] = []
    digicam: dict[str, int] = {}      # DIGICAM_CONFIGURE field -> value
    shown: list[str] = []             # the plan's settings behind them, for the step's description
    for key, value, s in message_settings(cam, p.values):
        if s.command.message == "PARAM_SET":
            param_sets.append(_param_step(p, s, value, f"{key} = {written.get(key)!r} (plan setting)"))
        elif s.command.message == "DIGICAM_CONFIGURE":
            digicam[s.command.field] = int(value)
            shown.append(f"{key} = {written.get(key)!r}")
        else:
            raise PlanError(f"payload {p.name}: {key} travels in the {s.command.message} message, which the setup "
                            "sequence does not send", hint="set it in the RedEdge web page (http://192.168.10.254)")
    if survey is not None:
        auto = {
            "autoCapMode": ("overlap", "RedEdge overlap mode (autoCapMode 2): it triggers itself from GPS, "
                                       "MicaSense's recommended mode; autopilot trigger commands do not reach it"),
            "operatingAlt": (survey.altitude_m, "overlap mode's target altitude: the lowest survey altitude above "
                                                "take-off"),
            "opAltTolerance": (survey.altitude_tolerance_m,
                               "it captures from this many metres below the target altitude up (not while "
                               "climbing to it)"),
            "overlapAlongTrk": (survey.front_pct, "front overlap of the plan (overlap mode computes along-track "
                                                  "only)"),
            "overlapCrossTrk": (survey.side_pct, "side overlap of the plan (the lines are spaced by the planner)"),
        }
        for param, (value, why) in auto.items():
            s = cam.setting_by_param(param)
            if s is None:
                raise PlanError(f"payload {p.name}: the catalogue's {cam.id} has no parameter {param}",
                                hint="the RedEdge table in cdf/tables/ lists the overlap-mode parameters; restore it")
            if s.key in user:
                continue   # the plan's own setting wins
            steps.append(_param_step(p, s, value, why))
    steps += param_sets
    if digicam:
        fields = tuple(sorted({**digicam, "extra_param": ALL_IMAGERS}.items()))
        steps.append(SetupStep(description=f"exposure of every imager: {', '.join(shown)} (the RedEdge does not "
                                           "answer)",
                               target_component=p.component_id, kind="message", message="DIGICAM_CONFIGURE",
                               fields=fields, expect="UNACKNOWLEDGED", payload=p.name))
    return steps


def setup_json(plan_name: str, steps: Iterable[SetupStep]) -> dict:
    return {"format": SETUP_FORMAT, "version": SETUP_VERSION, "plan": plan_name,
            "steps": [s.to_json() for s in steps]}


def dumps_setup(plan_name: str, steps: Iterable[SetupStep]) -> str:
    """NAME.setup.json text. None params are JSON null (NaN is not JSON): null means NaN = keep."""
    return json.dumps(setup_json(plan_name, steps), indent=2, allow_nan=False) + "\n"


def wire_params(params: Iterable[float | None]) -> tuple[float, ...]:
    """The seven COMMAND_LONG floats: None -> NaN."""
    return tuple(math.nan if v is None else float(v) for v in params)
