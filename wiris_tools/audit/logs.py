"""What a flight left, read into one typed record: the photos the camera reported, the triggers the autopilot
logged, the track, the attitude and the mode changes.

    log = read_log("flight.tlog")        # a ground station's tlog, a DataFlash .BIN or a PX4 .ulg
    log.captures, log.triggers, log.track, log.modes, log.notes

pymavlink reads tlogs and DataFlash logs, pyulog reads ULogs: no hand-written parser. Nothing is invented: a
log without camera acknowledgements has no captures (a DataFlash log records triggers only), one without an
attitude gives photos without a heading, and what the reader could not know is said in `notes`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Sequence

from wiris_tools.errors import LinkError

# A clock that jumps back, or forward by more than this between two messages, is a log of two flights or a
# reset clock: times across the jump do not pair photos with positions.
CLOCK_JUMP_S = 600.0


@dataclass(frozen=True)
class Pose:
    """Where the vehicle was at `time_s`: WGS84, metres above home, degrees (heading clockwise from north)."""

    time_s: float
    lat: float
    lon: float
    alt_rel_m: float | None
    heading_deg: float | None = None
    pitch_deg: float | None = None
    roll_deg: float | None = None


@dataclass(frozen=True)
class Shot:
    """One photo event: a capture the camera reported or a trigger the autopilot logged."""

    pose: Pose
    seq: int | None             # image index / trigger number as logged
    source: str                 # the message it came from: CAMERA_IMAGE_CAPTURED, CAMERA_FEEDBACK, CAM, TRIG, ...
    ok: bool = True             # the camera reported success (CAMERA_IMAGE_CAPTURED.capture_result)
    # the pose's heading, pitch and roll are the camera's own (its image's gimbal angles: pitch is the tilt from
    # straight down), not the airframe's: they place the footprint whatever the mount
    oriented: bool = False
    flight: int = 0             # which of several logs audited together it came from (their lines stay apart)


@dataclass(frozen=True)
class ModeChange:
    time_s: float
    mode: str
    armed: bool


@dataclass(frozen=True)
class FlightLog:
    path: str
    kind: str                            # "tlog" | "dataflash" | "ulog"
    captures: tuple[Shot, ...]           # the camera's own reports (None-free positions)
    triggers: tuple[Shot, ...]           # the autopilot's trigger records
    track: tuple[Pose, ...]
    modes: tuple[ModeChange, ...]        # each change of mode or of the armed state, in time order
    mission_seq: tuple[tuple[float, int], ...]   # (time, current mission item) at each change
    notes: tuple[str, ...]               # what the log could not tell, clock jumps, a truncated end

    @property
    def start_s(self) -> float | None:
        return self.track[0].time_s if self.track else None

    @property
    def end_s(self) -> float | None:
        return self.track[-1].time_s if self.track else None


def _yaw_pitch_roll(q: Sequence[float]) -> tuple[float, float, float] | None:
    """(heading, pitch, roll) in degrees of the quaternion w, x, y, z (NED body to earth); None if it is unset."""
    w, x, y, z = (float(v) for v in q)
    if not all(math.isfinite(v) for v in (w, x, y, z)) or abs(w * w + x * x + y * y + z * z - 1.0) > 0.1:
        return None
    roll = math.degrees(math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x)))))
    yaw = math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))) % 360.0
    return yaw, pitch, roll


class _Attitudes:
    """Attitude samples in time order; `at(t)` gives the nearest within a second (None: none that near)."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.v: list[tuple[float, float, float]] = []

    def add(self, t: float, heading: float, pitch: float, roll: float) -> None:
        self.t.append(t)
        self.v.append((heading % 360.0, pitch, roll))

    def at(self, t: float) -> tuple[float, float, float] | None:
        import bisect
        k = bisect.bisect_left(self.t, t)
        best = min((j for j in (k - 1, k) if 0 <= j < len(self.t)), key=lambda j: abs(self.t[j] - t), default=None)
        return None if best is None or abs(self.t[best] - t) > 1.0 else self.v[best]


