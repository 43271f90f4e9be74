"""Camera settings in a plan checked against the camera catalogue, with the same `Setting.check` and messages
as the camera definition: a payload's settings before flight and a camera step's changes in flight.

    state = {}
    check_settings(camera, body["settings"], ("payloads", "thermal", "settings"), yaml_doc, state)

`state` is the payload's settings so far: a setting that takes effect only with another (`when`) is judged
against what the camera will hold at that point of the mission, not against the step alone.
"""

from __future__ import annotations

from typing import Any

from cdf.errors import CdfError, shown
from missions.plan.yaml_reader import PositionedYaml


def check_settings(camera: Any, settings: Any, path: tuple, doc: PositionedYaml,
                   state: dict[str, float | int]) -> None:
    """Report each problem of `settings` (written at `path`) to `doc`; add the good ones' values to `state`."""
    if not isinstance(settings, dict):
        return
    given = _checked_values(camera, settings, path, doc)
    merged = {**state, **given}
    _check_conditions(camera, given, merged, path, doc)
    _check_message_fields(camera, given, merged, path, doc)
    state.update(given)


def _checked_values(camera: Any, settings: dict, path: tuple, doc: PositionedYaml) -> dict[str, float | int]:
    """The wire value of each setting the camera has and accepts the value of, in the plan's order."""
    values: dict[str, float | int] = {}
    for key, value in settings.items():
        # the plan name or the PARAM_EXT name, in any case: the names `wiris camera set` takes too
        s = camera.setting_named(key)
        if s is None:
            doc.report(path + (key,), f"{camera.id} has no setting {shown(key)}", camera.setting_hint(key), key=True)
            continue
        if s.key in values:
            doc.report(path + (key,), f"{key} is {s.key} again (a setting given twice)",
                       f"give {s.key} once", key=True)
            continue
        try:
            values[s.key] = s.check(value)
        except CdfError as e:
            doc.report(path + (key,), f"{camera.id}: {e.message}", e.hint)
    return values


def _check_conditions(camera: Any, given: dict[str, float | int], merged: dict[str, float | int], path: tuple,
                      doc: PositionedYaml) -> None:
    """Each given setting whose `when` (another setting's option) the camera will not hold."""
    for key in given:
        s = camera.setting(key)
        if s.command and s.command.when:
            for wkey, wval in s.command.when:
                if merged.get(wkey) != wval:
                    opt = camera.option_key(wkey, wval)
                    doc.report(path + (key,), f"{key} takes effect only with {wkey}: {opt}",
                               f"add `{wkey}: {opt}` to the same settings", key=True)


def _check_message_fields(camera: Any, given: dict[str, float | int], merged: dict[str, float | int], path: tuple,
                          doc: PositionedYaml) -> None:
    # A message such as DIGICAM_CONFIGURE sends every field at once and, unlike a MAV_CMD (NaN), has no
    # value meaning "keep": a field whose `when` holds must be given, or the camera would get a made-up one.
    for s in camera.settings:
        slot = s.command
        if slot is None or slot.message in (None, "PARAM_SET") or not slot.when or s.key in merged:
            continue
        trigger = next((k for k, v in slot.when if k in given and given[k] == v), None)
        if trigger is not None and all(merged.get(k) == v for k, v in slot.when):
            opt = camera.option_key(trigger, given[trigger])
            doc.report(path + (trigger,), f"{trigger}: {opt} also needs {s.key} ({s.label}): the {slot.message} "
                       "message carries it and has no value meaning 'keep'", f"add `{s.key}` to the same settings")
