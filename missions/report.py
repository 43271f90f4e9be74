"""The measured report of a compiled mission: what the emitted items will really do, not what the planner meant.

    sim = simulate(compiled)        # flown path, photo positions, timeline — from compiled.items only
    rep = report(compiled)          # the `wiris mission check --json` object (cli.md's binding fields + more)

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
  home's elevation: the report cannot know the terrain, and neither can the autopilot without terrain data.
* Camera: DO commands execute when the vehicle leaves the previous NAV position, so a command takes effect
  at the path vertex it follows. DO_SET_CAM_TRIGG_DIST (on/off, param3 "trigger once") is re-run through
  `missions.triggers.simulate_distance_trigger`, which fires as ArduPilot's AP_Camera and PX4's
  camera_trigger do (straight-line distance from the last photo). IMAGE_START_CAPTURE with one image,
  DO_DIGICAM_CONTROL(shoot) and a trigger-once take one photo there; IMAGE_START_CAPTURE with an interval
  takes photos by time along the simulated timeline until IMAGE_STOP_CAPTURE; so does PX4's interval trigger
  (DO_SET_CAM_TRIGG_INTERVAL sets the interval, DO_TRIGGER_CONTROL starts/pauses/stops it).
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
  Climbs and descents are limited to CLIMB_MPS / DESCENT_MPS, the last LAND_FINAL_M of a landing to
  LAND_MPS. Holds (NAV_WAYPOINT param1 on multirotors, LOITER_TIME, NAV_DELAY) add their time.
  For comparison `flight_time_qgc_s` is QGroundControl's statistic (MissionController: horizontal distance /
  cruise speed + hold times, no acceleration, no climbs); Mission Planner shows distance / (0.8·speed).
  Our model is longer than QGC's on every survey with turns — that is the point of it.
* Measuring: per survey/corridor step and payload with `missions.coverage`, in one metric plane (the first
  area's projection, so photos on a line stay exactly collinear). Coverage takes every photo whose footprint can
  reach the area, whichever step took it, grouped by altitude (one footprint size per group; coverage is the
  union over all groups). The rest is the step's own, so that a neighbouring step does not blur it: its overlaps,
  photo count and metres outside the area take the photos taken and the path flown while the mission executes
  the step's items (`AreaInfo.items`; the vehicle executes a NAV item while it flies towards it and holds at it,
  so the approach to the step's first waypoint is the step's). Front
  overlap pairs consecutive photos of one camera-on stretch; a turn of more than TURN_SPLIT_DEG starts a new
  stretch (a turnaround is not a front pair; a corridor's gentle bend is, and its lower overlap is real).
  Coverage below COVERAGE_TARGET and overlaps more than OVERLAP_SLACK below the request are warnings, not
  errors: the mission flies, the result is worse than asked.
* Holes and exclusion zones: the whole flown path is measured inside each step's zones as drawn
  (`Area.excluded`, so an exclusion across the boundary counts too), deeper than route.ZONE_EDGE_TOL_M (a
  path along a zone's edge is beside it), split into metres with the camera on (distance or interval
  triggering) and off, with the photos centred inside; more than a metre is the path_over_exclusion warning.
  Unlike the figures above these stay the whole flight's: an exclusion is ground not to fly over or photograph
  (the plan schema's words), and another step flying over it is as real as this one.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, NamedTuple, Sequence

import numpy as np

from missions.compiled import Compiled, PayloadInfo
from missions.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_GLOBAL_TERRAIN_ALT, MissionItem, mavlink

# ArduCopter defaults (WPNAV_ACCEL 250 cm/s², WPNAV_SPEED_UP 250 cm/s, WPNAV_SPEED_DN 150 cm/s,
# LAND_SPEED 50 cm/s below LAND_ALT_LOW 10 m, RTL_ALT 15 m); PX4's multicopter defaults are close
# (MPC_ACC_HOR 3 m/s², MPC_Z_VEL_MAX_UP 3 m/s, MPC_Z_VEL_MAX_DN 1.5 m/s, MPC_LAND_SPEED 0.7 m/s).
ACCEL_MPS2 = 2.5
CLIMB_MPS = 2.5
DESCENT_MPS = 1.5
LAND_MPS = 0.5
LAND_FINAL_M = 10.0
RTL_ALT_M = 15.0
# Most of the world's drone rules (EU 2019/947 open category, FAA part 107) cap flights at 120 m / 400 ft.
MAX_AGL_M = 120.0
# A DO_JUMP loop is followed at most this many items: an infinite repeat is reported, not simulated forever.
MAX_SIMULATED_ITEMS = 2_000_000
# Coverage below this is worth a warning: the examples and the tests hold the compiler to it.
COVERAGE_TARGET = 0.995
# Measured minimum overlaps within this of the request are rounding at the edges, not a planning fault.
OVERLAP_SLACK = 0.01

INT_FRAMES = {mavlink.MAV_FRAME_GLOBAL_INT: FRAME_GLOBAL,
              mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: FRAME_GLOBAL_RELATIVE_ALT,
              mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: FRAME_GLOBAL_TERRAIN_ALT}

C = mavlink   # command numbers below come from pymavlink's dialect (common.xml + ardupilotmega.xml)
NAV_POSITION = {C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_SPLINE_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME,
                C.MAV_CMD_NAV_LOITER_TURNS, C.MAV_CMD_NAV_LOITER_TO_ALT}
NAV_TAKEOFF = {C.MAV_CMD_NAV_TAKEOFF, C.MAV_CMD_NAV_VTOL_TAKEOFF}
NAV_LAND = {C.MAV_CMD_NAV_LAND, C.MAV_CMD_NAV_VTOL_LAND}


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
    projection: Any                            # missions.geo.LocalProjection
    path_length_m: float                       # horizontal
    climb_m: float
    flight_time_s: float
    flight_time_qgc_s: float
    vertex_times_s: tuple[float, ...]          # arrival time at each vertex
    trigger_intervals: tuple[tuple[str, float, float, int], ...] = ()   # (payload, distance|interval value, seconds, item)
    notes: tuple[tuple[str, str], ...] = ()    # (code, message) found while simulating
    ends_on_ground: bool = False
    camera_on: tuple[tuple[int, int], ...] = ()  # vertex ranges flown with distance or interval triggering on

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
        from cdf.catalogue import catalogue
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
    from missions.geo import LocalProjection

    if compiled.areas:
        return compiled.areas[0].area.projection
    lats = [compiled.home[0]]
    lons = [compiled.home[1]]
    for it in compiled.items:
        if it.frame != mavlink.MAV_FRAME_MISSION and (it.x or it.y):
            lats.append(it.lat)
            lons.append(it.lon)
    return LocalProjection.centred_on(lats, lons)


def area_geometry(area: Any, proj: Any) -> Any:
    """`area` (missions.area.Area) as a shapely geometry in projection `proj` (re-projected through lat/lon when
    it was built in another plane; its edges are short enough to stay straight in both)."""
    from shapely.geometry import MultiPolygon, Polygon

    if area.projection == proj:
        return area.geometry
    polys = []
    for rings in area.latlon_rings():
        xy = []
        for ring in rings:
            x, y = proj.to_xy([p[0] for p in ring], [p[1] for p in ring])
            xy.append(list(zip(x.tolist(), y.tolist())))
        polys.append(Polygon(xy[0], xy[1:]))
    return polys[0] if len(polys) == 1 else MultiPolygon(polys)


@dataclass
class _Walk:
    """Mutable state of one simulation run (local to `simulate`, never shared)."""

    verts: list[Vertex] = field(default_factory=list)
    singles: list[tuple[int, tuple[str, ...], int]] = field(default_factory=list)      # vertex, payloads, item
    dist_spans: list[tuple[int, int, float, bool, bool, int]] = field(default_factory=list)
    time_spans: list[tuple[int, int, float, tuple[str, ...], int, int]] = field(default_factory=list)
    notes: list[tuple[str, str]] = field(default_factory=list)


def simulate(compiled: Compiled) -> Simulation:
    """Fly `compiled.items` in the model above; return path, photos and times."""
    proj = _projection(compiled)
    home_lat, home_lon, home_amsl = compiled.home
    hx, hy = proj.point_to_xy(home_lat, home_lon)
    items = compiled.items
    # A VTOL takes off and lands vertically but flies its mission fixed-wing (hover triggering is refused
    # for it): between take-off and landing it keeps its speed through turns and ignores holds, like a plane.
    copter = compiled.frame == "copter"
    vertical = compiled.frame in ("copter", "vtol")
    ap = compiled.firmware == "ardupilot"
    w = _Walk()
    w.verts.append(Vertex(hx, hy, 0.0, -1, stop=True))
    speed = float(compiled.speed_mps)
    trig_payloads = _trigger_payloads(compiled)
    dist_on: tuple[int, float, bool, int] | None = None          # start vertex, distance, shoot at start, item
    time_on: tuple[int, float, tuple[str, ...], int, int] | None = None  # start vertex, interval, payloads, count, item
    jumps: dict[int, int] = {}
    has_trigger_control = any(it.command == C.MAV_CMD_DO_TRIGGER_CONTROL for it in items)
    trig_interval_s = 0.0
    terrain_items: list[int] = []
    ended = False
    on_ground = False
    i = 0
    steps = 0
    seq_base = 1 if ap else 0      # ArduPilot numbers the mission from 1 (seq 0 is home)

    def cur() -> Vertex:
        return w.verts[-1]

    def add(x: float, y: float, alt: float, item: int, hold: float = 0.0, stop: bool = False,
            yaw: float | None = None, spd: float | None = None) -> None:
        w.verts.append(Vertex(x, y, alt, item, hold, stop or hold > 0, yaw, spd if spd is not None else speed))

    while i < len(items):
        steps += 1
        if steps > MAX_SIMULATED_ITEMS:
            w.notes.append(("jump_loop", f"DO_JUMP loops were followed for {MAX_SIMULATED_ITEMS} items and cut off"))
            break
        it = items[i]
        cmd = it.command
        c = cur()
        if cmd in NAV_POSITION or cmd in NAV_TAKEOFF or cmd in NAV_LAND or cmd == C.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            here = not (it.x or it.y)
            x, y = (c.x, c.y) if here else proj.point_to_xy(it.lat, it.lon)
            alt, terrain = _altitude(it, home_amsl, c.alt_m)
            if terrain:
                terrain_items.append(i)
            if cmd in NAV_TAKEOFF:
                on_ground = False
                add(c.x, c.y, alt, i, stop=True, spd=CLIMB_MPS)
                if not here and not ap and math.hypot(x - c.x, y - c.y) > 1.0 and not vertical:
                    add(x, y, alt, i)
            elif cmd in NAV_POSITION:
                hold = 0.0
                if cmd == C.MAV_CMD_NAV_WAYPOINT and copter:
                    hold = max(0.0, it.param1)
                elif cmd == C.MAV_CMD_NAV_LOITER_TIME:
                    hold = max(0.0, it.param1)
                # PX4 flies a waypoint's yaw (param4) as the heading to hold; ArduPilot does not even store it
                yaw = it.param4 if cmd == C.MAV_CMD_NAV_WAYPOINT and math.isfinite(it.param4) and copter and not ap \
                    else None
                add(x, y, alt, i, hold=hold, yaw=yaw)
            elif cmd == C.MAV_CMD_NAV_RETURN_TO_LAUNCH:
                rtl_alt = max(c.alt_m, RTL_ALT_M)
                if rtl_alt > c.alt_m + 0.01:
                    add(c.x, c.y, rtl_alt, i, stop=True, spd=CLIMB_MPS)
                add(hx, hy, rtl_alt, i, stop=True)
                add(hx, hy, 0.0, i, stop=True)
                ended = on_ground = True
            else:  # land
                if math.hypot(x - c.x, y - c.y) > 0.01:
                    add(x, y, c.alt_m, i, stop=True)
                add(x, y, 0.0, i, stop=True)
                ended = on_ground = True
        elif cmd == C.MAV_CMD_NAV_LOITER_UNLIM:
            x, y = (c.x, c.y) if not (it.x or it.y) else proj.point_to_xy(it.lat, it.lon)
            alt, _ = _altitude(it, home_amsl, c.alt_m)
            add(x, y, alt, i, stop=True)
            w.notes.append(("loiter_unlimited", f"item {i + seq_base}: LOITER_UNLIM — the mission never ends by itself"))
            ended = True
        elif cmd in (C.MAV_CMD_NAV_DELAY, C.MAV_CMD_CONDITION_DELAY):
            secs = max(0.0, it.param1)
            w.verts[-1] = Vertex(c.x, c.y, c.alt_m, c.item, c.hold_s + secs, True, c.yaw_deg, c.speed_mps)
        elif cmd == C.MAV_CMD_DO_CHANGE_SPEED:
            if it.param2 > 0:
                speed = float(it.param2)
        elif cmd == C.MAV_CMD_DO_JUMP:
            target = int(it.param1) - seq_base
            repeat = int(it.param2)
            done = jumps.get(i, 0)
            if repeat < 0:
                w.notes.append(("jump_forever", f"item {i + seq_base}: DO_JUMP repeats forever; followed once"))
                repeat = 1
            if 0 <= target < len(items) and done < repeat:
                jumps[i] = done + 1
                i = target
                continue
        elif cmd == C.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
            vi = len(w.verts) - 1
            if dist_on is not None:
                s0, d, at_start, src = dist_on
                w.dist_spans.append((s0, vi, d, at_start, it.param1 <= 0 and it.param3 == 1, src))
                dist_on = None
            elif it.param3 == 1 and it.param1 <= 0:
                w.singles.append((vi, trig_payloads, i))
            if it.param1 > 0:
                dist_on = (vi, float(it.param1), it.param3 == 1, i)
        elif cmd == C.MAV_CMD_IMAGE_START_CAPTURE:
            vi = len(w.verts) - 1
            targets = _payload_for_target(compiled, it.param1)
            count = int(it.param3) if math.isfinite(it.param3) else 0
            interval = it.param2 if math.isfinite(it.param2) else 0.0
            if count == 1 or interval <= 0:
                w.singles.append((vi, targets, i))
            else:
                if time_on is not None:
                    s0, iv, pl, n, src = time_on
                    w.time_spans.append((s0, vi, iv, pl, n, src))
                time_on = (vi, float(interval), targets, count, i)
        elif cmd == C.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL:
            # PX4 (TRIG_MODE 1 "time based, on command"): this sets the interval; DO_TRIGGER_CONTROL starts and
            # stops it. A mission without DO_TRIGGER_CONTROL is taken to start shooting here.
            vi = len(w.verts) - 1
            if it.param1 > 0:
                trig_interval_s = it.param1 / 1000.0
            if not has_trigger_control:
                if time_on is not None:
                    s0, iv, pl, n, src = time_on
                    w.time_spans.append((s0, vi, iv, pl, n, src))
                    time_on = None
                if it.param1 > 0:
                    time_on = (vi, trig_interval_s, trig_payloads, 0, i)
        elif cmd == C.MAV_CMD_DO_TRIGGER_CONTROL:
            vi = len(w.verts) - 1
            start = it.param1 == 1 or (it.param1 < 0 and it.param3 == 0)
            stop = it.param1 == 0 or it.param3 == 1
            if stop and time_on is not None:
                s0, iv, pl, n, src = time_on
                w.time_spans.append((s0, vi, iv, pl, n, src))
                time_on = None
            elif start and time_on is None and trig_interval_s > 0:
                time_on = (vi, trig_interval_s, trig_payloads, 0, i)
        elif cmd == C.MAV_CMD_IMAGE_STOP_CAPTURE:
            if time_on is not None:
                s0, iv, pl, n, src = time_on
                w.time_spans.append((s0, len(w.verts) - 1, iv, pl, n, src))
                time_on = None
        elif cmd == C.MAV_CMD_DO_DIGICAM_CONTROL:
            # param5 "Shot": 1 takes a photo (frame MISSION keeps it in x), whether or not DO_TRIGGER_CONTROL
            # has stopped the trigger: PX4's camera_trigger fires a one-shot without looking at its enabled
            # state (CameraTrigger::Run, "One shot command-based capture handling", PX4-Autopilot 7704fe75)
            if it.x == 1:
                w.singles.append((len(w.verts) - 1, trig_payloads, i))
        if ended:
            break
        i += 1

    last = len(w.verts) - 1
    if dist_on is not None:
        s0, d, at_start, src = dist_on
        w.dist_spans.append((s0, last, d, at_start, False, src))
        w.notes.append(("trigger_left_on", f"item {src + seq_base}: distance triggering is never switched off"))
    if time_on is not None:
        s0, iv, pl, n, src = time_on
        w.time_spans.append((s0, last, iv, pl, n, src))
    if terrain_items:
        w.notes.append(("terrain_frame", f"{len(terrain_items)} items use the terrain frame: heights are taken "
                                         "as above ground; footprints assume the autopilot follows terrain"))
    verts = _yaws_in_plane(_mark_stops(w.verts, copter), proj)
    times = _timeline(verts, copter)
    photos = _photos(compiled, verts, times, w, proj, trig_payloads)
    xy = np.array([(v.x, v.y) for v in verts], dtype=float)
    seg = np.hypot(*np.diff(xy, axis=0).T) if len(xy) > 1 else np.zeros(0)
    dz = np.diff([v.alt_m for v in verts]) if len(verts) > 1 else np.zeros(0)
    horiz = float(seg.sum())
    holds = sum(v.hold_s for v in verts)
    qgc = sum(seg[k] / max(verts[k + 1].speed_mps or compiled.speed_mps, 0.1) for k in range(len(seg))
              if verts[k + 1].item < 0 or items[verts[k + 1].item].command not in NAV_TAKEOFF) + holds
    lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
    intervals = _trigger_intervals(compiled, w, verts, trig_payloads)
    return Simulation(
        vertices=tuple(verts), latlon=tuple(zip(lat.tolist(), lon.tolist())), photos=tuple(photos), projection=proj,
        path_length_m=horiz, climb_m=float(np.clip(dz, 0, None).sum()), flight_time_s=float(times[-1] + verts[-1].hold_s),
        flight_time_qgc_s=float(qgc), vertex_times_s=tuple(times.tolist()), trigger_intervals=tuple(intervals),
        notes=tuple(w.notes), ends_on_ground=on_ground,
        camera_on=tuple((s[0], s[1]) for s in w.dist_spans) + tuple((s[0], s[1]) for s in w.time_spans))


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


def _timeline(verts: Sequence[Vertex], copter: bool) -> np.ndarray:
    """Arrival time at each vertex (holds at a vertex are spent after arriving)."""
    n = len(verts)
    vc = _corner_speeds(verts, copter)
    a = ACCEL_MPS2 if copter else 2.0 * ACCEL_MPS2
    xy = np.array([(v.x, v.y) for v in verts], dtype=float).reshape(-1, 2)
    L = np.hypot(*np.diff(xy, axis=0).T) if n > 1 else np.zeros(0)
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


def _photos(compiled: Compiled, verts: Sequence[Vertex], times: np.ndarray, w: _Walk, proj: Any,
            trig_payloads: tuple[str, ...]) -> list[Photo]:
    from missions.survey import check_photo_budget
    from missions.triggers import TriggerSpan, simulate_distance_trigger

    xy = np.array([(v.x, v.y) for v in verts], dtype=float).reshape(-1, 2)
    alts = np.array([v.alt_m for v in verts], dtype=float)
    holds = np.array([v.hold_s for v in verts], dtype=float)
    # x y alt heading payloads span cause time item (see Photo)
    raw: list[tuple[float, float, float, float, tuple[str, ...], int, int, float, int]] = []
    span_id = 0
    # distance triggering
    for s0, s1, d, at_start, at_stop, src in w.dist_spans:
        pts = simulate_distance_trigger(xy, [TriggerSpan(s0, s1, d, at_start, at_stop)])
        if not pts:
            span_id += 1
            continue
        seg_idx, frac = _locate(xy, s0, s1, pts)
        k = np.asarray(seg_idx, dtype=int)
        f = np.asarray(frac, dtype=float)
        k1 = np.minimum(k + 1, len(alts) - 1)
        alt = (alts[k] + f * (alts[k1] - alts[k])).tolist()
        depart = times[k] + holds[k]
        tt = np.where(k >= len(times) - 1, times[-1], depart + f * (times[k1] - depart)).tolist()
        for j, p in enumerate(pts):
            if s0 == s1:      # on and off at one vertex: the photos are taken there
                hd, nav = _vertex_heading(verts, seg_idx[j], p.heading_deg), verts[s0].item
            else:
                hd, nav = p.heading_deg, verts[int(k1[j])].item
            raw.append((p.x, p.y, alt[j], hd, trig_payloads, span_id, src, tt[j], nav))
        span_id += 1
    # interval triggering: photos at start + k·interval along the timeline
    for s0, s1, iv, pl, count, src in w.time_spans:
        t0 = times[s0] + verts[s0].hold_s * 0.0
        t_end = times[s1] + verts[s1].hold_s
        k = 0
        while True:
            tk = t0 + k * iv
            if tk > t_end + 1e-9 or (count > 0 and k >= count) or k > 10_000_000:
                break
            x, y, alt, hd, nav = _position_at(times, verts, tk, s0, s1)
            raw.append((x, y, alt, hd, pl, span_id, src, tk, nav))
            k += 1
        span_id += 1
    # single photos: hover captures share a span while they go on along one line with one heading. The heading
    # alone is not enough: a vehicle that reaches the next line's first stop through a detour arrives with the
    # old line's heading, and that photo beside the last one (a side neighbour) became a front pair.
    last: tuple[float, float, float] | None = None
    for vi, pl, src in sorted(w.singles, key=lambda s: (s[0], s[2])):
        v = verts[vi]
        hd = _vertex_heading(verts, vi, None)
        if last is None or abs(((hd - last[2]) + 180) % 360 - 180) > 1.0 \
                or not _ahead_on_line(last[0], last[1], last[2], v.x, v.y):
            span_id += 1
        last = (v.x, v.y, hd)
        raw.append((v.x, v.y, v.alt_m, hd, pl, span_id, src, float(times[vi]), v.item))
    # payloads that trigger themselves (RedEdge overlap mode): distance triggering wherever the altitude fits
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
            if inband[k] and inband[k + 1]:
                j = k + 1
                while j < len(verts) - 1 and inband[j + 1]:
                    j += 1
                pts = simulate_distance_trigger(xy, [TriggerSpan(k, j, d, True, False)])
                seg_idx, frac = _locate(xy, k, j, pts)
                for p, sk, f in zip(pts, seg_idx, frac):
                    alt = alts[sk] + f * (alts[min(sk + 1, len(alts) - 1)] - alts[sk])
                    raw.append((p.x, p.y, float(alt), p.heading_deg, (name,), span_id, -1,
                                _time_at(times, verts, sk, f), verts[min(sk + 1, len(verts) - 1)].item))
                span_id += 1
                k = j
            else:
                k += 1
    if not raw:
        return []
    raw = _split_at_turns(raw)
    arr = np.array([(r[0], r[1]) for r in raw])
    lat, lon = proj.to_latlon(arr[:, 0], arr[:, 1])
    return [Photo(r[0], r[1], float(la), float(lo), r[2], r[3], r[4], r[5], r[6], r[7], r[8])
            for r, la, lo in zip(raw, lat.tolist(), lon.tolist())]


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


def _split_at_turns(raw: list[tuple]) -> list[tuple]:
    """Give photos after a sharp turn a span of their own (span ids stay unique and in order)."""
    out = []
    new_id = -1
    prev_span = prev_hd = None
    for r in raw:
        span, hd = r[5], r[3]
        if span != prev_span or abs(((hd - prev_hd) + 180.0) % 360.0 - 180.0) > TURN_SPLIT_DEG:
            new_id += 1
        prev_span, prev_hd = span, hd
        out.append(r[:5] + (new_id,) + r[6:])
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


def _trigger_intervals(compiled: Compiled, w: _Walk, verts: Sequence[Vertex],
                       trig_payloads: tuple[str, ...]) -> list[tuple[str, float, float, int]]:
    """(payload, trigger value, seconds between photos at the cruise speed, item) for every camera-on span."""
    out = []
    for s0, s1, d, _a, _b, src in w.dist_spans:
        spd = max((verts[k].speed_mps for k in range(s0 + 1, s1 + 1)), default=compiled.speed_mps)
        if spd > 0:
            for p in trig_payloads:
                out.append((p, d, d / spd, src))
    for s0, s1, iv, pl, _n, src in w.time_spans:
        for p in pl:
            out.append((p, iv, iv, src))
    for name, (op_alt, tol, front_pct) in self_triggering(compiled).items():
        d = compiled.payload(name).footprint_m(op_alt)[1] * (1.0 - front_pct / 100.0)
        spd = max((v.speed_mps for v in verts if v.alt_m >= op_alt - tol - 1e-6), default=compiled.speed_mps)
        if spd > 0:
            out.append((name, d, d / spd, -1))
    return out


# --------------------------------------------------------------------------------------------- measuring

def footprint_ring(photo: Photo, payload: PayloadInfo) -> list[tuple[float, float]]:
    """The photo's footprint corners in the simulation's metres (x, y), closed ring."""
    across, along = payload.footprint_m(max(photo.alt_m, 0.0))
    h = math.radians(photo.heading_deg)
    d = np.array([math.sin(h), math.cos(h)])
    n = np.array([math.cos(h), -math.sin(h)])
    c = np.array([photo.x, photo.y])
    pts = [c - d * along / 2 - n * across / 2, c + d * along / 2 - n * across / 2,
           c + d * along / 2 + n * across / 2, c - d * along / 2 + n * across / 2]
    pts.append(pts[0])
    return [(float(p[0]), float(p[1])) for p in pts]


def _measure_area(area_info: Any, payload: PayloadInfo, photos: Sequence[Photo], sim: Simulation,
                  path: np.ndarray | None = None) -> dict:
    """Coverage and overlaps of one payload's photos over one area, in the area's own projection.

    Coverage counts every photo whose footprint can reach the area: a neighbouring step's photo covers ground
    too. The overlaps and the photo count take the photos the step took (`area_info.items`), the metres outside
    the area the path segments it flew (`path`, a mask over the simulation's segments, `_step_paths`): another
    step's photos and path are measured against its own area. Without a range (an AreaInfo built by hand) the
    photos near the area and the whole path stand in for them. The zones are checked against the whole flight:
    an exclusion is ground not to fly over or photograph, whichever step does it."""
    import shapely
    from missions.coverage import coverage_fraction, footprint_polygons, min_front_overlap, min_side_overlap
    from missions.footprint import Footprint
    from missions.triggers import PhotoPoint

    proj = sim.projection
    geom = area_geometry(area_info.area, proj)
    result: dict[str, Any] = {"coverage": 0.0, "front_min": None, "side_min": None, "photos": 0}
    if photos:
        x = np.array([p.x for p in photos])
        y = np.array([p.y for p in photos])
        alts = np.array([max(p.alt_m, 0.0) for p in photos])
        # photos whose footprint can reach the area (others cover other ground)
        reach = max(payload.footprint_m(1.0)) * alts        # footprints scale with altitude
        near = np.nonzero(shapely.dwithin(shapely.points(x, y), geom, reach))[0]
    else:
        x = y = alts = np.zeros(0)
        near = np.zeros(0, int)
    if area_info.items is not None:
        first, end = area_info.items
        own = np.array([k for k, p in enumerate(photos) if first <= p.item < end], dtype=int)
    else:
        own = near

    def by_altitude(idx: np.ndarray) -> dict[float, list[int]]:
        """One Footprint per altitude; photos keep their mission order within a group."""
        groups: dict[float, list[int]] = {}
        for k in idx.tolist():
            if alts[k] > 0:
                groups.setdefault(round(float(alts[k]), 2), []).append(k)
        return groups

    def points(ks: list[int]) -> list[PhotoPoint]:
        return [PhotoPoint(float(x[k]), float(y[k]), photos[k].heading_deg, photos[k].span) for k in ks]

    groups = by_altitude(near)
    if len(groups) == 1:
        (alt, ks), = groups.items()
        result["coverage"] = coverage_fraction(geom, points(ks), Footprint(*payload.footprint_m(alt)))[1]
    elif groups and geom.area > 0:
        polys = [footprint_polygons(np.column_stack([x[ks], y[ks]]), np.radians([photos[k].heading_deg for k in ks]),
                                    Footprint(*payload.footprint_m(alt))) for alt, ks in groups.items()]
        union = shapely.union_all(np.concatenate(polys))
        result["coverage"] = float(shapely.intersection(geom, union).area / geom.area)
    fronts, sides = [], []
    for alt, ks in by_altitude(own).items():
        fp = Footprint(*payload.footprint_m(alt))
        fronts.append(min_front_overlap(points(ks), fp))
        sides.append(min_side_overlap(points(ks), fp))
    result["front_min"] = min((f for f in fronts if f is not None), default=None)
    result["side_min"] = min((s for s in sides if s is not None), default=None)
    result["photos"] = int(len(own))
    result["outside_m"] = _outside_m(sim.xy, path, geom)
    zones = _zones(area_info.area, proj)
    result["over_gaps_m"], result["over_gaps_camera_m"] = _over_zones_m(sim, zones)
    result["photos_in_zones"] = _photos_in(zones, photos)
    return result


def _step_paths(compiled: Compiled, sim: Simulation) -> list[np.ndarray | None]:
    """Per area step, the path segments it flew (a mask over the simulation's segments; None: unknown, a
    hand-built AreaInfo). Segment k (vertex k to k + 1) is flown executing the NAV item of vertex k + 1, so a step's
    path is what it flies towards its own waypoints, the approach to its first one included."""
    seg_item = np.array([v.item for v in sim.vertices[1:]], dtype=int)
    return [None if a.items is None else (seg_item >= a.items[0]) & (seg_item < a.items[1]) for a in compiled.areas]


def _outside_m(xy: np.ndarray, path: np.ndarray | None, geom: Any) -> float:
    """Metres of the path segments `path` selects (None: all) outside `geom`, one polyline per run of them."""
    from missions.coverage import outside_length_m

    if path is None:
        return outside_length_m(xy, geom)
    k = np.flatnonzero(path)
    if not len(k):
        return 0.0
    cut = np.flatnonzero(np.diff(k) > 1)
    return sum(outside_length_m(xy[a:b + 2], geom) for a, b in zip(np.r_[k[0], k[cut + 1]], np.r_[k[cut], k[-1]]))


def _zones(area: Any, proj: Any) -> Any:
    """The area's holes and exclusion zones as drawn (`Area.excluded`: an exclusion that touches, crosses or
    splits the boundary is no hole of the surveyed geometry) in projection `proj`. An Area built without that
    record (by hand) has only its geometry's holes."""
    import shapely
    from shapely.geometry import Polygon

    from missions.geo import leaf_parts

    zones = getattr(area, "excluded", None)
    if zones is None:
        holes = [Polygon(r) for p in leaf_parts(area.geometry, "Polygon") for r in p.interiors]
        zones = shapely.union_all(holes) if holes else Polygon()
    if zones.is_empty or area.projection == proj:
        return zones

    def move(xy: np.ndarray) -> np.ndarray:
        lat, lon = area.projection.to_latlon(xy[:, 0], xy[:, 1])
        return np.column_stack(proj.to_xy(lat, lon))

    return shapely.transform(zones, move)