def _with_attitude(pose: Pose, att: _Attitudes) -> Pose:
    if pose.heading_deg is not None:
        return pose
    a = att.at(pose.time_s)
    return pose if a is None else Pose(pose.time_s, pose.lat, pose.lon, pose.alt_rel_m, *a)


def _clock_notes(times: Iterable[float], what: str) -> list[str]:
    notes, last = [], None
    for t in times:
        if last is not None and (t < last - 1.0 or t - last > CLOCK_JUMP_S):
            notes.append(f"{what}: the clock jumps from {last:.1f} s to {t:.1f} s (a reset clock, or two flights "
                         "in one log): photos are paired with positions on each side of the jump only")
        last = t
    return notes


def _dedupe(shots: list[Shot]) -> list[Shot]:
    """One shot per logged sequence number: a ground station hears a CAMERA_IMAGE_CAPTURED again when it is
    re-sent or re-requested."""
    seen: set[tuple[str, int]] = set()
    out = []
    for s in shots:
        if s.seq is not None:
            if (s.source, s.seq) in seen:
                continue
            seen.add((s.source, s.seq))
        out.append(s)
    return out


# --------------------------------------------------------------------------------------------- MAVLink (tlog)

def _mode_name(hb: Any) -> str:
    from pymavlink import mavutil
    try:
        return mavutil.mode_string_v10(hb)
    except Exception:   # an unknown autopilot's custom mode: its number is all there is
        return f"mode {hb.custom_mode}"


def _read_tlog(path: Path) -> FlightLog:
    from pymavlink import mavutil
    from pymavlink.dialects.v20 import ardupilotmega as mavlink2

    conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega", robust_parsing=True)
    att = _Attitudes()
    captures: list[Shot] = []
    triggers: list[Shot] = []
    track: list[Pose] = []
    modes: list[ModeChange] = []
    seqs: list[tuple[float, int]] = []
    times: list[float] = []
    bad = 0
    try:
        while True:
            m = conn.recv_match(blocking=False)
            if m is None:
                break
            t = float(getattr(m, "_timestamp", 0.0))
            kind = m.get_type()
            if kind == "BAD_DATA":
                bad += 1
                continue
            times.append(t)
            if kind == "ATTITUDE" and m.get_srcComponent() == mavlink2.MAV_COMP_ID_AUTOPILOT1:
                att.add(t, math.degrees(m.yaw), math.degrees(m.pitch), math.degrees(m.roll))
            elif kind == "GLOBAL_POSITION_INT" and m.get_srcComponent() == mavlink2.MAV_COMP_ID_AUTOPILOT1:
                if m.lat or m.lon:
                    track.append(Pose(t, m.lat / 1e7, m.lon / 1e7, m.relative_alt / 1e3))
            elif kind == "CAMERA_IMAGE_CAPTURED":
                ypr = _yaw_pitch_roll(m.q)
                pose = Pose(t, m.lat / 1e7, m.lon / 1e7, m.relative_alt / 1e3, *(ypr or (None, None, None)))
                captures.append(Shot(pose, int(m.image_index), kind, ok=int(m.capture_result) == 1))
            elif kind == "CAMERA_FEEDBACK":
                triggers.append(Shot(Pose(t, m.lat / 1e7, m.lng / 1e7, float(m.alt_rel), m.yaw % 360.0, m.pitch,
                                          m.roll), int(m.img_idx), kind))
            elif kind == "HEARTBEAT" and m.get_srcComponent() == mavlink2.MAV_COMP_ID_AUTOPILOT1 \
                    and m.type != mavlink2.MAV_TYPE_GCS:
                armed = bool(m.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)
                name = _mode_name(m)
                if not modes or (modes[-1].mode, modes[-1].armed) != (name, armed):
                    modes.append(ModeChange(t, name, armed))
            elif kind == "MISSION_CURRENT" and m.get_srcComponent() == mavlink2.MAV_COMP_ID_AUTOPILOT1:
                if not seqs or seqs[-1][1] != m.seq:
                    seqs.append((t, int(m.seq)))
    finally:
        conn.close()
    notes = _clock_notes(times, "tlog")
    if bad:
        notes.append(f"{bad} unreadable stretch(es) skipped (a damaged or truncated tlog)")
    captures = [Shot(_with_attitude(s.pose, att), s.seq, s.source, s.ok) for s in _dedupe(captures)]
    return FlightLog(str(path), "tlog", tuple(captures), tuple(_dedupe(triggers)), tuple(track), tuple(modes),
                     tuple(seqs), tuple(notes))


