"""The re-flight of a compiled mission: what the emitted items will really do, not what the planner meant.

    sim = simulate(compiled)        # flown path, photo positions, timeline — from compiled.items only

How the items are flown (the model, stated so it can be checked):
* Path: home (relative altitude 0) → every NAV item with a position, in mission order, following DO_JUMP
  with its repeat count. A NAV item at lat = lon = 0 means "here" (ArduPilot's convention, which PX4's
  takeoff and land share). Takeoff climbs vertically over the current position (both firmwares take off over
  the launch point). RTL climbs to RTL_ALT (ArduPilot's default 15 m) when lower, flies home and descends;
  LAND descends where it is. After RTL, LAND or LOITER_UNLIM nothing further is flown.
* A mission split into parts is measured as `compiled.items`, the whole flight: the parts reproduce it, each
  ending in a hold (LOITER_UNLIM) while the next one is uploaded; upload time is not in the flight time.
* Altitude: relative frames are above home; absolute (AMSL) frames are converted with home's AMSL altitude;
  terrain frames are taken as height above the ground (a warning says so). The ground is assumed flat at
  home's elevation here; with a DEM in the plan the report measures the photos over it instead
  (missions.terrain.reflight: heights above the ground below each photo, footprints cut by the terrain).
* Camera: DO commands execute when the vehicle leaves the previous NAV position, so a command takes effect
  at the path vertex it follows. DO_SET_CAM_TRIGG_DIST (on/off, param3 "trigger once") is re-run through
  `missions.geometry.triggers.simulate_distance_trigger`, which fires as ArduPilot's AP_Camera and PX4's
  camera_trigger do (straight-line distance from the last photo). ArduPilot checks it at 50 Hz, so it flies the
  distance rounded up to whole checks of travel, and measures it in its own metres (Location's sphere: 0.2 %
  longer than true east-west at 50° N, see missions.emit.trigger_distance). PX4 checks that distance every 50 ms and
  measures the next from where it fired, so it flies the spacing `px4_trigger_spacing_m` (half a check's
  travel longer), and it shoots once on every switch-on whatever param3 says. IMAGE_START_CAPTURE with one image,
  DO_DIGICAM_CONTROL(shoot) and a trigger-once take one photo there; IMAGE_START_CAPTURE with an interval
  takes photos by time along the simulated timeline until IMAGE_STOP_CAPTURE; so does PX4's interval trigger
  (DO_SET_CAM_TRIGG_INTERVAL sets the interval, DO_TRIGGER_CONTROL starts/pauses/stops it): camera_trigger's
  update_intervalometer schedules the first shot at once when enabled, then one every interval until a
  DO_TRIGGER_CONTROL stops it (measured: the first shot 60 ms after the item ran).
* Which camera: a photo from the autopilot's trigger (distance, interval, DIGICAM) fires the payloads the
  plan surveys with that the trigger reaches — on ArduPilot its camera instances (every payload but a RedEdge,
  which is no AP_Camera backend), on PX4 every camera component (camera_trigger over MAVLink).
  IMAGE_START_CAPTURE addresses param1: 0 = all reached payloads, 100..105 = the payload with that component
  id, 1..6 = camera instance n (the n-th non-RedEdge payload, as the compiler numbers them). A RedEdge that
  the setup puts in its own overlap mode shoots by itself (see `self_triggering`).
* Footprint: nadir, centred on the photo position, at the photo's altitude, rotated to the vehicle's heading
  — the direction of travel (ArduPilot's WP_YAW_BEHAVIOR default and PX4's MPC_YAW_MODE default) or, on PX4,
  the yaw of a NAV_WAYPOINT's param4 when it sets one (ArduPilot's AP_Mission does not store it). A hover photo
  keeps the heading the vehicle arrived with: from the waypoint before, or the waypoint's own yaw on PX4.
* Flight time: every segment is flown with a trapezoidal speed profile (acceleration ACCEL_MPS2, cruise
  speed from the plan or the last DO_CHANGE_SPEED). A multirotor slows at a corner to speed·cos(turn) (it
  stops at turns of 90° and more, at holds and where the path turns vertical); a plane keeps its speed, and
  so does a VTOL between its vertical take-off and landing (it flies the mission fixed-wing).
  A PX4 multicopter is timed at PX4_MC_TRACKED_SPEED_RATIO of the commanded speed (its position smoothing
  slows down while the vehicle lags it; measured in SITL). Climbs and descents are limited to CLIMB_MPS /
  DESCENT_MPS, the last LAND_FINAL_M of a landing to LAND_MPS. Holds (NAV_WAYPOINT param1 on multirotors, LOITER_TIME, NAV_DELAY) add their time.
  For comparison `flight_time_qgc_s` is QGroundControl's statistic (MissionController: horizontal distance /
  cruise speed + hold times, no acceleration, no climbs); Mission Planner shows distance / (0.8·speed).
  Our model is longer than QGC's on every survey with turns — that is the point of it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np

from cdf.catalogue import catalogue
from missions.compiled import Compiled
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, MissionItem, mavlink
from missions.geometry.geo import LocalProjection
from missions.geometry.survey import check_photo_budget
from missions.emit.firmware import PX4_ACCEPTANCE_M, PX4_TRIGGER_CHECK_S
from missions.geometry.turns import dubins_length_m
from missions.geometry.triggers import PhotoPoint, TriggerSpan, simulate_distance_trigger
from missions.emit.trigger_distance import AP_CAMERA_UPDATE_HZ, ApMetre, ardupilot_metre

# ArduCopter defaults (WPNAV_ACCEL 250 cm/s², WPNAV_SPEED_UP 250 cm/s, WPNAV_SPEED_DN 150 cm/s,
# LAND_SPEED 50 cm/s below LAND_ALT_LOW 10 m, RTL_ALT 15 m); PX4's multicopter defaults are close
# (MPC_ACC_HOR 3 m/s², MPC_Z_VEL_MAX_UP 3 m/s, MPC_Z_VEL_MAX_DN 1.5 m/s, MPC_LAND_SPEED 0.7 m/s).
ACCEL_MPS2 = 2.5
CLIMB_MPS = 2.5
DESCENT_MPS = 1.5
LAND_MPS = 0.5
LAND_FINAL_M = 10.0
RTL_ALT_M = 15.0
# PX4's multicopter flies its lines slower than the cruise speed it is given: its position smoothing slows the
# trajectory in proportion to how far the vehicle lags behind it (PositionSmoothing's time stretch against
# MPC_XY_ERR_MAX, 2 m), and a vehicle tracking a moving setpoint always lags a little. Measured in PX4 1.16 SITL
# (SIH quad, 5 m/s commanded): 95.8 m lines flown in 20.8-21.4 s with the trajectory's speed at 5.0 m/s and the
# vehicle at 4.0 rising to 4.95; timed at this ratio of the commanded speed the model gives 21.3 s.
# Only the timeline uses it (interval triggering, flight time); distance triggering is positional.
PX4_MC_TRACKED_SPEED_RATIO = 0.9
# A DO_JUMP loop is followed at most this many items: an infinite repeat is reported, not simulated forever.
MAX_SIMULATED_ITEMS = 2_000_000

INT_FRAMES = {mavlink.MAV_FRAME_GLOBAL_INT: FRAME_GLOBAL,
              mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: FRAME_GLOBAL_RELATIVE_ALT,
              mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: FRAME_GLOBAL_TERRAIN_ALT}

C = mavlink   # command numbers below come from pymavlink's dialect (common.xml + ardupilotmega.xml)
NAV_POSITION = {C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_SPLINE_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME,
                C.MAV_CMD_NAV_LOITER_TURNS, C.MAV_CMD_NAV_LOITER_TO_ALT}
NAV_TAKEOFF = {C.MAV_CMD_NAV_TAKEOFF, C.MAV_CMD_NAV_VTOL_TAKEOFF}
NAV_LAND = {C.MAV_CMD_NAV_LAND, C.MAV_CMD_NAV_VTOL_LAND}


# ArduPlane's navigate task (Plane.cpp scheduler table: SCHED_TASK(navigate, 10, ...)) runs the mission, its
# waypoint checks and the DO items after a waypoint, at 10 Hz: DO_SET_CAM_TRIGG_DIST after a line's entry (its
# first photo) and after its exit come up to 0.1 s of flight after the plane passes the waypoint.
ARDUPLANE_NAV_HZ = 10.0


@dataclass(frozen=True)
class Vertex:
    """One point of the flown path (x/y metres in the simulation's projection, altitude above home)."""

    x: float
    y: float
    alt_m: float
    item: int                 # index into compiled.items of the NAV item that put it there; -1 for home
    hold_s: float = 0.0
    stop: bool = False        # the vehicle comes to rest here (hold, start, end, vertical turn)
    yaw_deg: float | None = None    # commanded heading: degrees from true north in the walk, in the plane after it
    speed_mps: float = 0.0    # cruise speed of the segment that ends here


class Photo(NamedTuple):
    """One re-derived photo. A NamedTuple (immutable, ~10x cheaper to build than a frozen dataclass): a 100 km²
    survey has ~10^6 of them."""

    x: float
    y: float
    lat: float
    lon: float
    alt_m: float              # above home
    heading_deg: float
    payloads: tuple[str, ...]
    span: int                 # photos of one camera-on stretch share it (front overlap pairs)
    cause: int                # index into compiled.items of the command that took it; -1: the camera's own mode
    time_s: float
    # index into compiled.items of the NAV item the vehicle was executing when it took the photo: the one it flew
    # towards, or held at for a photo taken standing (the step whose items hold it took the photo)
    item: int


@dataclass(frozen=True)
class Simulation:
    vertices: tuple[Vertex, ...]
    latlon: tuple[tuple[float, float], ...]    # of each vertex
    photos: tuple[Photo, ...]
    projection: Any                            # missions.geometry.geo.LocalProjection
    path_length_m: float                       # horizontal
    climb_m: float
    flight_time_s: float
    flight_time_qgc_s: float
    vertex_times_s: tuple[float, ...]          # arrival time at each vertex
    trigger_intervals: tuple[TriggerInterval, ...] = ()
    notes: tuple[Note, ...] = ()               # found while simulating
    ends_on_ground: bool = False
    camera_on: tuple[CameraOn, ...] = ()       # stretches flown with distance or interval triggering on

    @property
    def xy(self) -> np.ndarray:
        return np.array([(v.x, v.y) for v in self.vertices], dtype=float).reshape(-1, 2)


# --------------------------------------------------------------------------------------------- simulation

def _altitude(it: MissionItem, home_amsl: float, current: float) -> tuple[float, bool]:
    """Altitude above home of a NAV item and whether it is terrain-relative."""
    frame = INT_FRAMES.get(it.frame, it.frame)
    if frame == FRAME_GLOBAL:
        return it.z - home_amsl, False
    if frame == FRAME_GLOBAL_TERRAIN_ALT:
        return it.z, True
    if frame == FRAME_GLOBAL_RELATIVE_ALT:
        return it.z, False
    return current, False


def _heading(dx: float, dy: float) -> float:
    return math.degrees(math.atan2(dx, dy)) % 360.0


def _protocol(camera_id: str) -> str:
    try:
        return catalogue().get(camera_id).protocol
    except Exception:   # an id the catalogue does not know cannot come out of the compiler; stay neutral
        return ""


def _mavlink_cameras(compiled: Compiled) -> list[str]:
    """Payloads the autopilot drives as camera instances 1..n (ArduPilot CAMn): every one but the RedEdge,
    which is not an AP_Camera backend (it listens to the serial API only)."""
    return [p.name for p in compiled.payloads if _protocol(p.camera_id) != "rededge-serial"]


def _payload_for_target(compiled: Compiled, target: float) -> tuple[str, ...]:
    t = int(target) if math.isfinite(target) else 0
    if t == 0:
        return tuple(_reached_by_trigger(compiled, [p.name for p in compiled.payloads]))
    if 1 <= t <= 6:
        cams = _mavlink_cameras(compiled)
        if compiled.firmware == "ardupilot":
            # CAMn is the camera at component 100 + n - 1 (MAVLinkCamV2 looks nowhere else; the compiler numbers
            # instances so): a WIRIS alone at 101 is CAM2
            return tuple(n for n in cams if compiled.payload(n).component_id == C.MAV_COMP_ID_CAMERA + t - 1)
        return (cams[t - 1],) if t <= len(cams) else ()
    return tuple(p.name for p in compiled.payloads if p.component_id == t)


def _reached_by_trigger(compiled: Compiled, names: Sequence[str]) -> list[str]:
    """Which of `names` the autopilot's own triggering reaches. ArduPilot triggers its camera instances only;
    PX4's camera_trigger with TRIG_INTERFACE 3 sends IMAGE_START_CAPTURE and DO_DIGICAM_CONTROL to every
    component 100..105, the RedEdge included."""
    if compiled.firmware == "ardupilot":
        cams = set(_mavlink_cameras(compiled))
        return [n for n in names if n in cams]
    return list(names)


def self_triggering(compiled: Compiled) -> dict[str, tuple[float, float, float]]:
    """Payloads the setup puts in a capture mode of their own: name -> (altitude, tolerance, front overlap %).

    A RedEdge in overlap mode (autoCapMode 2, MicaSense's recommended mode) shoots from its own GPS whenever it
    is no more than opAltTolerance below operatingAlt (higher is fine: "when the sensor's altitude is below the
    Target Altitude Tolerance from the Target Altitude, the sensor stops capturing", RedEdge-MX Integration
    Guide) and has moved (1 − overlapAlongTrk) of a footprint, taken here at operatingAlt: the autopilot's
    trigger commands do not reach it, so its photos follow the path and altitude, not the trigger items.
    """
    params: dict[str, dict[str, float]] = {}
    for st in compiled.setup:
        if st.kind == "param_set" and st.param_id and st.value is not None:
            params.setdefault(st.payload, {})[st.param_id] = float(st.value)
    out = {}
    for name, pv in params.items():
        if int(pv.get("autoCapMode", -1)) == 2 and "operatingAlt" in pv:
            out[name] = (pv["operatingAlt"], pv.get("opAltTolerance", 5.0), pv.get("overlapAlongTrk", 75.0))
    return out


def _trigger_payloads(compiled: Compiled) -> tuple[str, ...]:
    own = self_triggering(compiled)
    names: list[str] = []
    for a in compiled.areas:
        for n in a.payloads:
            if n not in names and n not in own:
                names.append(n)
    if not compiled.areas:
        names = [p.name for p in compiled.payloads if p.name not in own]
    return tuple(_reached_by_trigger(compiled, names))


def _projection(compiled: Compiled):
    """The first area's own projection when there is one (so photos and area share one plane: runs of photos
    stay exactly collinear for the overlap measurement); else one centred on home and every item."""
    if compiled.areas:
        return compiled.areas[0].area.projection
    lats = [compiled.home[0]]
    lons = [compiled.home[1]]
    for it in compiled.items:
        if it.frame != mavlink.MAV_FRAME_MISSION and (it.x or it.y):
            lats.append(it.lat)
            lons.append(it.lon)
    return LocalProjection.centred_on(lats, lons)


# --------------------------------------------------------------------------------------------- camera records

class SinglePhoto(NamedTuple):
    """One photo commanded at a path vertex (IMAGE_START_CAPTURE of one image, DIGICAM shot, trigger once)."""

    vertex: int
    payloads: tuple[str, ...]
    item: int                 # index into compiled.items of the command that took it


class DistanceSpan(NamedTuple):
    """Distance triggering on from vertex `start` to vertex `end`."""

    start: int
    end: int
    distance_m: float
    shoot_at_start: bool      # DO_SET_CAM_TRIGG_DIST param3 "trigger once" when switching on
    shoot_at_stop: bool       # ... and when switching off
    item: int                 # the DO_SET_CAM_TRIGG_DIST that switched it on


class IntervalSpan(NamedTuple):
    """Time-interval triggering on from vertex `start` to vertex `end`."""

    start: int
    end: int
    interval_s: float
    payloads: tuple[str, ...]
    count: int                # images to take, 0 = until stopped
    item: int                 # the command that started it


class _DistanceOn(NamedTuple):
    """Distance triggering switched on and not yet off."""

    start: int
    distance_m: float
    shoot_at_start: bool
    item: int

    def until(self, end: int, shoot_at_stop: bool) -> DistanceSpan:
        return DistanceSpan(self.start, end, self.distance_m, self.shoot_at_start, shoot_at_stop, self.item)


class _IntervalOn(NamedTuple):
    """Interval triggering started and not yet stopped."""

    start: int
    interval_s: float
    payloads: tuple[str, ...]
    count: int
    item: int

    def until(self, end: int) -> IntervalSpan:
        return IntervalSpan(self.start, end, self.interval_s, self.payloads, self.count, self.item)


class TriggerInterval(NamedTuple):
    """How often one payload is triggered over one camera-on span."""

    payload: str
    value: float              # the trigger's own value: metres (distance) or seconds (interval)
    seconds: float            # between photos at the cruise speed
    item: int                 # the command that switched it on; -1: the camera's own mode


class Note(NamedTuple):
    """Something found while flying the items that the report turns into a warning."""

    code: str
    message: str


class CameraOn(NamedTuple):
    """A stretch flown with distance or interval triggering on: from path vertex `start` to vertex `end`, so the
    path segments `start` .. `end - 1` (a slice of the segments, as of the vertices)."""

    start: int
    end: int


# --------------------------------------------------------------------------------------------- flying the items

class _Flight:
    """The state of one re-flight of `compiled.items` (local to `simulate`, never shared): the path flown so far,
    the camera commands met, and the handlers that fly each MAV_CMD (`_HANDLERS`)."""

    def __init__(self, compiled: Compiled) -> None:
        self.compiled = compiled
        self.items = compiled.items
        self.proj = _projection(compiled)
        home_lat, home_lon, self.home_amsl = compiled.home
        self.hx, self.hy = self.proj.point_to_xy(home_lat, home_lon)
        # A VTOL takes off and lands vertically but flies its mission fixed-wing (hover triggering is refused
        # for it): between take-off and landing it keeps its speed through turns and ignores holds, like a plane.
        self.copter = compiled.frame == "copter"
        self.vertical = compiled.frame in ("copter", "vtol")
        self.ardupilot = compiled.firmware == "ardupilot"
        self.seq_base = 1 if self.ardupilot else 0      # ArduPilot numbers the mission from 1 (seq 0 is home)
        self.speed = float(compiled.speed_mps)
        self.trigger_payloads = _trigger_payloads(compiled)
        self.has_trigger_control = any(it.command == C.MAV_CMD_DO_TRIGGER_CONTROL for it in self.items)
        self.verts: list[Vertex] = [Vertex(self.hx, self.hy, 0.0, -1, stop=True)]
        self.singles: list[SinglePhoto] = []
        self.distance_spans: list[DistanceSpan] = []
        self.interval_spans: list[IntervalSpan] = []
        self.notes: list[Note] = []
        self.distance_on: _DistanceOn | None = None
        self.interval_on: _IntervalOn | None = None
        self.interval_s = 0.0                      # PX4's DO_SET_CAM_TRIGG_INTERVAL, started by DO_TRIGGER_CONTROL
        self.jumps: dict[int, int] = {}            # DO_JUMP index -> times taken
        self.terrain_items: list[int] = []
        self.ended = False
        self.on_ground = False

    # -- the walk

    def fly(self) -> None:
        """Execute the items in mission order; a handler may return the next index (DO_JUMP)."""
        i = 0
        steps = 0
        while i < len(self.items):
            steps += 1
            if steps > MAX_SIMULATED_ITEMS:
                self.notes.append(Note("jump_loop",
                                       f"DO_JUMP loops were followed for {MAX_SIMULATED_ITEMS} items and cut off"))
                break
            it = self.items[i]
            handler = _HANDLERS.get(it.command)
            nxt = handler(self, i, it) if handler is not None else None
            if self.ended:
                break
            i = i + 1 if nxt is None else nxt
        self._close_open_spans()

    def _close_open_spans(self) -> None:
        last = len(self.verts) - 1
        if self.distance_on is not None:
            self.distance_spans.append(self.distance_on.until(last, False))
            self.notes.append(Note("trigger_left_on", f"item {self.distance_on.item + self.seq_base}: "
                                                      "distance triggering is never switched off"))
        if self.interval_on is not None:
            self.interval_spans.append(self.interval_on.until(last))
        if self.terrain_items:
            self.notes.append(Note("terrain_frame",
                                   f"{len(self.terrain_items)} items use the terrain frame: heights are taken "
                                   "as above ground; footprints assume the autopilot follows terrain"))

    # -- path helpers

    @property
    def here(self) -> Vertex:
        return self.verts[-1]

    @property
    def last_vertex(self) -> int:
        return len(self.verts) - 1

    def add(self, x: float, y: float, alt: float, item: int, hold: float = 0.0, stop: bool = False,
            yaw: float | None = None, spd: float | None = None) -> None:
        self.verts.append(Vertex(x, y, alt, item, hold, stop or hold > 0, yaw, spd if spd is not None else self.speed))

    def _xy(self, it: MissionItem) -> tuple[bool, float, float]:
        """Whether the item means "here" (lat = lon = 0), and the plane position it flies to."""
        here = not (it.x or it.y)
        c = self.here
        x, y = (c.x, c.y) if here else self.proj.point_to_xy(it.lat, it.lon)
        return here, x, y

    def _target(self, i: int, it: MissionItem) -> tuple[bool, float, float, float]:
        """`_xy` and the item's altitude above home; terrain-frame items are counted for the note."""
        here, x, y = self._xy(it)
        alt, terrain = _altitude(it, self.home_amsl, self.here.alt_m)
        if terrain:
            self.terrain_items.append(i)
        return here, x, y, alt

    # -- NAV handlers

    def takeoff(self, i: int, it: MissionItem) -> None:
        here, x, y, alt = self._target(i, it)
        c = self.here
        self.on_ground = False
        self.add(c.x, c.y, alt, i, stop=True, spd=CLIMB_MPS)
        # a PX4 plane flies on to the take-off's position once it is up; what takes off vertically climbs over
        # where it stands
        if not here and not self.ardupilot and math.hypot(x - c.x, y - c.y) > 1.0 and not self.vertical:
            self.add(x, y, alt, i)

    def waypoint(self, i: int, it: MissionItem) -> None:
        _, x, y, alt = self._target(i, it)
        hold = 0.0
        if it.command == C.MAV_CMD_NAV_WAYPOINT and self.copter:
            hold = max(0.0, it.param1)
        elif it.command == C.MAV_CMD_NAV_LOITER_TIME:
            hold = max(0.0, it.param1)
        # PX4 flies a waypoint's yaw (param4) as the heading to hold; ArduPilot does not even store it
        pins_yaw = it.command == C.MAV_CMD_NAV_WAYPOINT and math.isfinite(it.param4) and self.copter \
            and not self.ardupilot
        self.add(x, y, alt, i, hold=hold, yaw=it.param4 if pins_yaw else None)

    def return_to_launch(self, i: int, it: MissionItem) -> None:
        self._target(i, it)
        c = self.here
        rtl_alt = max(c.alt_m, RTL_ALT_M)
        if rtl_alt > c.alt_m + 0.01:
            self.add(c.x, c.y, rtl_alt, i, stop=True, spd=CLIMB_MPS)
        self.add(self.hx, self.hy, rtl_alt, i, stop=True)
        self.add(self.hx, self.hy, 0.0, i, stop=True)
        self.ended = self.on_ground = True

    def land(self, i: int, it: MissionItem) -> None:
        _, x, y, _alt = self._target(i, it)
        c = self.here
        if math.hypot(x - c.x, y - c.y) > 0.01:
            self.add(x, y, c.alt_m, i, stop=True)
        self.add(x, y, 0.0, i, stop=True)
        self.ended = self.on_ground = True

    def loiter_unlimited(self, i: int, it: MissionItem) -> None:
        _, x, y = self._xy(it)
        alt, _ = _altitude(it, self.home_amsl, self.here.alt_m)
        self.add(x, y, alt, i, stop=True)
        self.notes.append(Note("loiter_unlimited",
                               f"item {i + self.seq_base}: LOITER_UNLIM — the mission never ends by itself"))
        self.ended = True

    def delay(self, i: int, it: MissionItem) -> None:
        c = self.here
        self.verts[-1] = replace(c, hold_s=c.hold_s + max(0.0, it.param1), stop=True)

    # -- DO handlers

    def change_speed(self, i: int, it: MissionItem) -> None:
        if it.param2 > 0:
            self.speed = float(it.param2)

    def jump(self, i: int, it: MissionItem) -> int | None:
        target = int(it.param1) - self.seq_base
        repeat = int(it.param2)
        done = self.jumps.get(i, 0)
        if repeat < 0:
            self.notes.append(Note("jump_forever", f"item {i + self.seq_base}: DO_JUMP repeats forever; followed once"))
            repeat = 1
        if 0 <= target < len(self.items) and done < repeat:
            self.jumps[i] = done + 1
            return target
        return None

    def trigger_distance(self, i: int, it: MissionItem) -> None:
        vi = self.last_vertex
        trigger_once = it.param3 == 1
        if self.distance_on is not None:
            self.distance_spans.append(self.distance_on.until(vi, it.param1 <= 0 and trigger_once))
            self.distance_on = None
        elif trigger_once and it.param1 <= 0:
            self.singles.append(SinglePhoto(vi, self.trigger_payloads, i))
        if it.param1 > 0:
            self.distance_on = _DistanceOn(vi, self._fired_distance(float(it.param1)), trigger_once, i)

    def _fired_distance(self, d: float) -> float:
        """The spacing the firmware's distance trigger really gives. ArduPilot checks the distance from the last
        photo in AP_Camera_Backend::update() at 50 Hz and shoots at the first check at or past `d`, so each photo
        comes up to one check's travel late and the next is measured from there: the spacing is `d` rounded up
        to whole 50 Hz steps of travel at the cruise speed (measured in SITL: powerline-corridor at 6 m/s,
        d = 6.872 m -> 6.96 m, 870 photos taken where exact spacing predicts 882). The spacing is in ArduPilot's
        metres: `_fire` turns it into true metres along the path. A plane's is arduplane_trigger_spacing_m."""
        if not self.ardupilot:
            return d
        return ardupilot_trigger_spacing_m(d, self.speed) if self.copter else arduplane_trigger_spacing_m(d, self.speed)

    def image_start(self, i: int, it: MissionItem) -> None:
        vi = self.last_vertex
        targets = _payload_for_target(self.compiled, it.param1)
        count = int(it.param3) if math.isfinite(it.param3) else 0
        interval = it.param2 if math.isfinite(it.param2) else 0.0
        if count == 1 or interval <= 0:
            self.singles.append(SinglePhoto(vi, targets, i))
            return
        if self.interval_on is not None:
            self.interval_spans.append(self.interval_on.until(vi))
        self.interval_on = _IntervalOn(vi, float(interval), targets, count, i)

    def image_stop(self, i: int, it: MissionItem) -> None:
        self._stop_interval()

    def trigger_interval(self, i: int, it: MissionItem) -> None:
        # PX4 (TRIG_MODE 1 "time based, on command"): this sets the interval; DO_TRIGGER_CONTROL starts and
        # stops it. A mission without DO_TRIGGER_CONTROL is taken to start shooting here.
        if it.param1 > 0:
            self.interval_s = it.param1 / 1000.0
        if not self.has_trigger_control:
            self._stop_interval()
            if it.param1 > 0:
                self.interval_on = _IntervalOn(self.last_vertex, self.interval_s, self.trigger_payloads, 0, i)

    def trigger_control(self, i: int, it: MissionItem) -> None:
        start = it.param1 == 1 or (it.param1 < 0 and it.param3 == 0)
        stop = it.param1 == 0 or it.param3 == 1
        if stop and self.interval_on is not None:
            self._stop_interval()
        elif start and self.interval_on is None and self.interval_s > 0:
            self.interval_on = _IntervalOn(self.last_vertex, self.interval_s, self.trigger_payloads, 0, i)

    def digicam_control(self, i: int, it: MissionItem) -> None:
        # param5 "Shot": 1 takes a photo (frame MISSION keeps it in x), whether or not DO_TRIGGER_CONTROL
        # has stopped the trigger: PX4's camera_trigger fires a one-shot without looking at its enabled
        # state (CameraTrigger::Run, "One shot command-based capture handling", read at PX4-Autopilot master
        # 7704fe75; the v1.16.0 tag the project's PX4 SITL runs could not be read here, nor was this flown on it)
        if it.x == 1:
            self.singles.append(SinglePhoto(self.last_vertex, self.trigger_payloads, i))

    def _stop_interval(self) -> None:
        if self.interval_on is not None:
            self.interval_spans.append(self.interval_on.until(self.last_vertex))
            self.interval_on = None


# One handler per MAV_CMD; commands not listed (speed-neutral DO items, camera set-up) do not change the flight.
_HANDLERS: dict[int, Callable[[_Flight, int, MissionItem], int | None]] = {
    **{cmd: _Flight.takeoff for cmd in NAV_TAKEOFF},
    **{cmd: _Flight.waypoint for cmd in NAV_POSITION},
    **{cmd: _Flight.land for cmd in NAV_LAND},
    C.MAV_CMD_NAV_RETURN_TO_LAUNCH: _Flight.return_to_launch,
    C.MAV_CMD_NAV_LOITER_UNLIM: _Flight.loiter_unlimited,
    C.MAV_CMD_NAV_DELAY: _Flight.delay,
    C.MAV_CMD_CONDITION_DELAY: _Flight.delay,
    C.MAV_CMD_DO_CHANGE_SPEED: _Flight.change_speed,
    C.MAV_CMD_DO_JUMP: _Flight.jump,
    C.MAV_CMD_DO_SET_CAM_TRIGG_DIST: _Flight.trigger_distance,
    C.MAV_CMD_IMAGE_START_CAPTURE: _Flight.image_start,
    C.MAV_CMD_IMAGE_STOP_CAPTURE: _Flight.image_stop,
    C.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL: _Flight.trigger_interval,
    C.MAV_CMD_DO_TRIGGER_CONTROL: _Flight.trigger_control,
    C.MAV_CMD_DO_DIGICAM_CONTROL: _Flight.digicam_control,
}


def _flown_from(compiled: Compiled) -> tuple:
    return (compiled.items, compiled.home, compiled.frame, compiled.firmware, compiled.payloads, compiled.setup,
            compiled.areas, compiled.speed_mps)


def simulate(compiled: Compiled) -> Simulation:
    """Fly `compiled.items` in the model above; return path, photos and times. Flown once per Compiled value
    (`FlightCache`): asked again for the same items, it answers with the same Simulation."""
    cache = getattr(compiled, "flight_cache", None)
    key = _flown_from(compiled)
    if cache is not None and len(cache.key) == len(key) and all(a is b for a, b in zip(cache.key, key)):
        return cache.sim
    sim = _simulate(compiled)
    if cache is not None:
        cache.key, cache.sim = key, sim
    return sim


def _simulate(compiled: Compiled) -> Simulation:
    flight = _Flight(compiled)
    flight.fly()
    proj = flight.proj
    verts = _yaws_in_plane(_mark_stops(flight.verts, flight.copter), proj)
    times = _timeline(_px4_tracked(verts) if flight.copter and compiled.firmware == "px4" else verts,
                      flight.copter, None if flight.copter else compiled.turn_radius_m)
    photos = _photos(compiled, verts, times, flight, proj)
    xy = np.array([(v.x, v.y) for v in verts], dtype=float)
    seg = np.hypot(*np.diff(xy, axis=0).T) if len(xy) > 1 else np.zeros(0)
    dz = np.diff([v.alt_m for v in verts]) if len(verts) > 1 else np.zeros(0)
    lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
    spans = [*flight.distance_spans, *flight.interval_spans]
    return Simulation(
        vertices=tuple(verts), latlon=tuple(zip(lat.tolist(), lon.tolist())), photos=tuple(photos), projection=proj,
        path_length_m=float(seg.sum()), climb_m=float(np.clip(dz, 0, None).sum()),
        flight_time_s=float(times[-1] + verts[-1].hold_s), flight_time_qgc_s=_qgc_flight_time(compiled, verts, seg),
        vertex_times_s=tuple(times.tolist()), trigger_intervals=tuple(_trigger_intervals(compiled, flight, verts)),
        notes=tuple(flight.notes), ends_on_ground=flight.on_ground,
        camera_on=tuple(CameraOn(s.start, s.end) for s in spans))


def _px4_tracked(verts: Sequence[Vertex]) -> list[Vertex]:
    """The vertices at the speed a PX4 multicopter really flies for the speed commanded
    (PX4_MC_TRACKED_SPEED_RATIO)."""
    return [replace(v, speed_mps=v.speed_mps * PX4_MC_TRACKED_SPEED_RATIO) for v in verts]


def _qgc_flight_time(compiled: Compiled, verts: Sequence[Vertex], seg: np.ndarray) -> float:
    """QGroundControl's statistic (MissionController): horizontal distance / cruise speed + holds, take-offs not
    counted as distance, no acceleration and no climbs."""
    items = compiled.items
    holds = sum(v.hold_s for v in verts)
    return float(sum(seg[k] / max(verts[k + 1].speed_mps or compiled.speed_mps, 0.1) for k in range(len(seg))
                     if verts[k + 1].item < 0 or items[verts[k + 1].item].command not in NAV_TAKEOFF) + holds)


def _yaws_in_plane(verts: list[Vertex], proj: Any) -> list[Vertex]:
    """Commanded yaws (degrees from true north) as headings in the simulation's plane."""
    ks = [k for k, v in enumerate(verts) if v.yaw_deg is not None]
    if not ks:
        return verts
    hd = proj.plane_headings([verts[k].x for k in ks], [verts[k].y for k in ks], [verts[k].yaw_deg for k in ks])
    out = list(verts)
    for k, h in zip(ks, hd.tolist()):
        v = verts[k]
        out[k] = Vertex(v.x, v.y, v.alt_m, v.item, v.hold_s, v.stop, h, v.speed_mps)
    return out


def _mark_stops(verts: list[Vertex], copter: bool) -> list[Vertex]:
    out = list(verts)
    n = len(out)
    for k in range(n):
        v = out[k]
        stop = v.stop or k == 0 or k == n - 1
        if not stop and 0 < k < n - 1:
            a, b = out[k - 1], out[k + 1]
            h_in = math.hypot(v.x - a.x, v.y - a.y)
            h_out = math.hypot(b.x - v.x, b.y - v.y)
            # a vertical leg on either side: the vehicle stops to change between climbing and cruising
            if (h_in < 0.01 and abs(v.alt_m - a.alt_m) > 0.01) or (h_out < 0.01 and abs(b.alt_m - v.alt_m) > 0.01):
                stop = True
        if stop != v.stop:
            out[k] = Vertex(v.x, v.y, v.alt_m, v.item, v.hold_s, stop, v.yaw_deg, v.speed_mps)
    return out


def _corner_speeds(verts: Sequence[Vertex], copter: bool) -> np.ndarray:
    n = len(verts)
    vc = np.zeros(n)
    for k in range(1, n - 1):
        v = verts[k]
        cruise = min(v.speed_mps, verts[k + 1].speed_mps)
        if v.stop:
            continue
        if not copter:
            vc[k] = cruise
            continue
        a, b = verts[k - 1], verts[k + 1]
        d1 = np.array([v.x - a.x, v.y - a.y])
        d2 = np.array([b.x - v.x, b.y - v.y])
        n1, n2 = np.hypot(*d1), np.hypot(*d2)
        if n1 < 1e-6 or n2 < 1e-6:
            vc[k] = cruise
            continue
        cos_turn = float(d1 @ d2) / (n1 * n2)
        vc[k] = cruise * max(0.0, cos_turn)
    return vc


def _segment_time(L: float, v0: float, v1: float, vmax: float, a: float) -> float:
    """Time over L metres starting at v0, ending at v1, cruising at most vmax, accelerating at a."""
    if L <= 1e-9:
        return 0.0
    vmax = max(vmax, 0.1)
    d_acc = max(0.0, (vmax ** 2 - v0 ** 2) / (2 * a))
    d_dec = max(0.0, (vmax ** 2 - v1 ** 2) / (2 * a))
    if d_acc + d_dec <= L:
        return (vmax - v0) / a + (vmax - v1) / a + (L - d_acc - d_dec) / vmax
    vp = math.sqrt(max((2 * a * L + v0 ** 2 + v1 ** 2) / 2.0, max(v0, v1) ** 2))
    return max(0.0, (vp - v0) / a) + max(0.0, (vp - v1) / a)


def turn_lengths(verts: Sequence[Vertex], radius_m: float | None) -> np.ndarray:
    """The horizontal length flown over each segment: straight for a copter (radius None). A plane flies each
    segment as the Dubins path at its turn radius (missions.geometry.turns) between the headings it holds at the
    two ends: along the segment leaving a vertex when that segment is at least a radius long (it lines up with a
    flight line, a run-in, a long connection), else towards the next vertex whose leaving segment is (short
    connection stubs are flown through, not lined up with). So a corner between long segments is an arc flown
    ahead of the waypoint, and a turnaround onto a line closer than two radii is the loop a plane really flies.
    Segments from or onto a standstill (a vertical take-off, a landing) stay straight."""
    xy = np.array([(v.x, v.y) for v in verts], dtype=float).reshape(-1, 2)
    straight = np.hypot(*np.diff(xy, axis=0).T) if len(verts) > 1 else np.zeros(0)
    L = straight.copy()
    n = len(verts)
    if not radius_m or n < 3:
        return L
    heading = np.zeros(n)
    nxt = n - 1
    for k in range(n - 2, -1, -1):
        if straight[k] >= radius_m or verts[k + 1].stop:
            nxt = k
        d = xy[nxt + 1 if nxt == k else nxt] - xy[k]
        if math.hypot(*d) < 1e-6:
            d = xy[k + 1] - xy[k]
        heading[k] = _heading(*d) if math.hypot(*d) > 1e-6 else (heading[k + 1] if k + 1 < n else 0.0)
    heading[n - 1] = heading[n - 2]
    for k in range(1, n - 1):
        if straight[k] < 1e-6 or verts[k].stop or verts[k + 1].stop or straight[k - 1] < 1e-6:
            continue
        if abs((heading[k + 1] - heading[k] + 180.0) % 360.0 - 180.0) < 0.1 and \
                abs((heading[k] - _heading(*(xy[k + 1] - xy[k])) + 180.0) % 360.0 - 180.0) < 0.1:
            continue
        L[k] = max(straight[k], dubins_length_m(tuple(xy[k]), float(heading[k]), tuple(xy[k + 1]),
                                                float(heading[k + 1]), radius_m))
    return L


def _timeline(verts: Sequence[Vertex], copter: bool, radius_m: float | None = None) -> np.ndarray:
    """Arrival time at each vertex (holds at a vertex are spent after arriving)."""
    n = len(verts)
    vc = _corner_speeds(verts, copter)
    a = ACCEL_MPS2 if copter else 2.0 * ACCEL_MPS2
    L = turn_lengths(verts, radius_m)
    # speeds a vehicle can actually reach at the vertices given the segment lengths (forward/backward pass)
    for k in range(1, n):
        vc[k] = min(vc[k], math.sqrt(vc[k - 1] ** 2 + 2 * a * L[k - 1]))
    for k in range(n - 2, -1, -1):
        vc[k] = min(vc[k], math.sqrt(vc[k + 1] ** 2 + 2 * a * L[k]))
    t = np.zeros(n)
    for k in range(n - 1):
        p, q = verts[k], verts[k + 1]
        th = _segment_time(float(L[k]), vc[k], vc[k + 1], q.speed_mps, a)
        dz = q.alt_m - p.alt_m
        if dz > 0:
            tv = dz / CLIMB_MPS
        elif q.alt_m <= 0.01 < p.alt_m:        # a landing: the last metres at landing speed
            final = min(-dz, LAND_FINAL_M)
            tv = (-dz - final) / DESCENT_MPS + final / LAND_MPS
        else:
            tv = -dz / DESCENT_MPS
        t[k + 1] = t[k] + p.hold_s + max(th, tv)
    return t

# A PX4 fixed-wing reaches a waypoint, and runs the DO items after it, at the larger of NAV_ACC_RAD (10 m in
# rc.fw_defaults) and the acceptance radius its position controller publishes: NPFG's switch distance,
# NPFG_SW_DST_MLT x the track-error bound (ground speed x NPFG_PERIOD x NPFG_DAMPING), all PX4 defaults. Measured
# in PX4 1.16 SITL (sihsim_airplane): acceptance_radius 28.5-32.1 m at 12.7-14.3 m/s ground speed, the plane
# flying its lines at 13.8 m/s for DO_CHANGE_SPEED 15 (true airspeed 13.7 m/s, no wind).
PX4_FW_NAV_ACC_RAD_M = 10.0
PX4_NPFG_SWITCH_S = 0.32 * 10.0 * 0.7          # NPFG_SW_DST_MLT x NPFG_PERIOD x NPFG_DAMPING: 2.24 s of travel
PX4_FW_GROUND_SPEED_RATIO = 0.92


def px4_do_item_lead_m(frame: str, speed_mps: float) -> float:
    """How far before a waypoint PX4 counts it reached and runs the DO items after it: NAV_ACC_RAD on a
    multicopter, NPFG's switch distance at the ground speed it flies for `speed_mps` on a fixed-wing."""
    if frame == "copter":
        return PX4_ACCEPTANCE_M
    return max(PX4_FW_NAV_ACC_RAD_M, PX4_NPFG_SWITCH_S * PX4_FW_GROUND_SPEED_RATIO * speed_mps)


# --------------------------------------------------------------------------------------------- placing photos

class _Shot(NamedTuple):
    """A photo placed in the plane before its lat/lon is known (fields as in Photo)."""

    x: float
    y: float
    alt_m: float
    heading_deg: float
    payloads: tuple[str, ...]
    span: int
    cause: int
    time_s: float
    item: int


class _Path(NamedTuple):
    """The flown path as arrays, for placing photos along it."""

    verts: Sequence[Vertex]
    times: np.ndarray
    xy: np.ndarray
    alts: np.ndarray
    holds: np.ndarray

    @classmethod
    def of(cls, verts: Sequence[Vertex], times: np.ndarray) -> _Path:
        return cls(verts, times, np.array([(v.x, v.y) for v in verts], dtype=float).reshape(-1, 2),
                   np.array([v.alt_m for v in verts], dtype=float), np.array([v.hold_s for v in verts], dtype=float))


def _photos(compiled: Compiled, verts: Sequence[Vertex], times: np.ndarray, flight: _Flight, proj: Any) -> list[Photo]:
    """Every photo the items take, in the order: distance spans, interval spans, single shots, then payloads that
    trigger themselves. Span ids number camera-on stretches (front-overlap pairs never cross one)."""
    path = _Path.of(verts, times)
    shots: list[_Shot] = []
    late = arduplane_late_m(flight.speed) if flight.ardupilot and not flight.copter else 0.0
    ap_metre = ardupilot_metre(proj.lat0) if compiled.firmware == "ardupilot" else None
    span_id = _distance_photos(path, flight.distance_spans, flight.trigger_payloads, shots, 0,
                               px4=compiled.firmware == "px4", frame=compiled.frame, late_m=late, ap_metre=ap_metre)
    span_id = _interval_photos(path, flight.interval_spans, shots, span_id)
    span_id = _single_photos(path, flight.singles, shots, span_id)
    _self_triggered_photos(compiled, path, shots, span_id)
    if not shots:
        return []
    shots = _split_at_turns(shots)
    arr = np.array([(s.x, s.y) for s in shots])
    lat, lon = proj.to_latlon(arr[:, 0], arr[:, 1])
    return [Photo(s.x, s.y, float(la), float(lo), s.alt_m, s.heading_deg, s.payloads, s.span, s.cause, s.time_s,
                  s.item) for s, la, lo in zip(shots, lat.tolist(), lon.tolist())]


def ardupilot_trigger_spacing_m(distance_m: float, speed_mps: float) -> float:
    """The spacing ArduPilot's distance trigger flies for DO_SET_CAM_TRIGG_DIST `distance_m` at `speed_mps`: the
    distance rounded up to whole steps of travel between its AP_CAMERA_UPDATE_HZ checks (Simulation's model)."""
    if speed_mps <= 0:
        return distance_m
    step = speed_mps / AP_CAMERA_UPDATE_HZ
    return math.ceil(distance_m / step - 1e-9) * step


def arduplane_trigger_spacing_m(distance_m: float, speed_mps: float) -> float:
    """The mean spacing ArduPlane's distance trigger flies: the same 50 Hz check as a copter's, but a plane's ground
    speed wanders with TECS and its turns (in SITL at 20 m/s airspeed: 20.4-21.5 m/s), so where the trigger
    distance falls between two checks is random: each photo comes half a check's travel late on average.
    Measured in arduplane SITL (CAMERA_FEEDBACK): 26.96 m mean spacing for 26.78 m at 20 m/s, where whole
    steps would give 26.80."""
    return distance_m + speed_mps / AP_CAMERA_UPDATE_HZ / 2.0


def arduplane_late_m(speed_mps: float) -> float:
    """How far past a line's entry ArduPlane takes its first photo on average: half a navigate tick's flight."""
    return speed_mps / ARDUPLANE_NAV_HZ / 2.0


def fired_spacing_m(firmware: str, distance_m: float, speed_mps: float) -> float:
    """The spacing `firmware`'s distance trigger flies for a commanded `distance_m` at `speed_mps`."""
    if firmware == "px4":
        return px4_trigger_spacing_m(distance_m, speed_mps)
    return ardupilot_trigger_spacing_m(distance_m, speed_mps)


def px4_trigger_spacing_m(distance_m: float, speed_mps: float) -> float:
    """The mean spacing PX4's camera_trigger flies for DO_SET_CAM_TRIGG_DIST `distance_m` at `speed_mps`: it
    checks the distance every PX4_TRIGGER_CHECK_S and measures the next from where it fired (Run() polls at
    50 ms; update_distance sets _last_shoot_position = current_position), so each shot overshoots by half a
    check's travel on average. Measured in PX4 1.16 SITL: 5.465 m flown for 5.356 m at 5 m/s (5.481 here)."""
    return distance_m + speed_mps * PX4_TRIGGER_CHECK_S / 2.0


def _distance_photos(path: _Path, spans: Sequence[DistanceSpan], payloads: tuple[str, ...], shots: list[_Shot],
                     span_id: int, *, px4: bool = False, frame: str = "copter", late_m: float = 0.0,
                     ap_metre: ApMetre | None = None) -> int:
    """Distance triggering, re-run as the firmware fires it; returns the next span id. PX4 shoots once whenever
    the trigger is switched on (update_distance's first valid position, or param3's one shot: never both),
    flies px4_trigger_spacing_m, and runs the DO items after a waypoint when it comes within px4_do_item_lead_m
    of it: every shot of the span comes that much earlier along the line (measured: 2.0 m median offset on a
    multicopter; on a plane NPFG's switch distance, about 30 m).
    ArduPilot (`ap_metre` given) measures the distance in its own metres (trigger_distance.AP_EARTH_RADIUS_M):
    the trigger is re-run on the path in those metres and its photos brought back.
    `late_m`: every shot of a span comes that much later along its line (ArduPlane: arduplane_late_m)."""
    verts, times, xy, alts, holds = path
    for span in spans:
        d, at_start = span.distance_m, span.shoot_at_start
        if px4:
            spd = max((verts[k].speed_mps for k in range(span.start + 1, span.end + 1)), default=verts[span.start].speed_mps)
            d, at_start = px4_trigger_spacing_m(d, spd), True
        pts = _fire(xy, TriggerSpan(span.start, span.end, d, at_start, span.shoot_at_stop), ap_metre)
        if not pts:
            span_id += 1
            continue
        seg_idx, frac = _locate(xy, span.start, span.end, pts)
        k = np.asarray(seg_idx, dtype=int)
        f = np.asarray(frac, dtype=float)
        k1 = np.minimum(k + 1, len(alts) - 1)
        alt = (alts[k] + f * (alts[k1] - alts[k])).tolist()
        depart = times[k] + holds[k]
        tt = np.where(k >= len(times) - 1, times[-1], depart + f * (times[k1] - depart)).tolist()
        shift = -px4_do_item_lead_m(frame, spd) if px4 else late_m
        if shift:
            pts = [p._replace(x=p.x + shift * math.sin(math.radians(p.heading_deg)),
                              y=p.y + shift * math.cos(math.radians(p.heading_deg))) for p in pts]
        for j, p in enumerate(pts):
            if span.start == span.end:      # on and off at one vertex: the photos are taken there
                hd, nav = _vertex_heading(verts, seg_idx[j], p.heading_deg), verts[span.start].item
            else:
                hd, nav = p.heading_deg, verts[int(k1[j])].item
            shots.append(_Shot(p.x, p.y, alt[j], hd, payloads, span_id, span.item, tt[j], nav))
        span_id += 1
    return span_id


def _fire(xy: np.ndarray, span: TriggerSpan, ap_metre: ApMetre | None) -> list[PhotoPoint]:
    """The distance trigger's photos over `span` of the path `xy` (true metres), measured in ArduPilot's metres
    when `ap_metre` is given (a survey's extent is small enough for one scale east and one north)."""
    if ap_metre is None:
        return simulate_distance_trigger(xy, [span])
    kx, ky = ap_metre
    pts = simulate_distance_trigger(xy / np.array([kx, ky]), [span])
    return [p._replace(x=p.x * kx, y=p.y * ky,
                       heading_deg=math.degrees(math.atan2(kx * math.sin(math.radians(p.heading_deg)),
                                                           ky * math.cos(math.radians(p.heading_deg)))) % 360.0)
            for p in pts]


def _interval_photos(path: _Path, spans: Sequence[IntervalSpan], shots: list[_Shot], span_id: int) -> int:
    """Interval triggering: photos at start + k·interval along the timeline; returns the next span id."""
    verts, times = path.verts, path.times
    for span in spans:
        t0 = times[span.start] + verts[span.start].hold_s * 0.0
        t_end = times[span.end] + verts[span.end].hold_s
        k = 0
        while True:
            tk = t0 + k * span.interval_s
            if tk > t_end + 1e-9 or (span.count > 0 and k >= span.count) or k > 10_000_000:
                break
            x, y, alt, hd, nav = _position_at(times, verts, tk, span.start, span.end)
            shots.append(_Shot(x, y, alt, hd, span.payloads, span_id, span.item, tk, nav))
            k += 1
        span_id += 1
    return span_id


def _single_photos(path: _Path, singles: Sequence[SinglePhoto], shots: list[_Shot], span_id: int) -> int:
    """Single photos: hover captures share a span while they go on along one line with one heading. The heading
    alone is not enough: a vehicle that reaches the next line's first stop through a detour arrives with the
    old line's heading, and that photo beside the last one (a side neighbour) would be a front pair. Returns
    the span id of the last run."""
    verts, times = path.verts, path.times
    last: tuple[float, float, float] | None = None
    for single in sorted(singles, key=lambda s: (s.vertex, s.item)):
        v = verts[single.vertex]
        hd = _vertex_heading(verts, single.vertex, None)
        if last is None or abs(((hd - last[2]) + 180) % 360 - 180) > 1.0 \
                or not _ahead_on_line(last[0], last[1], last[2], v.x, v.y):
            span_id += 1
        last = (v.x, v.y, hd)
        shots.append(_Shot(v.x, v.y, v.alt_m, hd, single.payloads, span_id, single.item, float(times[single.vertex]),
                           v.item))
    return span_id


def _self_triggered_photos(compiled: Compiled, path: _Path, shots: list[_Shot], span_id: int) -> int:
    """Payloads that trigger themselves (RedEdge overlap mode): distance triggering wherever the altitude fits."""
    verts, times, xy, alts, _ = path
    for name, (op_alt, tol, front_pct) in self_triggering(compiled).items():
        pay = compiled.payload(name)
        d = pay.footprint_m(op_alt)[1] * (1.0 - front_pct / 100.0)
        inband = alts >= op_alt - tol - 1e-6
        # it shoots on transits too: the plan's photo budget holds them (checked before they are placed)
        in_band_m = float(np.hypot(*np.diff(xy, axis=0).T)[inband[:-1] & inband[1:]].sum())
        check_photo_budget(in_band_m / d, f"flight's {name} payload (shooting by itself wherever it flies "
                                          f"{op_alt - tol:g} m or higher, transits included)")
        k = 0
        while k < len(verts) - 1:
            if not (inband[k] and inband[k + 1]):
                k += 1
                continue
            j = k + 1
            while j < len(verts) - 1 and inband[j + 1]:
                j += 1
            pts = simulate_distance_trigger(xy, [TriggerSpan(k, j, d, True, False)])
            seg_idx, frac = _locate(xy, k, j, pts)
            for p, sk, f in zip(pts, seg_idx, frac):
                alt = alts[sk] + f * (alts[min(sk + 1, len(alts) - 1)] - alts[sk])
                shots.append(_Shot(p.x, p.y, float(alt), p.heading_deg, (name,), span_id, -1,
                                   _time_at(times, verts, sk, f), verts[min(sk + 1, len(verts) - 1)].item))
            span_id += 1
            k = j
    return span_id


def _ahead_on_line(x0: float, y0: float, heading_deg: float, x1: float, y1: float) -> bool:
    """(x1, y1) lies ahead of (x0, y0) on its line of flight: forward along the heading and off it by no more than
    the lat/lon rounding of the items (1e-7° ≈ 1 cm) and a projection's curvature over the distance."""
    h = math.radians(heading_deg)
    dx, dy = x1 - x0, y1 - y0
    along = dx * math.sin(h) + dy * math.cos(h)
    cross = dx * math.cos(h) - dy * math.sin(h)
    return along > 0 and abs(cross) <= 0.05 + 1e-3 * along


# Consecutive photos more than this far apart in heading are not a front-overlap pair: the vehicle turned onto
# another line (a turnaround, a RedEdge shooting through the turn). Gentler bends (a corridor following a
# power line) stay pairs, and their lower overlap is real and reported.
TURN_SPLIT_DEG = 45.0


def _split_at_turns(shots: list[_Shot]) -> list[_Shot]:
    """Give photos after a sharp turn a span of their own (span ids stay unique and in order)."""
    out = []
    new_id = -1
    prev_span = prev_hd = None
    for s in shots:
        if s.span != prev_span or abs(((s.heading_deg - prev_hd) + 180.0) % 360.0 - 180.0) > TURN_SPLIT_DEG:
            new_id += 1
        prev_span, prev_hd = s.span, s.heading_deg
        out.append(s._replace(span=new_id))
    return out


def _vertex_heading(verts: Sequence[Vertex], k: int, fallback: float | None) -> float:
    """Heading of the vehicle resting at vertex k: its commanded yaw, else the direction it arrived from."""
    v = verts[k]
    if v.yaw_deg is not None:
        return v.yaw_deg % 360.0
    for j in range(k, 0, -1):
        a, b = verts[j - 1], verts[j]
        if math.hypot(b.x - a.x, b.y - a.y) > 1e-6:
            return _heading(b.x - a.x, b.y - a.y)
    if fallback is not None:
        return fallback
    for j in range(k, len(verts) - 1):
        a, b = verts[j], verts[j + 1]
        if math.hypot(b.x - a.x, b.y - a.y) > 1e-6:
            return _heading(b.x - a.x, b.y - a.y)
    return 0.0


def _locate(xy: np.ndarray, s0: int, s1: int, pts: Sequence[Any]) -> tuple[list[int], list[float]]:
    """Segment index and fraction along it of each photo of a span (photos come in path order)."""
    if not pts:
        return [], []
    last = max(min(s1, len(xy) - 1), s0 + 1) if len(xy) > 1 else 0
    if len(xy) < 2:
        return [0] * len(pts), [0.0] * len(pts)
    segs = np.arange(s0, min(last, len(xy) - 1))
    P = np.array([(p.x, p.y) for p in pts], dtype=float)
    if len(segs) <= 64:
        # photos × segments at once: distance to each segment, the nearest wins (ties: the earliest)
        A = xy[segs]
        D = xy[segs + 1] - A
        L2 = np.maximum((D * D).sum(1), 1e-18)
        W = P[:, None, :] - A[None, :, :]
        f = np.clip((W * D[None]).sum(2) / L2[None], 0.0, 1.0)
        dist = np.hypot(*(W - f[..., None] * D[None]).transpose(2, 0, 1))
        j = np.argmin(dist + 1e-9 * np.arange(len(segs))[None, :], axis=1)
        return segs[j].tolist(), f[np.arange(len(P)), j].tolist()
    seg_idx, frac = [], []
    k = 0
    for p in P:
        best = None
        while k < len(segs):
            a, b = xy[segs[k]], xy[segs[k] + 1]
            d = b - a
            L2 = float(d @ d)
            f = 0.0 if L2 < 1e-18 else min(1.0, max(0.0, float((p - a) @ d) / L2))
            dist = float(np.hypot(*(a + f * d - p)))
            if best is None or dist < best[2] - 1e-9:
                best = (int(segs[k]), f, dist)
            if dist < 1e-6:
                break
            k += 1
        if k >= len(segs):
            k = len(segs) - 1 if best is None else segs.tolist().index(best[0])
        seg_idx.append(best[0])
        frac.append(best[1])
    return seg_idx, frac


def _time_at(times: np.ndarray, verts: Sequence[Vertex], k: int, f: float) -> float:
    if k >= len(times) - 1:
        return float(times[-1])
    start = times[k] + verts[k].hold_s
    return float(start + f * (times[k + 1] - start))


def _position_at(times: np.ndarray, verts: Sequence[Vertex], t: float, s0: int,
                 s1: int) -> tuple[float, float, float, float, int]:
    """Where the vehicle is at time t (linear in time within a segment: good enough for photo spacing): x, y,
    altitude, heading and the NAV item it is executing (the one it holds at or flies towards)."""
    k = int(np.searchsorted(times, t, side="right") - 1)
    k = min(max(k, s0), max(s1, s0))
    v = verts[k]
    depart = times[k] + v.hold_s
    if k >= len(verts) - 1 or t <= depart:
        return v.x, v.y, v.alt_m, _vertex_heading(verts, k, None), v.item
    q = verts[k + 1]
    f = min(1.0, (t - depart) / max(times[k + 1] - depart, 1e-9))
    hd = _heading(q.x - v.x, q.y - v.y) if math.hypot(q.x - v.x, q.y - v.y) > 1e-6 else _vertex_heading(verts, k, None)
    return v.x + f * (q.x - v.x), v.y + f * (q.y - v.y), v.alt_m + f * (q.alt_m - v.alt_m), hd, q.item


def _trigger_intervals(compiled: Compiled, flight: _Flight, verts: Sequence[Vertex]) -> list[TriggerInterval]:
    """How often each payload is triggered over every camera-on span, at the cruise speed flown there."""
    out = []
    for span in flight.distance_spans:
        spd = max((verts[k].speed_mps for k in range(span.start + 1, span.end + 1)), default=compiled.speed_mps)
        if spd > 0:
            for p in flight.trigger_payloads:
                out.append(TriggerInterval(p, span.distance_m, span.distance_m / spd, span.item))
    for span in flight.interval_spans:
        for p in span.payloads:
            out.append(TriggerInterval(p, span.interval_s, span.interval_s, span.item))
    for name, (op_alt, tol, front_pct) in self_triggering(compiled).items():
        d = compiled.payload(name).footprint_m(op_alt)[1] * (1.0 - front_pct / 100.0)
        spd = max((v.speed_mps for v in verts if v.alt_m >= op_alt - tol - 1e-6), default=compiled.speed_mps)
        if spd > 0:
            out.append(TriggerInterval(name, d, d / spd, -1))
    return out