def _over_zones_m(sim: Simulation, zones: Any) -> tuple[float, float]:
    """Metres of the flown path inside `zones`, and how many of them with the camera on. Inside means deeper than
    route.ZONE_EDGE_TOL_M: a path along a zone's edge (a detour inside the area) is beside it."""
    import shapely
    from missions.route import ZONE_EDGE_TOL_M

    xy = sim.xy
    if zones.is_empty or len(xy) < 2:
        return 0.0, 0.0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    shapely.prepare(core)
    segs = shapely.linestrings(np.stack([xy[:-1], xy[1:]], axis=1))
    inside = np.zeros(len(segs))
    hit = shapely.intersects(core, segs)
    if hit.any():
        inside[hit] = shapely.length(shapely.intersection(segs[hit], core))
    on = np.zeros(len(segs), bool)
    for s0, s1 in sim.camera_on:
        on[s0:s1] = True
    return float(inside.sum()), float(inside[on].sum())


def _photos_in(zones: Any, photos: Sequence[Photo]) -> int:
    """Photos centred inside `zones` (deeper than the edge tolerance, as for the path)."""
    import shapely
    from missions.route import ZONE_EDGE_TOL_M

    if zones.is_empty or not photos:
        return 0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    return int(shapely.contains_xy(core, [p.x for p in photos], [p.y for p in photos]).sum())


