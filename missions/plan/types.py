"""The capture plan as frozen values: what the loader (`missions.plan.load`) returns and every later stage reads.

`Plan.where` and `Plan.step_where` give the file:line:col of a value, so a later stage's error points into
the plan the user wrote.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import datetime as dt
from types import MappingProxyType
from typing import Any, Mapping

@dataclass(frozen=True)
class Vehicle:
    firmware: str                   # "ardupilot" | "px4"
    frame: str                      # "copter" | "plane" | "vtol"
    speed_mps: float | None         # None: `auto`, the fastest the cameras allow (missions.thermal.speed)
    max_mission_items: int | None = None
    max_speed_mps: float | None = None
    max_altitude_m: float | None = None     # a permit's ceiling above home; None: MAX_AGL_M (120 m) holds
    firmware_version: str | None = None   # e.g. "4.6": NAME.params names parameters as that version does


@dataclass(frozen=True)
class Home:
    lat: float
    lon: float
    alt_amsl_m: float


@dataclass(frozen=True)
class Payload:
    name: str
    camera: str                                    # catalogue id
    imager: str | None = None                      # None: the camera's first imager with known optics
    lens_mm: float | None = None
    component_id: int = 100
    autopilot_serial: int | None = None            # the autopilot serial port it is wired to (None: the default)
    component_given: bool = True                   # False: chosen by the loader (missions.plan.meaning)
    landscape: bool = True
    settings: tuple[tuple[str, Any], ...] = ()     # as written in the plan
    values: tuple[tuple[str, float | int], ...] = ()   # checked wire values (Setting.check), same order

    def value(self, key: str) -> float | int | None:
        return dict(self.values).get(key)


@dataclass(frozen=True)
class TakeoffStep:
    index: int
    alt_m: float


@dataclass(frozen=True)
class Target:
    """The surface inspected: a PV module plane (tilt from horizontal, azimuth its face looks to)."""

    tilt_deg: float
    azimuth_deg: float


@dataclass(frozen=True)
class Timing:
    """When a step is flown and the wind then (None: the plan's, or not given)."""

    when: dt.datetime | None = None
    wind_mps: float | None = None


@dataclass(frozen=True)
class SurveyStep:
    index: int
    area: str | tuple[tuple[float, float], ...]
    payloads: tuple[str, ...]
    front_pct: float
    side_pct: float
    altitude_m: float | None = None
    gsd_cm: float | None = None
    exclude: tuple[Any, ...] = ()
    angle_deg: float | str = "auto"
    trigger: str = "distance"
    turnaround_m: float | None = None
    refly_90: bool = False
    blur_px: float = 1.0
    timing: Timing = Timing()
    target: Target | None = None
    camera_pitch_deg: float = 0.0
    profile: Any = None             # missions.thermal.pv.PvProfile, or None
    no_fly: tuple[Any, ...] = ()          # zones (missions.geometry.zones): inline points or file paths
    no_photo: tuple[Any, ...] = ()
    zone_margin_m: float | None = None    # None: zones.DEFAULT_ZONE_MARGIN_M


@dataclass(frozen=True)
class CorridorStep:
    index: int
    line: tuple[tuple[float, float], ...]
    width_m: float
    payloads: tuple[str, ...]
    front_pct: float
    side_pct: float
    altitude_m: float | None = None
    gsd_cm: float | None = None
    trigger: str = "distance"
    turnaround_m: float | None = None
    blur_px: float = 1.0
    timing: Timing = Timing()
    exclude: tuple[Any, ...] = ()
    no_fly: tuple[Any, ...] = ()
    no_photo: tuple[Any, ...] = ()
    zone_margin_m: float | None = None


@dataclass(frozen=True)
class WaypointStep:
    index: int
    lat: float
    lon: float
    alt_m: float
    hold_s: float = 0.0
    capture: str | None = None


@dataclass(frozen=True)
class CameraStep:
    index: int
    payload: str
    settings: tuple[tuple[str, Any], ...]
    values: tuple[tuple[str, float | int], ...]


@dataclass(frozen=True)
class RtlStep:
    index: int


@dataclass(frozen=True)
class LandStep:
    index: int
    lat: float | None = None
    lon: float | None = None


Step = TakeoffStep | SurveyStep | CorridorStep | WaypointStep | CameraStep | RtlStep | LandStep


@dataclass(frozen=True)
class Plan:
    version: int
    name: str
    vehicle: Vehicle
    home: Home
    payloads: tuple[Payload, ...]
    mission: tuple[Step, ...]
    path: str = "<plan>"
    base_dir: str = "."
    notes: tuple[str, ...] = ()          # decisions the loader took for the user (e.g. a moved component id)
    timing: Timing = Timing()            # `when` and `when_wind_mps` of the whole plan
    fence_margin_m: float | None = None  # `fence: {margin_m}`: an inclusion fence this far around the flight
    corridor_scan: bool = False          # `qgc: {corridor_scan: true}`: corridors as QGC CorridorScan items
    locations: Mapping[tuple, str] = field(default_factory=lambda: MappingProxyType({}), compare=False, repr=False)

    def payload(self, name: str) -> Payload:
        return next(p for p in self.payloads if p.name == name)

    def where(self, *path: Any) -> str:
        """file:line:col of the deepest located node on `path` (the file name when nothing is located)."""
        p = tuple(path)
        while p:
            if p in self.locations:
                return self.locations[p]
            p = p[:-1]
        return self.locations.get((), self.path)

    def step_where(self, step: Step, *path: Any) -> str:
        kind = _STEP_KIND[type(step)]
        return self.where("mission", step.index, kind, *path)


_STEP_KIND = {TakeoffStep: "takeoff", SurveyStep: "survey", CorridorStep: "corridor", WaypointStep: "waypoint",
              CameraStep: "camera", RtlStep: "rtl", LandStep: "land"}
