"""What the compiler hands to the outputs and the report: the emitted mission and everything needed to
check it, as frozen values.

The report re-derives photo positions from `items` (it never trusts the planner's intent); `areas` and
`payloads` give it what to measure against. `intent` keeps the planner's own geometry for previews only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from missions.emit.items import MissionItem


@dataclass(frozen=True)
class PlanWarning:
    """Something the pilot should know that does not stop the mission: `code` is stable (the report's JSON
    carries it), `message` says what and where."""

    code: str
    message: str

    def __str__(self) -> str:
        return f"{self.code}: {self.message}"


@dataclass(frozen=True)
class PayloadInfo:
    """A payload as the compiler resolved it from the plan and the catalogue."""

    name: str                       # the plan's payload name, e.g. "thermal"
    camera_id: str                  # catalogue id, e.g. "wiris-pro"
    imager: str                     # catalogue imager id, e.g. "thermal"
    component_id: int
    focal_mm: float
    sensor_mm: tuple[float, float]  # width, height of the image as flown (landscape unless portrait)
    resolution_px: tuple[int, int]
    landscape: bool = True          # long image side across track
    min_interval_s: float | None = None
    time_constant_ms: float | None = None   # thermal imagers: the blur budget's integration time (catalogue)
    time_constant_assumed: bool = False     # the catalogue marks it assumed (no datasheet value)

    def footprint_m(self, altitude_m: float) -> tuple[float, float]:
        """Ground footprint (across track, along track) in metres at `altitude_m` above ground, nadir."""
        w, h = self.sensor_mm
        across, along = (w, h) if self.landscape else (h, w)
        return across * altitude_m / self.focal_mm, along * altitude_m / self.focal_mm

    def gsd_cm(self, altitude_m: float) -> float:
        """Ground sample distance in cm/pixel at `altitude_m` (across-track pixels)."""
        w_px, h_px = self.resolution_px
        across_px = w_px if self.landscape else h_px
        return 100.0 * self.footprint_m(altitude_m)[0] / across_px


@dataclass(frozen=True)
class AreaInfo:
    """One survey or corridor step: what it must cover."""

    step: int                       # index of the step in the plan's mission list
    kind: str                       # "survey" | "corridor"
    payloads: tuple[str, ...]       # payload names; the first sets the lines
    area: Any                       # missions.geometry.area.Area (projected shapely geometry + projection)
    altitude_m: float               # above home
    front_overlap: float            # fraction 0..1 requested
    side_overlap: float
    trigger: str                    # "distance" | "interval" | "hover"
    trigger_distance_m: float | None = None
    # The items this step emitted: [first, end) indices into Compiled.items (the whole mission, not a part).
    # The report measures the step's overlaps, photo count and path against them; None (an AreaInfo built by
    # hand, without a mission) measures every photo and the whole path near the area.
    items: tuple[int, int] | None = None
    # The zones near the step (missions.geometry.zones.StepZones): the report's zone table and the coverable area.
    # None: no zone near it.
    zones: Any = None
    # The NAV items that end a leg of the step's lines (flying from a span's entry to its exit): a payload that
    # shoots by itself (a RedEdge in overlap mode, also on turnarounds and transits) has its overlaps measured
    # over the photos taken flying towards them. None: every photo of `items`.
    line_items: tuple[int, ...] | None = None


@dataclass(frozen=True)
class CaptureSize:
    """What each photo of one payload writes to the camera's storage during a step."""

    payload: str
    formats: str                    # the files each photo writes, e.g. "radiometric_jpeg + visible_jpeg"
    mb_per_photo: float | None      # megabytes (10^6 bytes); None: the catalogue knows no published size
    source: str                     # where the size comes from


@dataclass(frozen=True)
class StepFacts:
    """What the compiler chose for one survey or corridor step, as a pilot reads it; the report adds what it
    measures (photos, GSD range, storage, flight time)."""

    step: int                       # index in the plan's mission list
    kind: str                       # "survey" | "corridor"
    where: str                      # the step's file:line:col
    lead: str                       # the payload whose footprint sets the lines
    angle_deg: float | None         # line direction, degrees from north; None: a corridor follows its line
    angle_auto: bool                # the compiler chose the angle (angle_deg: auto)
    spacing_m: float                # between lines
    lines: int
    trigger: str                    # "distance" | "interval" | "hover"
    trigger_distance_m: float
    speed_mps: float                # planned speed along the lines
    footprint_m: tuple[float, float]    # the lead payload's, across and along track, at the step's altitude
    capture: tuple[CaptureSize, ...]    # per payload of the step
    assumptions: tuple[str, ...]        # every assumption the numbers rest on

    @property
    def photo_interval_s(self) -> float | None:
        """Seconds between photos at the planned speed (None when hovering: each photo is a stop)."""
        return None if self.trigger == "hover" else self.trigger_distance_m / self.speed_mps