def _r(v: float | None, nd: int = 4) -> float | None:
    return None if v is None else round(float(v), nd)


def report(compiled: Compiled, sim: Simulation | None = None, plan_path: str | None = None) -> dict:
    """The measured report (`wiris mission check --json`)."""
    sim = sim or simulate(compiled)
    warnings: list[dict] = [_compiler_warning(m) for m in compiled.warnings]
    errors: list[dict] = []
    names = [p.name for p in compiled.payloads]
    photos_of = {n: [p for p in sim.photos if n in p.payloads] for n in names}
    seq_base = 1 if compiled.firmware == "ardupilot" else 0

    # areas: coverage and overlap per payload, measured against what each step must cover
    area_rows = []
    cov_acc: dict[str, list[tuple[float, float]]] = {}
    ov_acc: dict[str, dict[str, list[float]]] = {}
    for a, path in zip(compiled.areas, _step_paths(compiled, sim)):
        row: dict[str, Any] = {"step": a.step, "kind": a.kind, "area_m2": _r(a.area.area_m2, 1),
                               "altitude_m": _r(a.altitude_m, 2), "trigger": a.trigger,
                               "requested": {"front": a.front_overlap, "side": a.side_overlap},
                               "coverage": {}, "overlap": {}, "photos": {}}
        for pname in a.payloads:
            pay = compiled.payload(pname)
            m = _measure_area(a, pay, photos_of.get(pname, []), sim, path)
            row["coverage"][pname] = _r(m["coverage"], 5)
            row["overlap"][pname] = {"front_min": _r(m["front_min"]), "side_min": _r(m["side_min"])}
            row["photos"][pname] = m["photos"]
            row["outside_m"] = _r(m["outside_m"], 1)
            row["over_gaps_m"] = _r(m["over_gaps_m"], 1)
            row["over_gaps_camera_m"] = _r(m["over_gaps_camera_m"], 1)
            row.setdefault("photos_in_zones", {})[pname] = m["photos_in_zones"]
            cov_acc.setdefault(pname, []).append((m["coverage"], a.area.area_m2))
            acc = ov_acc.setdefault(pname, {"front": [], "side": []})
            if m["front_min"] is not None:
                acc["front"].append(m["front_min"])
            if m["side_min"] is not None:
                acc["side"].append(m["side_min"])
            where = f"step {a.step} ({a.kind}), payload {pname}"
            if m["coverage"] < COVERAGE_TARGET:
                warnings.append({"code": "coverage_low",
                                 "message": f"{where}: measured coverage {100 * m['coverage']:.2f} % "
                                            f"(target {100 * COVERAGE_TARGET:.1f} %)"})
            if a.trigger != "hover" and m["front_min"] is not None and m["front_min"] < a.front_overlap - OVERLAP_SLACK:
                warnings.append({"code": "front_overlap_low",
                                 "message": f"{where}: minimum front overlap {100 * m['front_min']:.1f} % "
                                            f"< requested {100 * a.front_overlap:.0f} %"})
            if m["side_min"] is not None and m["side_min"] < a.side_overlap - OVERLAP_SLACK:
                warnings.append({"code": "side_overlap_low",
                                 "message": f"{where}: minimum side overlap {100 * m['side_min']:.1f} % "
                                            f"< requested {100 * a.side_overlap:.0f} %"})
        if row.get("over_gaps_m", 0) > 1.0:
            warnings.append({"code": "path_over_exclusion", "message": _over_zones_text(a, row)})
        area_rows.append(row)
    coverage = {n: _r(sum(c * A for c, A in v) / sum(A for _, A in v), 5) if sum(A for _, A in v) > 0 else 0.0
                for n, v in cov_acc.items()}
    overlap = {n: {"front_min": _r(min(v["front"])) if v["front"] else None,
                   "side_min": _r(min(v["side"])) if v["side"] else None} for n, v in ov_acc.items()}

    gsd = {}
    for n in names:
        ph = photos_of[n]
        if ph:
            pay = compiled.payload(n)
            alts = [p.alt_m for p in ph if p.alt_m > 0]
            gsd[n] = [_r(pay.gsd_cm(min(alts)), 3), _r(pay.gsd_cm(max(alts)), 3)] if alts else None
        else:
            gsd[n] = None

    # safety and feasibility
    max_alt = max((v.alt_m for v in sim.vertices), default=0.0)
    high = [v for v in sim.vertices if v.alt_m > MAX_AGL_M + 1e-6]
    if high:
        v = max(high, key=lambda v: v.alt_m)
        warnings.append({"code": "altitude_above_120m",
                         "message": f"item {v.item + seq_base} flies at {v.alt_m:.1f} m above home, above the "
                                    f"{MAX_AGL_M:.0f} m most rules allow without a permit"})
    for code, msg in sim.notes:
        warnings.append({"code": code, "message": msg})
    if compiled.items and not sim.ends_on_ground:
        warnings.append({"code": "no_landing", "message": "the mission ends in the air (no RTL or LAND): the "
                                                           "vehicle will hold at the last waypoint"})
    if len(compiled.parts) > 1 and not any(w["code"] == "mission_split" for w in warnings):
        warnings.append({"code": "mission_split",
                         "message": f"{len(compiled.items)} items exceed the limit of {compiled.item_limit}: "
                                    f"split into {len(compiled.parts)} parts, flown one after another"})
    for k, part in enumerate(compiled.parts):
        if len(part) > compiled.item_limit:
            errors.append({"code": "item_limit",
                           "message": f"part {k + 1} has {len(part)} items, more than the limit of {compiled.item_limit}"})
    if not compiled.items:
        errors.append({"code": "empty_mission", "message": "the mission has no items"})
    fast: dict[str, list[tuple[float, int]]] = {}
    for pname, _value, secs, src in sim.trigger_intervals:
        pay = compiled.payload(pname)
        if pay.min_interval_s and secs < pay.min_interval_s - 1e-9:
            fast.setdefault(pname, []).append((secs, src))
    for pname, spans in fast.items():
        secs, src = min(spans)
        pay = compiled.payload(pname)
        warnings.append({"code": "trigger_interval_short",
                         "message": f"{pname} would shoot every {secs:.2f} s ("
                                    + (f"item {src + seq_base}" if src >= 0 else "its own overlap mode")
                                    + (f" and {len(spans) - 1} more camera-on legs" if len(spans) > 1 else "")
                                    + f"), faster than the camera's minimum of {pay.min_interval_s:g} s at "
                                      f"{compiled.speed_mps:g} m/s — photos will be lost; fly slower or reduce "
                                      "the front overlap"})
    if not any(w["code"] == "assumed_optics" for w in warnings):
        warnings.extend(_optics_warnings(compiled))

    return {
        "plan": plan_path or compiled.name,
        "name": compiled.name,
        "firmware": compiled.firmware,
        "frame": compiled.frame,
        "mission_items": len(compiled.items),
        "item_limit": compiled.item_limit,
        "parts": len(compiled.parts),
        "part_items": [len(p) for p in compiled.parts],
        "photos": {n: len(photos_of[n]) for n in names},
        "path_length_m": _r(sim.path_length_m, 1),
        "climb_m": _r(sim.climb_m, 1),
        "flight_time_s": _r(sim.flight_time_s, 1),
        "flight_time_qgc_s": _r(sim.flight_time_qgc_s, 1),
        "max_altitude_m": _r(max_alt, 2),
        "area_m2": _r(sum(a.area.area_m2 for a in compiled.areas), 1),
        "gsd_cm": gsd,
        "coverage": coverage,
        "overlap": overlap,
        "areas": area_rows,
        "warnings": warnings,
        "errors": errors,
    }


