"""Mission items per firmware × camera: the one place that turns planned geometry and plan steps into
MISSION_ITEM_INT values. Every command choice cites the reference's acceptance matrix
(shared/reference/autopilots-and-cameras.md §7, survey-planners-and-mission-protocol.md §1.6/§7).

Conventions of every emitted item:
- positions in FRAME_GLOBAL_RELATIVE_ALT (altitude above home, as the plan gives it); DO/condition items in
  FRAME_MISSION with params 5/6 as int32 zeros (MISSION_ITEM_INT cannot carry NaN there, reference §4.2);
- yaw/reserved float params that mean "unchanged" are NaN, as QGroundControl writes them (survey-planners §1.6).

Triggering (one DO_SET_CAM_TRIGG_DIST per camera-on segment; PX4's camera_trigger sends each shot to
components 100..105, reference §3.2; ArduPilot distance-triggers only its primary AP_Camera instance —
AP_Camera::set_trigger_distance() — so the compiler refuses two WIRIS on one distance-triggered ArduPilot survey):
- distance: DO_SET_CAM_TRIGG_DIST(d, 0, 1) after the entry waypoint (param3 = 1: one photo at once, QGC
  does the same, survey-planners §1.6), DO_SET_CAM_TRIGG_DIST(0, 0, 0) after the exit waypoint;
- interval: PX4 only (ArduPilot rejects DO_SET_CAM_TRIGG_INTERVAL at upload): DO_SET_CAM_TRIGG_INTERVAL(ms)
  + DO_TRIGGER_CONTROL(1) at the entry, DO_TRIGGER_CONTROL(0) at the exit (PX4 camera_trigger, reference §3.2);
- hover: a waypoint with a hold and one IMAGE_START_CAPTURE(total 1) — on ArduPilot param1 is the AP_Camera
  instance (0 = all, n = CAMn), on PX4 the target component (common.xml 7..255; PX4 ≥ PR #23115; PX4 turns
  a single shot into DO_DIGICAM_CONTROL for every camera, reference §3.2). On PX4 the waypoint's yaw (param4)
  is its line's heading; ArduPilot drops it, and faces the line because the route arrives along it.
- A RedEdge is never triggered by the mission: it takes COMMAND_LONG neither for 203 nor 2000 (reference
  §0.4); it captures itself in overlap mode (missions.emit.setup) from the GPS the autopilot streams to it.

In-flight camera changes (`camera` steps): PX4 takes SET_CAMERA_MODE and DO_DIGICAM_CONTROL in missions and
forwards them; ArduPilot takes neither USER_1/2 nor SET_CAMERA_MODE, and its MAVLinkCamV2 backend (CAMx_TYPE 6,
the one that finds a WIRIS by its MAV_TYPE_CAMERA heartbeat) does not forward DIGICAM settings, so on
ArduPilot every change goes through the Lua bridge (missions.emit.lua). USER_1/2 on PX4 is an error naming the rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, Sequence

from missions.compiled import PlanWarning
from missions.errors import PlanError
from missions.emit.firmware import FirmwareProfile
from missions.emit.trigger_distance import commanded_trigger_distance
from missions.geometry.geo import great_circle_m
from missions.emit.items import FRAME_GLOBAL, FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem, deg_to_e7, mavlink
from missions.emit import lua as bridge
from missions.emit.setup import commands_for

NAN = math.nan
TAKEOFF_PITCH_DEG = 15.0       # fixed-wing minimum climb pitch of NAV_TAKEOFF param1 (ArduPlane, PX4)
HOVER_HOLD_S = 4.0             # QGC's hover-and-capture delay (survey-planners §1.4)
BRIDGE_PAUSE_S = 1.0           # hold between Lua bridge batches so the 5-item script queue drains
# Steepest fixed-wing landing approach accepted: PX4 refuses a mission whose glide from the waypoint before
# NAV_LAND is steeper than FW_LND_ANG (default 5°; FeasibilityChecker::checkFixedWindLandApproach), and an
# ArduPlane given no approach dives onto the point. 5° is a normal glide slope for small fixed-wings.
MAX_GLIDE_DEG = 5.0


@dataclass(frozen=True)
class TrackPoint:
    lat: float
    lon: float
    kind: str                  # turnaround | entry | exit | via | photo
    yaw_deg: float | None = None   # a hover photo's heading from true north (its line's), where the firmware takes it


@dataclass(frozen=True)
class Track:
    """A survey or corridor as it will be flown: ordered points and the camera-on spans."""

    points: tuple[TrackPoint, ...]
    spans: tuple[tuple[int, int], ...]          # (entry index, exit index) into points
    altitude_m: float
    trigger: str                                # distance | interval | hover
    trigger_distance_m: float
    interval_s: float | None = None
    hold_s: float = HOVER_HOLD_S
    # False when only RedEdges fly it: they capture themselves (overlap mode), no trigger items are emitted
    autopilot_triggers: bool = True
    # Terrain following (missions.terrain.lines): the points' frame, and with it each point's own altitude
    # (above mean sea level in FRAME_GLOBAL); None: every point at altitude_m
    frame: int = FRAME_GLOBAL_RELATIVE_ALT
    altitudes: tuple[float, ...] | None = None
    over_tolerance_m: float = 0.0              # how far above its band the climb/descent rates forced it
    highest_agl_m: float | None = None         # the most it rises above the ground (None: not followed)

    def altitude_of(self, i: int) -> float:
        return self.altitudes[i] if self.altitudes is not None else self.altitude_m


@dataclass
class _State:
    """Mutable bookkeeping of one emission run (local to `Emitter`, never shared)."""

    items: list[MissionItem] = field(default_factory=list)
    last_pos: tuple[float, float, float] | None = None
    last_frame: int = FRAME_GLOBAL_RELATIVE_ALT    # the frame last_pos's altitude is in
    script_run: int = 0        # script items since the last NAV item
    lua: bool = False
    warnings: list[PlanWarning] = field(default_factory=list)
    speed_set: bool = False
    track_navs: tuple[int, ...] = ()    # the item index of each point of the last track (`Emitter.track`)


@dataclass(frozen=True)
class Emitted:
    items: tuple[MissionItem, ...]
    needs_lua: bool
    warnings: tuple[PlanWarning, ...]


def _do(command: int, p1: float = 0.0, p2: float = 0.0, p3: float = 0.0, p4: float = 0.0, x: int = 0, y: int = 0,
        z: float = 0.0, comment: str = "") -> MissionItem:
    return MissionItem(command=command, frame=FRAME_MISSION, param1=float(p1), param2=float(p2), param3=float(p3),
                       param4=float(p4), x=int(x), y=int(y), z=float(z), comment=comment)


def _nav(command: int, lat: float, lon: float, alt: float, p1: float = 0.0, p2: float = 0.0, p3: float = 0.0,
         p4: float = NAN, comment: str = "", frame: int = FRAME_GLOBAL_RELATIVE_ALT) -> MissionItem:
    # ArduPilot stores mission altitudes in whole centimetres: a finer altitude reads back different and
    # would fail an upload's --verify, so emit what the vehicle will hold.
    return MissionItem(command=command, frame=frame, param1=float(p1), param2=float(p2),
                       param3=float(p3), param4=float(p4), x=deg_to_e7(lat), y=deg_to_e7(lon),
                       z=round(float(alt), 2), comment=comment)


def _unmet_hint(cam: Any, values: Sequence[tuple[str, Any]], state: dict) -> str:
    """Hint for settings that `commands_for` left out: the settings whose values their `when` needs."""
    need: list[str] = []
    for key, _ in values:
        s = cam.setting(key)
        for wkey, wval in (s.command.when if s is not None and s.command is not None else ()):
            if state.get(wkey) != wval:
                text = f"{wkey}: {cam.option_key(wkey, wval)}"
                if text not in need:
                    need.append(text)
    if need:
        return f"add {', '.join(need)} to this step or to the payload's settings"
    return "a bug in wiris-tools: please report it with the plan"


class Emitter:
    """Builds the item list step by step. One instance per compile (no module-level state)."""

    def __init__(self, profile: FirmwareProfile, frame: str, speed_mps: float, home: tuple[float, float],
                 cameras: dict[str, Any], component_ids: dict[str, int], instances: dict[str, int],
                 preflight: dict[str, dict] | None = None) -> None:
        self.profile = profile
        self.frame = frame
        self.speed_mps = speed_mps
        self.home = home
        self.cameras = cameras                  # payload name -> catalogue Camera
        self.component_ids = component_ids      # payload name -> component id
        self.instances = instances              # payload name -> ArduPilot CAMn instance (WIRIS only)
        # what each camera holds: the pre-flight settings (setup.json), then every in-flight change; an
        # in-flight value whose `when` a pre-flight setting meets travels (the plan loader judges alike)
        self.camera_state: dict[str, dict] = {name: dict(v) for name, v in (preflight or {}).items()}
        self.s = _State()
        # home's elevation, for a height above home from an altitude above mean sea level (terrain-following
        # lines emit FRAME_GLOBAL); None: every position is relative
        self.home_amsl_m: float | None = None

    # ------------------------------------------------------------------------------------------ plumbing
    def _add(self, item: MissionItem) -> None:
        self.s.items.append(item)
        if item.frame != FRAME_MISSION:
            self.s.script_run = 0
            if item.x or item.y:
                self.s.last_pos = (item.lat, item.lon, item.z)
                self.s.last_frame = item.frame

    def result(self) -> Emitted:
        return Emitted(tuple(self.s.items), self.s.lua, tuple(self.s.warnings))

    @property
    def item_count(self) -> int:
        """Items emitted so far: a step's items are [count before it, count after it)."""
        return len(self.s.items)

    # ------------------------------------------------------------------------------------------ steps
    def takeoff(self, alt_m: float) -> None:
        lat, lon = self.home
        if self.frame == "vtol":
            # NAV_VTOL_TAKEOFF: both stacks take off vertically, then transition toward the next waypoint.
            self._add(_nav(mavlink.MAV_CMD_NAV_VTOL_TAKEOFF, lat, lon, alt_m, comment="VTOL take-off"))
        elif self.frame == "plane":
            self._add(_nav(mavlink.MAV_CMD_NAV_TAKEOFF, lat, lon, alt_m, p1=TAKEOFF_PITCH_DEG,
                           comment="take-off (param1 minimum pitch)"))
        else:
            # ArduCopter climbs where it stands (lat/lon ignored); PX4 uses them: home is where it stands.
            self._add(_nav(mavlink.MAV_CMD_NAV_TAKEOFF, lat, lon, alt_m, comment="take-off"))
        self.set_speed()

    @property
    def speed_is_airspeed(self) -> bool:
        """ArduPlane (and QuadPlane in forward flight) reads a ground-speed DO_CHANGE_SPEED as its *minimum*
        ground speed (Plane::do_change_speed sets MIN_GNDSPD, which stays after the mission, RTL included) and
        keeps its cruise airspeed: the plan's speed has to be its airspeed there."""
        return self.profile.name == "ardupilot" and self.frame in ("plane", "vtol")

    @property
    def keeps_waypoint_yaw(self) -> bool:
        """NAV_WAYPOINT's param4 (yaw) is flown: PX4 keeps it (mavlink_mission.cpp -> mission_item.yaw; a finite
        yaw is the heading setpoint, over MPC_YAW_MODE). ArduPilot's AP_Mission stores only a waypoint's hold time
        and drops the yaw at upload; there the route's turnaround stubs set a hover photo's heading."""
        return self.profile.name == "px4"

    def set_speed(self) -> None:
        # param1 SPEED_TYPE_GROUNDSPEED: the plan's speed is over ground (photo spacing depends on it), except
        # where it can only be an airspeed (above); param3 -1 = throttle unchanged.
        kind = mavlink.SPEED_TYPE_AIRSPEED if self.speed_is_airspeed else mavlink.SPEED_TYPE_GROUNDSPEED
        what = "airspeed" if self.speed_is_airspeed else "survey speed"
        self._add(_do(mavlink.MAV_CMD_DO_CHANGE_SPEED, float(kind), self.speed_mps, -1.0,
                      comment=f"{what} {self.speed_mps:g} m/s"))
        self.s.speed_set = True

    def track(self, t: Track, where: str | None = None) -> None:
        if not self.s.speed_set:
            self.set_speed()
        navs: list[int] = []
        if not t.autopilot_triggers:
            for i, p in enumerate(t.points):
                navs.append(len(self.s.items))
                self._add(_nav(mavlink.MAV_CMD_NAV_WAYPOINT, p.lat, p.lon, t.altitude_of(i),
                               comment=f"{p.kind} (RedEdge captures itself)", frame=t.frame))
            self.s.track_navs = tuple(navs)
            return
        if t.trigger == "interval" and not self.profile.interval_trigger:
            raise PlanError(f"trigger: interval cannot be flown on {self.profile.title}", where=where,
                            hint=self.profile.rule(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL))
        starts = {a for a, _ in t.spans}
        stops = {b for _, b in t.spans}
        for i, p in enumerate(t.points):
            navs.append(len(self.s.items))
            if t.trigger == "hover" and p.kind == "photo":
                yaw = p.yaw_deg if p.yaw_deg is not None and self.keeps_waypoint_yaw else NAN
                self._add(_nav(mavlink.MAV_CMD_NAV_WAYPOINT, p.lat, p.lon, t.altitude_of(i), p1=t.hold_s, p4=yaw,
                               comment=f"hover {t.hold_s:g} s and shoot"
                                       + ("" if math.isnan(yaw) else f" facing {yaw:.1f}°"), frame=t.frame))
                self._add(self._capture(None, where))
                continue
            self._add(_nav(mavlink.MAV_CMD_NAV_WAYPOINT, p.lat, p.lon, t.altitude_of(i), comment=p.kind, frame=t.frame))
            if i in starts and t.trigger != "hover":
                self._trigger_on(t)
            if i in stops and t.trigger != "hover":
                self._trigger_off(t)
        self.s.track_navs = tuple(navs)

    def _trigger_on(self, t: Track, shoot_now: bool = True) -> None:
        if t.trigger == "interval":
            ms = round(t.interval_s * 1000.0)
            self._add(_do(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, ms, 0.0, 0.0,
                          comment=f"camera every {ms} ms (PX4 camera_trigger)"))
            self._add(_do(mavlink.MAV_CMD_DO_TRIGGER_CONTROL, 1.0, -1.0, -1.0, comment="camera trigger on"))
        else:
            # the firmware fires up to one distance check late: see missions.emit.trigger_distance
            d = commanded_trigger_distance(self.profile.name, self.frame, t.trigger_distance_m, self.speed_mps,
                                           self.home[0])
            self._add(_do(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST, d, 0.0, 1.0 if shoot_now else 0.0,
                          comment=f"camera every {d:.2f} m, one photo now"))

    def _trigger_off(self, t: Track) -> None:
        if t.trigger == "interval":
            self._add(_do(mavlink.MAV_CMD_DO_TRIGGER_CONTROL, 0.0, -1.0, -1.0, comment="camera trigger off"))
        else:
            self._add(_do(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST, 0.0, 0.0, 0.0, comment="camera off"))

    def waypoint(self, lat: float, lon: float, alt_m: float, hold_s: float, capture: str | None,
                 where: str | None = None) -> None:
        self._add(_nav(mavlink.MAV_CMD_NAV_WAYPOINT, lat, lon, alt_m, p1=hold_s,
                       comment=f"waypoint, hold {hold_s:g} s" if hold_s else "waypoint"))
        if capture is not None:
            self._add(self._capture(capture, where))

    def via(self, lat: float, lon: float, alt_m: float) -> None:
        """A waypoint of a transit routed round a no-fly zone (missions.geometry.zones)."""
        self._add(_nav(mavlink.MAV_CMD_NAV_WAYPOINT, lat, lon, alt_m, comment="via (round a no-fly zone)"))

    def _capture(self, payload: str | None, where: str | None) -> MissionItem:
        """One photo: IMAGE_START_CAPTURE(total 1). `payload` None = every camera."""
        if payload is not None and self.cameras[payload].protocol == "rededge-serial":
            raise PlanError(f"the mission cannot make the RedEdge ({payload}) take a photo", where=where,
                            hint="the RedEdge takes neither IMAGE_START_CAPTURE nor DO_DIGICAM_CONTROL as "
                                 "COMMAND_LONG (its serial API has only the DIGICAM_CONTROL message); it captures "
                                 "itself in overlap or timer mode — capture with a WIRIS payload here")
        if payload is None:
            target = 0.0          # 0 = all cameras on both stacks
            note = "every camera"
        elif self.profile.camera_target == "instance":
            target = float(self.instances[payload])
            note = f"ArduPilot camera instance {int(target)} ({payload})"
        else:
            target = float(self.component_ids[payload])
            note = f"component {int(target)} ({payload})"
            others = [n for n, c in self.cameras.items() if n != payload and c.protocol != "rededge-serial"]
            if others:
                self.s.warnings.append(
                    PlanWarning("px4_single_capture_all", "PX4 turns a single IMAGE_START_CAPTURE into "
                                "DO_DIGICAM_CONTROL for every camera (reference §3.2), so "
                                f"{', '.join(others)} may shoot too at {where or 'a capture'}"))
        return _do(mavlink.MAV_CMD_IMAGE_START_CAPTURE, target, 0.0, 1.0, 0.0, 0, 0, NAN, comment=f"one photo: {note}")

    def camera_change(self, payload: str, values: Sequence[tuple[str, Any]], where: str | None = None) -> None:
        cam = self.cameras[payload]
        comp = self.component_ids[payload]
        if cam.protocol == "rededge-serial":
            raise PlanError(f"RedEdge ({payload}) settings cannot change in flight", where=where,
                            hint="they are PARAM_SET messages, which no mission item carries; put them in the "
                                 "payload's settings (pre-flight)")
        state = self.camera_state.setdefault(payload, {})
        cmds = commands_for(cam, values, state)
        state.update(dict(values))
        if not cmds:
            raise PlanError(f"none of these settings reaches {cam.id} by a command", where=where,
                            hint=_unmet_hint(cam, values, state))
        if self.s.last_pos is None:
            raise PlanError("an in-flight camera change before the vehicle has a position", where=where,
                            hint="put settings for the start in the payload's settings (they are applied pre-flight)")
        for cmd in cmds:
            if cmd.command in ("MAV_CMD_IMAGE_START_CAPTURE", "MAV_CMD_VIDEO_START_CAPTURE"):
                keys = ", ".join(cmd.keys)
                raise PlanError(f"{keys} cannot change in flight", where=where,
                                hint=f"{cmd.command} carries {keys} and also "
                                     f"{'takes a photo' if 'IMAGE' in cmd.command else 'starts recording'}; "
                                     "set it in the payload's settings (pre-flight)")
            if self.profile.script_messages:
                self._bridge(cmd, comp, payload)
            else:
                self._px4_camera_item(cmd, cam, comp, payload, where)

    def _bridge(self, cmd, comp: int, payload: str) -> None:
        items = bridge.encode(bridge.BridgeCommand(cmd.command, comp, cmd.params),
                              comment=f"Lua bridge: {cmd.command.removeprefix('MAV_CMD_')} "
                                      f"({', '.join(cmd.keys)}) to {payload}")
        for it in items:
            if self.s.script_run >= bridge.QUEUE_SIZE:
                lat, lon, alt = self.s.last_pos
                self._add(_nav(mavlink.MAV_CMD_NAV_LOITER_TIME, lat, lon, alt, p1=BRIDGE_PAUSE_S, p4=0.0,
                               comment="pause so the Lua bridge drains its 5-item queue", frame=self.s.last_frame))
            self._add(it)
            self.s.script_run += 1
        self.s.lua = True

    def _px4_camera_item(self, cmd, cam: Any, comp: int, payload: str, where: str | None) -> None:
        cid = cmd.command_id
        if not self.profile.accepts(cid):
            keys = ", ".join(cmd.keys)
            raise PlanError(f"{keys} cannot change in flight on {self.profile.title}", where=where,
                            hint=f"{self.profile.rule(cid)}. Set {keys} in the payload's settings (the pre-flight "
                                 "sequence sends them as COMMAND_LONG), fly ArduPilot (Lua bridge), or send it "
                                 "from a companion computer")
        params = list(cmd.params)
        if cmd.command == "MAV_CMD_SET_CAMERA_MODE":
            params[0] = float(comp)      # target camera id = component (PX4 ≥ PR #23115 forwards to it)
        xy = []
        for idx in (4, 5):
            v = params[idx]
            if v is None:
                # keep: int32 slots cannot hold NaN; the manual's 0 = keep where the catalogue says so
                if not self._zero_keeps(cam, cmd.command, idx + 1):
                    raise PlanError(f"{cmd.command} param {idx + 1} cannot say 'keep' in a mission item",
                                    where=where, hint="set that setting too, or change it pre-flight")
                xy.append(0)
            else:
                if v != int(v):
                    raise PlanError(f"{cmd.command} param {idx + 1} = {v} must be whole in a mission item",
                                    where=where, hint="a bug in wiris-tools or its camera table (the slot is an "
                                                      "int32): please report it with the plan")
                xy.append(int(v))
        p = [NAN if v is None else float(v) for v in params]
        self._add(_do(cid, p[0], p[1], p[2], p[3], xy[0], xy[1], p[6],
                      comment=f"{cmd.command.removeprefix('MAV_CMD_')} ({', '.join(cmd.keys)}) to {payload}"))

    @staticmethod
    def _zero_keeps(cam: Any, command: str, param: int) -> bool:
        slots = [s.command for s in cam.settings if s.command and s.command.cmd == command and s.command.param == param]
        if command == "MAV_CMD_DO_DIGICAM_CONTROL" and param in (5, 6):
            return True   # p5 shoot 0 = no photo, p6 command identity unused (manual §6.3.2.2)
        return bool(slots) and all("0" in s.keep for s in slots)

    def rtl(self) -> None:
        self._add(MissionItem(command=mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=FRAME_MISSION,
                              comment="return to launch"))

    def _check_glide(self, lat: float, lon: float, where: str | None) -> None:
        plat, plon, alt = self.s.last_pos
        if self.s.last_frame == FRAME_GLOBAL and self.home_amsl_m is not None:
            alt -= self.home_amsl_m
        dist = great_circle_m(plat, plon, lat, lon)
        need = alt / math.tan(math.radians(MAX_GLIDE_DEG))
        if alt > 0 and dist < need:
            angle = 90.0 if dist <= 0 else math.degrees(math.atan2(alt, dist))
            raise PlanError(f"a fixed-wing landing from {alt:g} m over {dist:.0f} m is a {angle:.1f}° glide: PX4 "
                            f"refuses the mission (FW_LND_ANG, default {MAX_GLIDE_DEG:g}°) and ArduPlane would dive",
                            where=where,
                            hint=f"end with `rtl: {{}}` (the autopilot flies home by its own rules), or give the "
                                 f"landing point (land: {{lat: ..., lon: ...}}) at least {need:.0f} m from the last "
                                 "waypoint, into the wind")

    def land(self, lat: float | None, lon: float | None, where: str | None = None) -> None:
        if lat is None or lon is None:
            if self.s.last_pos is None:
                raise PlanError("land needs lat/lon when the vehicle has no position yet", where=where,
                                hint="give the landing point (land: {lat: 50.11, lon: 14.50}) or put a takeoff "
                                     "before it")
            lat, lon = self.s.last_pos[0], self.s.last_pos[1]
        if self.frame == "plane" and self.s.last_pos is not None:
            self._check_glide(lat, lon, where)
        cmd = mavlink.MAV_CMD_NAV_VTOL_LAND if self.frame == "vtol" else mavlink.MAV_CMD_NAV_LAND
        self._add(_nav(cmd, lat, lon, 0.0, comment="land"))