# --------------------------------------------------------------------------------------------- DataFlash (.BIN)

def _field(m: Any, *names: str) -> float | None:
    for n in names:
        if n in m.get_fieldnames():
            return float(getattr(m, n))
    return None


def _read_dataflash(path: Path) -> FlightLog:
    from pymavlink import DFReader

    try:
        log = DFReader.DFReader_binary(str(path), zero_time_base=True)
    except Exception as err:   # pymavlink raises what the bytes make it raise
        raise LinkError(f"not a readable DataFlash log: {err}", where=str(path),
                        hint="give the .BIN the autopilot wrote (its SD card, or downloaded by the GCS)") from None
    att = _Attitudes()
    triggers: list[Shot] = []
    track: list[Pose] = []
    events: list[tuple[float, str | None, bool | None]] = []     # (time, mode, armed) as logged
    seqs: list[tuple[float, int]] = []
    times: list[float] = []
    dumped: set[int] = set()
    total = None
    while True:
        try:
            m = log.recv_match(type=["CAM", "TRIG", "POS", "ATT", "MODE", "CMD", "ARM"])
        except Exception:   # a truncated last block
            break
        if m is None:
            break
        kind = m.get_type()
        t = float(m.TimeUS) / 1e6 if hasattr(m, "TimeUS") else float(getattr(m, "_timestamp", 0.0))
        times.append(t)
        if kind == "ATT":
            att.add(t, m.Yaw, m.Pitch, m.Roll)
        elif kind == "POS":
            track.append(Pose(t, m.Lat, m.Lng, getattr(m, "RelHomeAlt", None)))
        elif kind in ("CAM", "TRIG"):
            # 4.x logs the attitude as R, P, Y; older releases as Roll, Pitch, Yaw
            yaw, pitch, roll = (_field(m, "Y", "Yaw"), _field(m, "P", "Pitch"), _field(m, "R", "Roll"))
            triggers.append(Shot(Pose(t, m.Lat, m.Lng, float(m.RelAlt), None if yaw is None else yaw % 360.0,
                                      pitch, roll), int(m.Img), kind))
        elif kind == "MODE":
            name = log.flightmode if isinstance(getattr(log, "flightmode", None), str) else str(m.Mode)
            events.append((t, name, None))
        elif kind == "ARM":
            events.append((t, None, bool(m.ArmState)))
        elif kind == "CMD":
            # the logger writes the whole stored mission when the log starts (CNum 0..CTot-1): that is the
            # plan, not progress; a CMD after it is an item the vehicle started
            if total is None or len(dumped) < total:
                total = int(m.CTot)
                dumped.add(int(m.CNum))
            else:
                seqs.append((t, int(m.CNum)))
    modes = _df_modes(events)
    notes = _clock_notes(times, "DataFlash log")
    notes.append("a DataFlash log records the autopilot's triggers, not the camera's captures: give the tlog "
                 "or the images to count what the camera took")
    if not seqs:
        notes.append("the DataFlash log records no mission progress (CMD after the mission's dump): how far "
                     "the mission went is unknown")
    return FlightLog(str(path), "dataflash", (), tuple(_dedupe(triggers)), tuple(track), tuple(modes),
                     tuple(seqs), tuple(notes))