def _over_zones_text(a: Any, row: dict) -> str:
    """The path_over_exclusion message: how much, and on what — camera-on legs or the flight between them."""
    total, cam = row["over_gaps_m"], row.get("over_gaps_camera_m") or 0.0
    shots = ", ".join(f"{n} {k}" for n, k in (row.get("photos_in_zones") or {}).items() if k)
    parts = []
    if cam > 0.05:
        parts.append(f"{cam:.1f} m on camera-on legs" + (f" (photos centred inside: {shots})" if shots else ""))
    if total - cam > 0.05:
        parts.append(f"{total - cam:.1f} m with the camera off: turnarounds, connections, transits, take-off or "
                     "return")
    return (f"step {a.step} ({a.kind}): the flown path runs {total:.0f} m inside the area's holes or exclusion "
            f"zones — {'; '.join(parts)}. Check that overflight is allowed")


def _compiler_warning(text: str) -> dict:
    """The compiler's warnings are "code: message" strings; keep its code."""
    import re
    m = re.match(r"([a-z][a-z0-9_]*): (.*)", text, re.S)
    return {"code": m.group(1), "message": m.group(2)} if m else {"code": "compiler", "message": text}


def _optics_warnings(compiled: Compiled) -> list[dict]:
    out = []
    try:
        from cdf.catalogue import catalogue
        cat = catalogue()
    except Exception:  # the catalogue is checked by its own tests; a report still comes out without it
        return out
    for p in compiled.payloads:
        try:
            imager = cat.get(p.camera_id).imager(p.imager)
        except Exception:
            continue
        if imager is not None and imager.assumed:
            out.append({"code": "assumed_optics",
                        "message": f"{p.name}: {', '.join(imager.assumed)} of {p.camera_id}/{p.imager} are assumed, "
                                   "not from a published source — footprints, GSD and overlap depend on them; "
                                   "check them against your camera's datasheet"})
    return out


