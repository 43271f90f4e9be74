"""Stage 1, the capture plan: untrusted YAML -> frozen values (`Plan`), every problem reported with
file:line:col and a hint. The stage's interface is here:

    from missions.plan import Plan, SurveyStep, load_plan, parse_plan

Modules, in the order a plan goes through them (`load.parse_plan` drives it):

    yaml_reader    YAML with positions: size, depth and node caps, no duplicate keys
    schema         the JSON Schema of the format (`wiris mission schema` prints it)
    schema_errors  schema errors mapped back to file:line:col and said for a person
    meaning        what a schema cannot say: cameras, settings (`settings`), component ids, heights, area files
    build          checked values -> `Plan`
    types          the value types every later stage reads
"""

from missions.plan.load import MAX_PLAN_BYTES, input_files, load_plan, parse_plan, raise_problems
from missions.plan.types import (CameraStep, CorridorStep, Home, LandStep, Payload, Plan, RtlStep, Step,
                                 SurveyStep, TakeoffStep, Vehicle, WaypointStep)

__all__ = ["MAX_PLAN_BYTES", "input_files", "load_plan", "parse_plan", "raise_problems",
           "CameraStep", "CorridorStep", "Home", "LandStep", "Payload", "Plan", "RtlStep", "Step", "SurveyStep",
           "TakeoffStep", "Vehicle", "WaypointStep"]