def _df_modes(events: list[tuple[float, str | None, bool | None]]) -> list[ModeChange]:
    """Mode changes with the armed state. ArduPilot starts a log at arming by default, so a log whose first ARM
    record is a disarm was armed from its start."""
    first_arm = next((a for _, _, a in events if a is not None), None)
    armed = first_arm is False
    mode = "?"
    out: list[ModeChange] = []
    for t, name, arm in events:
        mode = name if name is not None else mode
        armed = arm if arm is not None else armed
        if not out or (out[-1].mode, out[-1].armed) != (mode, armed):
            out.append(ModeChange(t, mode, armed))
    return out


# --------------------------------------------------------------------------------------------- PX4 ULog

_PX4_NAV_STATES = {0: "MANUAL", 1: "ALTCTL", 2: "POSCTL", 3: "AUTO_MISSION", 4: "AUTO_LOITER", 5: "AUTO_RTL",
                   10: "ACRO", 14: "OFFBOARD", 15: "STAB", 17: "AUTO_TAKEOFF", 18: "AUTO_LAND"}


def _read_ulog(path: Path) -> FlightLog:
    import numpy as np
    from pyulog import ULog

    try:
        ulog = ULog(str(path), ["camera_capture", "camera_trigger", "vehicle_global_position", "vehicle_attitude",
                                "vehicle_status", "mission_result", "home_position"])
    except Exception as err:   # pyulog raises what the bytes make it raise
        raise LinkError(f"not a readable ULog: {err}", where=str(path),
                        hint="give the .ulg PX4 wrote (its SD card, or downloaded by the GCS)") from None
    topics = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    att = _Attitudes()
    if "vehicle_attitude" in topics:
        a = topics["vehicle_attitude"]
        for k in range(len(a["timestamp"])):
            ypr = _yaw_pitch_roll([a[f"q[{i}]"][k] for i in range(4)])
            if ypr:
                att.add(float(a["timestamp"][k]) / 1e6, *ypr)
    home_alt = _home_alt(topics)
    track: list[Pose] = []
    if "vehicle_global_position" in topics:
        g = topics["vehicle_global_position"]
        for k in range(len(g["timestamp"])):
            alt = None if home_alt is None else float(g["alt"][k]) - home_alt
            track.append(Pose(float(g["timestamp"][k]) / 1e6, float(g["lat"][k]), float(g["lon"][k]), alt))
    captures: list[Shot] = []
    if "camera_capture" in topics:
        c = topics["camera_capture"]
        for k in range(len(c["timestamp"])):
            ypr = _yaw_pitch_roll([c[f"q[{i}]"][k] for i in range(4)])
            pose = Pose(float(c["timestamp"][k]) / 1e6, float(c["lat"][k]), float(c["lon"][k]),
                        _capture_alt_rel(c, k, home_alt), *(ypr or (None, None, None)))
            captures.append(Shot(_with_attitude(pose, att), int(c["seq"][k]), "camera_capture",
                                 ok=int(c["result"][k]) == 1))
    triggers: list[Shot] = []
    if "camera_trigger" in topics:
        c = topics["camera_trigger"]
        for k in range(len(c["timestamp"])):
            t = float(c["timestamp"][k]) / 1e6
            p = _pose_at(track, t)
            if p is not None:
                triggers.append(Shot(_with_attitude(p, att), int(c["seq"][k]), "camera_trigger"))
    modes: list[ModeChange] = []
    if "vehicle_status" in topics:
        s = topics["vehicle_status"]
        for k in range(len(s["timestamp"])):
            name = _PX4_NAV_STATES.get(int(s["nav_state"][k]), f"nav_state {int(s['nav_state'][k])}")
            armed = int(s["arming_state"][k]) == 2
            if not modes or (modes[-1].mode, modes[-1].armed) != (name, armed):
                modes.append(ModeChange(float(s["timestamp"][k]) / 1e6, name, armed))
    seqs: list[tuple[float, int]] = []
    if "mission_result" in topics:
        r = topics["mission_result"]
        for k in range(len(r["timestamp"])):
            if not seqs or seqs[-1][1] != int(r["seq_current"][k]):
                seqs.append((float(r["timestamp"][k]) / 1e6, int(r["seq_current"][k])))
    notes = []
    if home_alt is None:
        notes.append("the ULog has no home position: track heights above home are unknown")
    if ulog.file_corruption:
        notes.append("the ULog is damaged or truncated: what follows the damage is lost")
    return FlightLog(str(path), "ulog", tuple(_dedupe(captures)), tuple(_dedupe(triggers)), tuple(track),
                     tuple(modes), tuple(seqs), tuple(notes))