# --------------------------------------------------------------------------------------------- text forms

def summary_lines(rep: dict) -> list[str]:
    """A few lines for `wiris mission compile`."""
    mins, secs = divmod(int(round(rep["flight_time_s"] or 0)), 60)
    lines = [f"{rep['name']}: {rep['firmware']} {rep['frame']}, {rep['mission_items']} items "
             f"(limit {rep['item_limit']}, {rep['parts']} part{'s' if rep['parts'] != 1 else ''}), "
             f"{rep['path_length_m'] / 1000:.2f} km, ~{mins} min {secs:02d} s"]
    for name, n in rep["photos"].items():
        extra = ""
        if name in rep["coverage"]:
            ov = rep["overlap"][name]
            f = "–" if ov["front_min"] is None else f"{100 * ov['front_min']:.1f} %"
            s = "–" if ov["side_min"] is None else f"{100 * ov['side_min']:.1f} %"
            extra = f", coverage {100 * rep['coverage'][name]:.2f} %, min overlap front {f} side {s}"
        lines.append(f"  {name}: {n} photos{extra}")
    for w in rep["warnings"]:
        lines.append(f"warning [{w['code']}]: {w['message']}")
    for e in rep["errors"]:
        lines.append(f"error [{e['code']}]: {e['message']}")
    return lines


