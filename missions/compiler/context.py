"""The values one compile passes between its stages, and the checks every stage makes on positions and errors.

`Compilation` is what every step reads (plan, firmware, payloads) and adds to (the emitter, `CompileState`);
both are local to one `missions.compile.compile_plan` call, never shared.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

from missions.compiled import AreaInfo, PayloadInfo, PlanWarning, StepFacts, TransectPattern
from missions.emit.emitter import Emitter
from missions.emit.firmware import FirmwareProfile, profile
from missions.errors import PlanError
from missions.geometry import optics
from missions.geometry.area import Area
from missions.geometry.corridor import CorridorPlan
from missions.geometry.footprint import Footprint
from missions.geometry.geo import MAX_EXTENT_M
from missions.geometry.survey import SurveyPlan
from missions.geometry.zones import TransitRouter, Zone
from missions.plan.load import Plan


NEAR_MIN_INTERVAL = 1.2      # warn when photos come less than 20 % slower than the camera's minimum
TURNAROUND_DEFAULT_M = {"copter": 10.0, "plane": 30.0, "vtol": 30.0}   # QGC's defaults (survey-planners §1.4)


class Altitude(NamedTuple):
    """An altitude the mission flies at, and where the plan sets it."""

    altitude_m: float
    where: str


class RedEdgeFlight(NamedTuple):
    """A survey or corridor a RedEdge flies: its one overlap mode must cover them all (`rededge_survey`)."""

    altitude_m: float
    front_pct: float
    side_pct: float


class RedEdgeCheck(NamedTuple):
    """A RedEdge flying beside another payload's lines: it captures by its own footprint and front overlap, so
    its interval at this altitude is checked once its overlap (the most demanding of its surveys) is known."""

    payload: str
    altitude_m: float
    where: str


@dataclass(frozen=True)
class Payloads:
    """The plan's payloads as the catalogue resolves them, by payload name."""

    cameras: dict[str, Any]                  # catalogue Camera
    instances: dict[str, int]                # ArduPilot CAMn instance (WIRIS only)
    optics: dict[str, PayloadInfo]           # payloads whose optics are known
    optics_errors: dict[str, PlanError]      # the others: an error only where a footprint is needed

    def is_rededge(self, name: str) -> bool:
        """A RedEdge triggers itself (overlap mode): no trigger items, no AP_Camera instance."""
        return self.cameras[name].protocol == "rededge-serial"


@dataclass
class CompileState:
    """Mutable bookkeeping of one compile (local to `compile_plan`, never shared), added to step by step."""

    warnings: list[PlanWarning | str]
    areas: list[AreaInfo] = field(default_factory=list)
    intent: list[SurveyPlan | CorridorPlan] = field(default_factory=list)
    patterns: list[TransectPattern] = field(default_factory=list)
    altitudes: list[Altitude] = field(default_factory=list)
    rededge_flights: dict[str, list[RedEdgeFlight]] = field(default_factory=dict)
    rededge_checks: list[RedEdgeCheck] = field(default_factory=list)
    # each payload's settings as the camera holds them at this point of the mission (wire values by key)
    settings_now: dict[str, dict[str, float | int]] = field(default_factory=dict)
    step_facts: list[StepFacts] = field(default_factory=list)


@dataclass(frozen=True)
class Compilation:
    """One compile: what every step reads (plan, firmware, payloads) and what it adds to (emitter, state)."""

    plan: Plan
    profile: FirmwareProfile
    payloads: Payloads
    emitter: Emitter
    state: CompileState
    speed_mps: float                         # the plan's, or the one `auto` chose (`mission_speed`)
    turn_radius_m: float | None = None       # a plane's or VTOL's (`missions.plan_turns.turn_radius_of`)
    zones: tuple[Zone, ...] = ()             # every zone of the plan (missions.geometry.zones.plan_zones)
    transits: TransitRouter | None = None    # routes the flight between steps around the no-fly zones
    terrain: Any = None                      # missions.terrain.model.Terrain when the plan names a DEM

    def warn(self, code: str, message: str) -> None:
        self.state.warnings.append(PlanWarning(code, message))


class LineInputs(NamedTuple):
    """What the survey and corridor planners take beside the step's own fields."""

    footprint: Footprint
    turnaround_m: float
    start_latlon: tuple[float, float]        # where the vehicle is when the lines begin
    photos_left: int                         # of MAX_PHOTOS, after the plan's earlier lines
    min_interval_s: float | None


class Lines(NamedTuple):
    """A planned survey or corridor and the area it covers (what the report measures against)."""

    route: SurveyPlan | CorridorPlan
    area: Area


def relocate(err: PlanError, where: str) -> PlanError:
    """Geometry errors name a field ("overlap.front") or nothing; give them the plan's file:line:col."""
    w = err.where
    if w is None or (":" not in w and "/" not in w and not w.endswith((".kml", ".geojson", ".json"))):
        new = PlanError(err.message, where=where + (f" ({w})" if w else ""), hint=err.hint)
        return new
    return err


def check_reach(home: Any, lat: float, lon: float, what: str, where: str) -> None:
    """A step must lie within MAX_EXTENT_M of home, like an area's own extent: farther is a typo in a
    coordinate, and the flight there (along which a RedEdge keeps shooting) would be thousands of km."""
    from pyproj import Geod   # heavy: loads only for a plan with a positioned step

    distance = Geod(ellps="WGS84").inv(home.lon, home.lat, lon, lat)[2]
    if not distance <= MAX_EXTENT_M:
        raise PlanError(f"this {what} lies {distance / 1000:,.0f} km from home, more than the "
                        f"{MAX_EXTENT_M / 1000:.0f} km one plan may reach", where=where,
                        hint="check the coordinates of home and of this step (latitude and longitude swapped?)")