@dataclass(frozen=True)
class TransectPattern:
    """A survey or corridor step as QGroundControl's pattern editor knows it (missions.formats.qgc_complex writes
    it as a ComplexItem around the items it emitted): the shape, the camera numbers that spaced its lines, and
    where its transect items are in Compiled.items."""

    kind: str                                   # "survey" | "corridor"
    items: tuple[int, int]                      # [first, end) of the transect items (the first waypoint on)
    payload: str                                # the payload whose optics set the lines
    altitude_m: float
    front_pct: float
    side_pct: float
    spacing_m: float                            # between lines
    trigger_distance_m: float
    turnaround_m: float
    hover: bool
    polygon: tuple[tuple[float, float], ...] = ()   # survey: the area's outer ring, (lat, lon)
    angle_deg: float = 0.0                      # survey: the lines' direction, degrees from north
    refly_90: bool = False
    line: tuple[tuple[float, float], ...] = ()  # corridor: the centre line, (lat, lon)
    width_m: float = 0.0                        # corridor


@dataclass(frozen=True)
class SetupStep:
    """One step of the pre-flight command sequence (NAME.setup.json)."""

    description: str
    target_component: int
    kind: str                                   # "command_long" | "param_ext_set" | "param_set" | "message"
    command: str | None = None                  # MAV_CMD name for command_long
    params: tuple[float | None, ...] = ()       # 7 values; None = NaN ("keep")
    param_id: str | None = None                 # for param_ext_set / param_set
    value: float | int | None = None
    type: str | None = None                     # CDF / MAV_PARAM_TYPE name of the value
    expect: str = "MAV_RESULT_ACCEPTED"         # or PARAM_ACK_ACCEPTED / PARAM_VALUE echo / UNACKNOWLEDGED
    payload: str = ""
    message: str | None = None                  # for "message": a MAVLink message name (DIGICAM_CONFIGURE)
    fields: tuple[tuple[str, int | float], ...] = ()   # its fields; those not given are sent as 0

    def to_json(self) -> dict:
        out: dict[str, Any] = {"description": self.description, "payload": self.payload,
                               "target_component": self.target_component, "kind": self.kind}
        if self.kind == "command_long":
            out["command"] = self.command
            out["params"] = list(self.params)
        elif self.kind == "message":
            out["message"] = self.message
            out["fields"] = dict(self.fields)
        else:
            out.update(param_id=self.param_id, value=self.value, type=self.type)
        out["expect"] = {"result": self.expect}
        return out


class FlightCache:
    """The re-flight of a Compiled, kept by `missions.measure.flight.simulate` so that the compile's own checks
    (battery, sun), the report and the outputs fly a mission once: a 100 km² survey's re-flight places ~660,000
    photos. It holds the values it was flown from and answers only while they are the very same objects, so a
    `dataclasses.replace` with other items (or home, payloads, setup, areas) flies again."""

    __slots__ = ("key", "sim")

    def __init__(self) -> None:
        self.key: tuple = ()
        self.sim: Any = None


@dataclass(frozen=True)
class Compiled:
    name: str
    firmware: str                               # "ardupilot" | "px4"
    frame: str                                  # "copter" | "plane" | "vtol"
    home: tuple[float, float, float]            # lat, lon, alt AMSL m
    speed_mps: float
    items: tuple[MissionItem, ...]              # the whole mission, no home row
    parts: tuple[tuple[MissionItem, ...], ...]  # `items` split at the item limit; (items,) when it fits
    item_limit: int
    payloads: tuple[PayloadInfo, ...]
    areas: tuple[AreaInfo, ...]
    setup: tuple[SetupStep, ...]
    lua: str | None = None                      # the ArduPilot bridge script, when in-flight changes need it
    params: tuple[tuple[str, float, str], ...] = ()   # autopilot parameters: name, value, why
    warnings: tuple[PlanWarning, ...] = ()
    intent: tuple[Any, ...] = field(default=(), compare=False)   # planner geometry, for previews only
    inputs: tuple[str, ...] = field(default=(), compare=False)   # the files the plan was read from (never written)
    sun: tuple[Any, ...] = ()                   # missions.thermal.assess.StepSun per timed step (plans with `when`)
    step_facts: tuple[StepFacts, ...] = ()      # per survey or corridor step, what the compiler chose
    patterns: tuple[TransectPattern, ...] = ()  # the surveys and corridors, for the .plan's ComplexItems
    corridor_scan: bool = False                 # write corridors as QGC CorridorScan (MAVSDK 4.1 cannot read them)
    fence: tuple[MissionItem, ...] = ()         # fence items (mission_type FENCE): exclusion zones, inclusion fence
    # missions.terrain.model.Terrain: the DEM the lines follow and the report measures over; None: flat ground
    terrain: Any = field(default=None, compare=False)
    # missions.sorties.Sortie per sortie when the mission is longer than a battery or the item limit (then
    # `parts` are their items); () when it is flown as one mission
    sorties: tuple[Any, ...] = field(default=(), compare=False)
    endurance: Any = field(default=None, compare=False)   # missions.sorties.Endurance the split used
    turn_radius_m: float | None = None          # a plane's or VTOL's (missions.geometry.turns); None: a copter
    flight_cache: FlightCache = field(default_factory=FlightCache, compare=False, repr=False)

    def payload(self, name: str) -> PayloadInfo:
        return next(p for p in self.payloads if p.name == name)