def _home_alt(topics: dict) -> float | None:
    """Home's AMSL altitude as it was at take-off: PX4 sets home again when it arms, so the last home_position
    published by the first arming (a second later at most), else the first one logged."""
    import numpy as np
    h = topics.get("home_position")
    if h is None or not len(h["alt"]):
        return None
    s = topics.get("vehicle_status")
    armed = np.flatnonzero(s["arming_state"] == 2) if s is not None else np.zeros(0, int)
    if not len(armed):
        return float(h["alt"][0])
    before = np.flatnonzero(h["timestamp"] <= s["timestamp"][armed[0]] + 1_000_000)
    return float(h["alt"][before[-1] if len(before) else 0])


def _capture_alt_rel(c: Any, k: int, home_alt: float | None) -> float | None:
    """camera_capture's height above home: its AMSL altitude less home's; without a home, its ground_distance
    (a range finder's, or the estimator's height above ground) is the nearest thing the log holds."""
    import numpy as np
    if home_alt is not None and np.isfinite(c["alt"][k]):
        return float(c["alt"][k]) - home_alt
    return float(c["ground_distance"][k]) if np.isfinite(c["ground_distance"][k]) else None


def _pose_at(track: Sequence[Pose], t: float) -> Pose | None:
    """The track's pose nearest `t` (within 2 s), timed `t`."""
    import bisect
    if not track:
        return None
    ts = [p.time_s for p in track]
    k = bisect.bisect_left(ts, t)
    best = min((j for j in (k - 1, k) if 0 <= j < len(track)), key=lambda j: abs(ts[j] - t))
    p = track[best]
    return None if abs(p.time_s - t) > 2.0 else Pose(t, p.lat, p.lon, p.alt_rel_m)


# --------------------------------------------------------------------------------------------- one entry point

def _kind_of(path: Path) -> str:
    head = path.read_bytes()[:16] if path.stat().st_size else b""
    if head.startswith(b"ULog"):
        return "ulog"
    if head[:2] == b"\xa3\x95":
        return "dataflash"
    if path.suffix.lower() in (".tlog", ".mavlink") or (len(head) > 8 and head[8:9] in (b"\xfe", b"\xfd")):
        return "tlog"
    raise LinkError("not a tlog, DataFlash log or ULog", where=str(path),
                    hint="give the ground station's .tlog, the autopilot's .BIN or PX4's .ulg")


def read_log(path: str | Path) -> FlightLog:
    """The flight record of one log file, its kind found from its first bytes."""
    p = Path(path)
    if not p.is_file():
        raise LinkError("no such log file", where=str(p), hint="give the path of a .tlog, .BIN or .ulg")
    if p.stat().st_size == 0:
        raise LinkError("the log is empty", where=str(p), hint="the logger stopped before it wrote anything")
    kind = _kind_of(p)
    return {"tlog": _read_tlog, "dataflash": _read_dataflash, "ulog": _read_ulog}[kind](p)
