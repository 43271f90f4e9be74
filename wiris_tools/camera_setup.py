"""Setup files: the pre-flight command sequence `wiris mission compile` writes (NAME.setup.json) and
`wiris camera apply` runs, read into Steps (command_long, param_ext_set, param_set, message), each checked
where it is written: kind, command or message, fields that fit the wire, values that are numbers.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.userfile import UserFile, read_user_file
from cdf.validation.values import INT_RANGES
from wiris_tools import paramext
from wiris_tools.errors import LinkError


MAX_SETUP_BYTES = 1024 * 1024
SETUP_FILE = UserFile("setup file", MAX_SETUP_BYTES, LinkError,
                      hint="check the path and its permissions; `wiris mission compile PLAN -o DIR` writes "
                           "DIR/NAME.setup.json",
                      size_hint="give the NAME.setup.json that `wiris mission compile` wrote, not another file")
MAX_STEPS = 1000


@dataclass(frozen=True)
class Step:
    number: int
    description: str
    kind: str
    target_component: int
    command: int | None = None
    params: tuple[float, ...] = ()
    expect: str = "MAV_RESULT_ACCEPTED"
    param_id: str = ""
    value: float | int | None = None
    type: str = ""
    message: str = ""                              # kind "message": the MAVLink message and its fields
    fields: tuple[tuple[str, float | int], ...] = ()
    payload: str = ""                              # the plan's payload the step sets up ("" when not said)

    @property
    def label(self) -> str:
        return f"step {self.number} ({self.description})" if self.description else f"step {self.number}"


def nan_params(values: list[float | None]) -> list[float]:
    return [math.nan if v is None else float(v) for v in values]


KINDS = ("command_long", "param_ext_set", "param_set", "message")
# Messages a "message" step may send: commands that a camera takes without answering. Only these, so that
# a setup file cannot send just any message (a DIGICAM_CONTROL would take photos, for one).
MESSAGES = ("DIGICAM_CONFIGURE",)
MESSAGE_GAP_S = 0.1


def _is_number(value: Any) -> bool:
    """A finite JSON number (true and false are not numbers here)."""
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


def message_fields(name: str) -> dict[str, str]:
    """A message's settable fields (all but the target ids, in order) and their C types, from pymavlink's
    dialect."""
    cls = getattr(mavlink2, f"MAVLink_{name.lower()}_message")
    return {f: t for f, t in zip(cls.fieldnames, cls.fieldtypes) if f not in ("target_system", "target_component")}


def _checked_message(s: dict, loc: str) -> tuple[str, tuple[tuple[str, float | int], ...]]:
    name = s.get("message")
    if name not in MESSAGES:
        raise LinkError(f"a setup step cannot send message {name!r}", where=loc,
                        hint=f"messages: {', '.join(MESSAGES)}")
    fields = s.get("fields", {})
    if not isinstance(fields, dict):
        raise LinkError("fields must be a JSON object of field name -> number", where=loc,
                        hint='e.g. "fields": {"mode": 2, "shutter_speed": 2000, "extra_param": 255}')
    types = message_fields(name)
    out = []
    for key, value in fields.items():
        ctype = types.get(key)
        if ctype is None:
            raise LinkError(f"{name} has no field {key!r} a step may set", where=loc,
                            hint=f"fields: {', '.join(types)}")
        if not _is_number(value):
            raise LinkError(f"{key} = {value!r} is not a finite number", where=loc,
                            hint=f'write a plain JSON number, e.g. "{key}": 2 (not text, true/false, null or NaN)')
        int_range = INT_RANGES.get(ctype.removesuffix("_t"))    # pymavlink's uint8_t is the CDF's uint8
        if int_range is not None:
            lo, hi = int_range
            if value != int(value) or not lo <= value <= hi:
                raise LinkError(f"{key} = {value!r} is not an integer {lo}–{hi} ({ctype})", where=loc,
                                hint=f"write a whole number from {lo} to {hi}, or compile the plan again "
                                     "(`wiris mission compile`)")
            value = int(value)
        out.append((key, value))
    return name, tuple(out)


def parse_setup(data: Any, where: str = "setup") -> list[Step]:
    """Steps of a NAME.setup.json document (missions' compiler output); unknown extra fields are ignored.

    Everything is checked before anything is sent, so a bad file changes nothing on the camera."""
    if not isinstance(data, dict) or not isinstance(data.get("steps"), list):
        raise LinkError('a setup file is a JSON object with a "steps" list', where=where,
                        hint="use the NAME.setup.json that `wiris mission compile` writes")
    raw_steps = data["steps"]
    if len(raw_steps) > MAX_STEPS:
        raise LinkError(f"{len(raw_steps)} steps; at most {MAX_STEPS} are accepted", where=where,
                        hint=f"split the steps into files of at most {MAX_STEPS} and apply them one after another")
    return [_parse_step(i, s, where) for i, s in enumerate(raw_steps, start=1)]


class _StepHead(NamedTuple):
    """What every step has: its number, description, kind, target component and where it is in the file."""

    index: int
    description: str
    kind: str
    component: int
    where: str


def _parse_step(i: int, s: Any, where: str) -> Step:
    loc = f"{where}: step {i}"
    if not isinstance(s, dict):
        raise LinkError("a step must be a JSON object", where=loc,
                        hint='write each step as an object, e.g. {"kind": "param_set", "param_id": '
                             '"autoCapMode", "value": 2}')
    desc = str(s.get("description") or "")[:200]
    if desc:
        loc += f" ({desc})"
    kind = s.get("kind")
    if kind not in KINDS:
        raise LinkError(f"unknown step kind {kind!r}", where=loc, hint=f"kinds: {', '.join(KINDS)}")
    comp = s.get("target_component", 0)
    if isinstance(comp, bool) or not isinstance(comp, int) or not 0 <= comp <= 255:
        raise LinkError(f"target_component {comp!r} is not a component id (0–255)", where=loc,
                        hint='write the camera\'s component id, e.g. "target_component": 100 (0: the camera '
                             'connected to)')
    payload = s.get("payload", "")
    if not isinstance(payload, str):
        raise LinkError(f"payload {payload!r} is not a payload name", where=loc,
                        hint='write the plan\'s payload name as text, e.g. "payload": "thermal", or leave it out')
    head = _StepHead(i, desc, kind, comp, loc)
    parse = _STEP_PARSERS.get(kind, _parse_param_step)
    return dataclasses.replace(parse(head, s), payload=payload)


def steps_of_payload(steps: list[Step], name: str, where: str = "setup") -> list[Step]:
    """The steps that set up payload `name` (in their order); LinkError naming the payloads there are when no
    step is for it."""
    mine = [s for s in steps if s.payload == name]
    if mine:
        return mine
    names = sorted({s.payload for s in steps if s.payload})
    if not names:
        raise LinkError(f"no step names its payload, so none can be chosen as {name!r}", where=where,
                        hint="compile the plan again: `wiris mission compile` names each step's payload")
    close = difflib.get_close_matches(name, names, n=1)
    raise LinkError(f"no step is for payload {name!r}" + (f"; did you mean {close[0]!r}?" if close else ""),
                    where=where, hint=f"the payloads of this file: {', '.join(names)}")


def _parse_command_step(head: _StepHead, s: dict) -> Step:
    loc = head.where
    cmd = s.get("command")
    if isinstance(cmd, str):
        number = getattr(mavlink2, cmd, None) if cmd.startswith("MAV_CMD_") else None
        if not isinstance(number, int):
            raise LinkError(f"unknown command {cmd!r}", where=loc, hint="use a MAV_CMD_* name from common.xml")
        cmd = number
    if isinstance(cmd, bool) or not isinstance(cmd, int) or not 0 <= cmd <= 65535:
        raise LinkError(f"command {s.get('command')!r} is not a MAV_CMD name or number", where=loc,
                        hint='e.g. "command": "MAV_CMD_SET_CAMERA_MODE" or its number 530')
    params = s.get("params", [])
    if not isinstance(params, list) or len(params) > 7 or any(
            p is not None and (isinstance(p, bool) or not isinstance(p, (int, float))) for p in params):
        raise LinkError("params must be a list of at most 7 numbers or null (NaN)", where=loc,
                        hint='e.g. "params": [0, 1, null, null, null, null, null] (null keeps the value)')
    params = list(params) + [None] * (7 - len(params))
    expect = (s.get("expect") or {}).get("result", "MAV_RESULT_ACCEPTED") \
        if isinstance(s.get("expect") or {}, dict) else "MAV_RESULT_ACCEPTED"
    if not isinstance(getattr(mavlink2, str(expect), None), int) or not str(expect).startswith("MAV_RESULT_"):
        raise LinkError(f"unknown expected result {expect!r}", where=loc, hint="e.g. MAV_RESULT_ACCEPTED")
    return Step(head.index, head.description, head.kind, head.component, cmd, tuple(nan_params(params)),
                str(expect))


def _parse_message_step(head: _StepHead, s: dict) -> Step:
    name, fields = _checked_message(s, head.where)
    return Step(head.index, head.description, head.kind, head.component, expect="UNACKNOWLEDGED", message=name,
                fields=fields)


def _parse_param_step(head: _StepHead, s: dict) -> Step:
    """param_set (a classic parameter) or param_ext_set (a PARAM_EXT one): name, value and its wire type."""
    loc, kind = head.where, head.kind
    pid = s.get("param_id")
    if not isinstance(pid, str) or not 1 <= len(pid) <= 16 or not pid.isascii():
        raise LinkError(f"param_id {pid!r} must be 1–16 ASCII characters", where=loc,
                        hint='write the name the camera uses, e.g. "param_id": "EMISSIVITY" '
                             '(`wiris camera settings` lists them)')
    value = s.get("value")
    if not _is_number(value):
        raise LinkError(f"value {value!r} is not a finite number", where=loc,
                        hint='write a plain JSON number, e.g. "value": 0.97 (not text, true/false, null or NaN)')
    ptype = str(s.get("type") or ("float" if kind == "param_set" else ""))
    if kind == "param_ext_set":
        try:
            paramext.encode(value, ptype)
        except paramext.WireValueError as err:
            raise LinkError(f"{pid}: {err}", where=loc,
                            hint="type is a definition type: uint8…int64, float, double") from None
    else:
        ptype = _classic_type_name(ptype)
        try:
            paramext.encode_classic(value, ptype)
        except paramext.WireValueError as err:
            raise LinkError(f"{pid}: {err}", where=loc,
                            hint='type is the parameter\'s MAV_PARAM_TYPE, e.g. "MAV_PARAM_TYPE_UINT32" or '
                                 '"MAV_PARAM_TYPE_REAL32" (4 bytes at most), with a value that fits it') from None
    return Step(head.index, head.description, kind, head.component, None, (), "", pid, value, ptype)


# One parser per step kind (the param kinds share one).
_STEP_PARSERS = {"command_long": _parse_command_step, "message": _parse_message_step,
                 "param_set": _parse_param_step, "param_ext_set": _parse_param_step}


def _classic_type_name(ptype: str) -> str:
    """A param_set step's type as a definition type name: "MAV_PARAM_TYPE_UINT32" (as compile writes it) ->
    "uint32", "MAV_PARAM_TYPE_REAL32" -> "float"; a definition type name stays as it is."""
    name = ptype.upper().removeprefix("MAV_PARAM_TYPE_").lower()
    return "float" if name == "real32" else name


def load_setup(path: str | Path) -> list[Step]:
    raw = read_user_file(path, SETUP_FILE)
    from missions.formats.outputs import check_output
    check_output(path)        # only the last complete compile's NAME.setup.json (PlanError otherwise)
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        line = getattr(err, "lineno", None)
        raise LinkError(f"not valid JSON: {err}", where=f"{path}:{line}" if line else str(path),
                        hint="fix the JSON (UTF-8) at that place, or write the file again with "
                             "`wiris mission compile`") from None
    return parse_setup(data, str(path))