def format_report(rep: dict) -> str:
    """The human-readable report of `wiris mission check`."""
    rows = [("plan", rep["plan"]), ("firmware", f"{rep['firmware']} {rep['frame']}"),
            ("mission items", f"{rep['mission_items']} (limit {rep['item_limit']}; "
                              + ("fits in one upload)" if rep["parts"] == 1 else
                                 f"{rep['parts']} parts of {', '.join(str(n) for n in rep['part_items'])} items)")),
            ("path length", f"{rep['path_length_m']:.0f} m (climb {rep['climb_m']:.0f} m)"),
            ("flight time", f"{rep['flight_time_s'] / 60:.1f} min (QGC's estimate: {rep['flight_time_qgc_s'] / 60:.1f} min)"),
            ("highest point", f"{rep['max_altitude_m']:.1f} m above home"),
            ("area", f"{rep['area_m2']:.0f} m² ({rep['area_m2'] / 10000:.2f} ha)" if rep["area_m2"] else
                     "none (no survey or corridor)")]
    for name, n in rep["photos"].items():
        g = rep["gsd_cm"].get(name)
        gs = "" if not g else (f", GSD {g[0]:.2f} cm/px" if abs(g[1] - g[0]) < 0.005 else f", GSD {g[0]:.2f}–{g[1]:.2f} cm/px")
        rows.append((f"photos {name}", f"{n}{gs}"))
    for name, c in rep["coverage"].items():
        ov = rep["overlap"][name]
        f = "–" if ov["front_min"] is None else f"{100 * ov['front_min']:.1f} %"
        s = "–" if ov["side_min"] is None else f"{100 * ov['side_min']:.1f} %"
        rows.append((f"coverage {name}", f"{100 * c:.2f} % (minimum overlap: front {f}, side {s})"))
    for a in rep.get("areas", []):
        rows.append((f"step {a['step']} {a['kind']}", f"{a['area_m2']:.0f} m² at {a['altitude_m']:g} m, "
                                                      f"{a.get('outside_m', 0):.0f} m flown outside the area"))
    width = max(len(k) for k, _ in rows)
    out = [f"{k.ljust(width)}  {v}" for k, v in rows]
    for w in rep["warnings"]:
        out.append(f"warning [{w['code']}]: {w['message']}")
    for e in rep["errors"]:
        out.append(f"error [{e['code']}]: {e['message']}")
    if not rep["warnings"] and not rep["errors"]:
        out.append("no warnings")
    return "\n".join(out)


def error_report(plan_path: str, err: Exception) -> dict:
    """`check --json` for a plan that does not compile: the binding keys, nothing measured, the errors located."""
    problems = getattr(err, "problems", None) or [err]
    errors = [{"code": "plan", "message": getattr(p, "message", str(p)), "where": getattr(p, "where", None),
               "hint": getattr(p, "hint", None)} for p in problems]
    return {"plan": plan_path, "firmware": None, "mission_items": 0, "item_limit": None, "parts": 0, "photos": {},
            "path_length_m": None, "flight_time_s": None, "area_m2": None, "gsd_cm": {}, "coverage": {},
            "overlap": {}, "warnings": [], "errors": errors}
