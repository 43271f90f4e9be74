"""Sorties: a mission longer than one battery (or than the vehicle's item limit) as several complete missions.

    sorties = split_sorties(compiled, budget)     # () when the mission fits one battery and one upload

Each sortie is a mission of its own: the plan's take-off, the survey speed, a transit to where it starts, its
stretch of the whole mission's items (lines with their own trigger items), and a return (RTL; the last sortie
keeps the plan's own ending). The stretches are consecutive pieces of the one planned tour, so the lines either
side of a seam are neighbours planned with the requested side overlap, and the tour (which starts nearest home)
already keeps the transits short; the union of the sorties flies every line the single mission flies.

Where a sortie ends (`_Cut`): after a positional waypoint with the camera off (a line's end) wherever one fits;
else after a waypoint with the camera on (a corridor's bend); else, when not even one line fits a battery,
inside a line at one of its photo positions. A sortie that starts with the camera on (a cut inside a line)
flies to the cut point first and switches the trigger on there with a photo at once, as the previous sortie's
last photo was taken there: the front overlap across the seam is the line's own.

How long a sortie flies is the report's flight model (missions.measure.flight.simulate) of the sortie's own
items: the cut is chosen from the whole mission's timeline plus a transit estimate, then every sortie is
re-flown and moved one cut earlier until it fits.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field, replace
import math
from typing import NamedTuple, Sequence

import numpy as np

from missions.compiled import Compiled, FlightCache, PlanWarning
from missions.emit.items import FRAME_MISSION, MissionItem, deg_to_e7, mavlink
from missions.errors import PlanError
from missions.geometry.geo import great_circle_m
from missions.measure.flight import (ACCEL_MPS2, CLIMB_MPS, DESCENT_MPS, LAND_FINAL_M, LAND_MPS, RTL_ALT_M, Simulation,
                                     _projection, simulate)

C = mavlink
# Minutes in the air on one battery when the plan gives no vehicle.endurance_min: a survey quadcopter carrying
# a ~1 kg WIRIS flies 20 to 30 min on one pack, a small electric survey plane 60 to 90, a VTOL 40 to 60 (its
# hover phases cost most); these are below the low end, so a plan longer than them is worth a warning.
DEFAULT_ENDURANCE_MIN = {"copter": 15.0, "plane": 45.0, "vtol": 30.0}
DEFAULT_RESERVE_PCT = 20.0
# The chosen cut's estimate leaves this share of the budget for what the estimate leaves out (the sortie's own
# accelerations at the seam); the exact re-flight then moves a cut earlier when it is still over.
ESTIMATE_MARGIN = 0.03
TRIGGERS = (C.MAV_CMD_DO_SET_CAM_TRIGG_DIST, C.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, C.MAV_CMD_DO_TRIGGER_CONTROL)
POSITIONAL = (C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME)
TAKEOFFS = (C.MAV_CMD_NAV_TAKEOFF, C.MAV_CMD_NAV_VTOL_TAKEOFF)
ENDINGS = (C.MAV_CMD_NAV_RETURN_TO_LAUNCH, C.MAV_CMD_NAV_LAND, C.MAV_CMD_NAV_VTOL_LAND)


@dataclass(frozen=True)
class Endurance:
    """One battery: minutes in the air, the reserve kept, and whether the plan gave them or the frame's default
    stands in (then the mission is not split, only warned about)."""

    minutes: float
    reserve_pct: float
    assumed: bool

    @property
    def usable_s(self) -> float:
        return self.minutes * 60.0 * (1.0 - self.reserve_pct / 100.0)

    def to_json(self) -> dict:
        return {"endurance_min": self.minutes, "reserve_pct": self.reserve_pct, "assumed": self.assumed,
                "usable_s": round(self.usable_s, 1)}


def endurance_of(frame: str, endurance_min: float | None, reserve_pct: float | None) -> Endurance:
    reserve = DEFAULT_RESERVE_PCT if reserve_pct is None else reserve_pct
    if endurance_min is None:
        return Endurance(DEFAULT_ENDURANCE_MIN[frame], reserve, True)
    return Endurance(endurance_min, reserve, False)


@dataclass(frozen=True)
class Sortie:
    """One complete mission of a plan flown in sorties. `origin[k]` is the index into the whole mission's items
    that item k stands for (its prefix stands for the first item it flies, its ending for the last), so photos it
    takes can be measured against the plan's steps."""

    number: int                              # 1..N, in flying order
    items: tuple[MissionItem, ...]
    origin: tuple[int, ...]
    flight_time_s: float
    photos: int
    first_line: int | None                   # the whole mission's lines (camera-on stretches), 1-based
    last_line: int | None
    flight: Simulation | None = field(default=None, compare=False, repr=False)   # its own re-flight

    def to_json(self, file: str) -> dict:
        return {"file": file, "flight_time_s": round(self.flight_time_s, 1), "photos": self.photos,
                "items": len(self.items), "first_line": self.first_line, "last_line": self.last_line}


class _Cut(NamedTuple):
    """Where a sortie ends: before item `index` of the whole mission; `point` (lat, lon, alt) is a photo
    position inside the leg towards item `index` when the cut falls inside a line, else None."""

    index: int
    point: tuple[float, float, float] | None = None
    time_s: float = 0.0                      # the whole mission's time there


class _Mission(NamedTuple):
    """The whole mission read for cutting: its opening (take-off and what follows it before the first
    waypoint), body [start, end) and ending (RTL or LAND, or none)."""

    items: tuple[MissionItem, ...]
    takeoff: MissionItem
    start: int
    end: int
    ending: tuple[MissionItem, ...]


# ------------------------------------------------------------------------------------------ the whole mission

def _read_mission(items: Sequence[MissionItem], where: str) -> _Mission:
    k = next((i for i, it in enumerate(items) if it.command in TAKEOFFS), None)
    if k is None:
        raise PlanError("a mission flown in sorties needs a takeoff step: each sortie takes off on its own battery",
                        where=where, hint="start the mission with `- takeoff: {alt_m: ...}`")
    start = k + 1
    while start < len(items) and items[start].frame == FRAME_MISSION and items[start].command not in ENDINGS:
        start += 1
    end = len(items)
    if end > start and items[-1].command in ENDINGS:
        end -= 1
    return _Mission(tuple(items), items[k], start, end, tuple(items[end:]))


def _is_nav(it: MissionItem) -> bool:
    return it.frame != FRAME_MISSION or it.command in ENDINGS


def _positional(it: MissionItem) -> bool:
    return it.command in POSITIONAL and bool(it.x or it.y)


class _State(NamedTuple):
    """What is in force before an item: the last speed change, the trigger items, the last positional NAV."""

    speed: MissionItem | None
    triggers: dict
    last_nav: int | None


def _states(m: _Mission) -> list[_State]:
    """The state before each item index 0..len(items)."""
    out: list[_State] = []
    speed, trig, last = None, {}, None
    for i, it in enumerate(m.items):
        out.append(_State(speed, dict(trig) if trig else {}, last))
        if it.command == C.MAV_CMD_DO_CHANGE_SPEED:
            speed = it
        elif it.command in TRIGGERS:
            trig = {**trig, it.command: it}
        if _positional(it):
            last = i
    out.append(_State(speed, dict(trig), last))
    return out


def _camera_on(trig: dict) -> bool:
    d = trig.get(C.MAV_CMD_DO_SET_CAM_TRIGG_DIST)
    t = trig.get(C.MAV_CMD_DO_TRIGGER_CONTROL)
    return bool((d is not None and d.param1 > 0) or (t is not None and t.param1 == 1))


# ------------------------------------------------------------------------------------------ building a sortie

def _waypoint(lat: float, lon: float, alt: float, frame: int, comment: str) -> MissionItem:
    return MissionItem(command=C.MAV_CMD_NAV_WAYPOINT, frame=frame, param4=math.nan, x=deg_to_e7(lat),
                       y=deg_to_e7(lon), z=round(alt, 2), comment=comment)


def _resume(m: _Mission, st: _State, at: MissionItem | None) -> list[MissionItem]:
    """A sortie's opening: take-off, speed, and when it starts inside a line the cut point with the trigger."""
    out = [m.takeoff.with_(comment=m.takeoff.comment or "take-off")]
    if st.speed is not None:
        out.append(st.speed)
    if at is not None and _camera_on(st.triggers):
        out.append(at.with_(comment="sortie start: where the previous sortie's line stopped"))
        for cmd in TRIGGERS:
            it = st.triggers.get(cmd)
            if it is None:
                continue
            if cmd == C.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
                it = it.with_(param3=1.0, comment="sortie start: camera trigger as it was, a photo at once")
            out.append(it)
    return out


def _camera_off(trig: dict) -> list[MissionItem]:
    out = []
    d = trig.get(C.MAV_CMD_DO_SET_CAM_TRIGG_DIST)
    if d is not None and d.param1 > 0:
        out.append(MissionItem(command=C.MAV_CMD_DO_SET_CAM_TRIGG_DIST, frame=FRAME_MISSION,
                               comment="sortie end: camera off"))
    t = trig.get(C.MAV_CMD_DO_TRIGGER_CONTROL)
    if t is not None and t.param1 == 1:
        out.append(MissionItem(command=C.MAV_CMD_DO_TRIGGER_CONTROL, frame=FRAME_MISSION, param2=-1.0, param3=-1.0,
                               comment="sortie end: camera off"))
    return out


def _rtl() -> MissionItem:
    return MissionItem(command=C.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=FRAME_MISSION,
                       comment="sortie end: return to launch, change the battery")


class _Built(NamedTuple):
    items: tuple[MissionItem, ...]
    origin: tuple[int, ...]


def _build(m: _Mission, states: list[_State], begin: _Cut, end: _Cut, last: bool) -> _Built:
    """The sortie flying the whole mission from cut `begin` to cut `end`."""
    st = states[begin.index]
    at = None
    if begin.point is not None:
        at = _waypoint(*begin.point, m.takeoff.frame, "")
    elif st.last_nav is not None and begin.index > m.start:
        at = m.items[st.last_nav]
    head = _resume(m, st, at)
    body = list(m.items[begin.index:end.index])
    origin = [begin.index] * len(head) + list(range(begin.index, end.index))
    tail: list[MissionItem] = []
    if end.point is not None:       # on the way to item end.index: its photos are that item's
        tail.append(_waypoint(*end.point, m.takeoff.frame, "sortie end: a photo position inside the line"))
        origin.append(end.index)
    if last:
        tail += list(m.ending) if m.ending else [_rtl()]
    else:
        tail += _camera_off(states[end.index].triggers) + [_rtl()]
    origin += [max(end.index - 1, begin.index)] * (len(tail) - (end.point is not None))
    return _Built(tuple(head + body + tail), tuple(origin))


# ------------------------------------------------------------------------------------------ timing

class _Timeline(NamedTuple):
    """The whole mission's re-flight read for cutting."""

    sim: Simulation
    nav_time: dict[int, float]              # arrival time at each positional NAV item's vertex (first visit)
    order: np.ndarray                       # sim.photos' indices by the time they are taken
    photo_times: np.ndarray                 # their times, in that order
    photo_lines: np.ndarray                 # their lines (`_line_numbers`), in that order


def _line_payload(compiled: Compiled) -> str | None:
    """The payload whose camera-on stretches number the lines: the first the autopilot triggers (a RedEdge's own
    stretches run through turns and transits), else the first."""
    from missions.measure.flight import self_triggering

    names = [n for a in compiled.areas for n in a.payloads] or [p.name for p in compiled.payloads]
    own = self_triggering(compiled)
    return next((n for n in names if n not in own), names[0] if names else None)


def _timeline(sim: Simulation, line_payload: str | None = None) -> _Timeline:
    t: dict[int, float] = {}
    for v, ts in zip(sim.vertices, sim.vertex_times_s):
        if v.item >= 0 and v.item not in t:
            t[v.item] = ts
    times = np.array([p.time_s for p in sim.photos], dtype=float)
    order = np.argsort(times, kind="stable")
    line_of = _line_numbers(sim, line_payload)
    lines = np.array([line_of.get(p.span, 0) for p in sim.photos], dtype=int)
    return _Timeline(sim, t, order, times[order], lines[order] if len(lines) else lines)


def _transit_s(distance_m: float, speed_mps: float, copter: bool) -> float:
    """A straight flight at cruise speed from rest to rest (the flight model's acceleration)."""
    a = ACCEL_MPS2 if copter else 2.0 * ACCEL_MPS2
    v = max(speed_mps, 0.1)
    return distance_m / v + v / a if distance_m >= v * v / a else 2.0 * math.sqrt(distance_m / a)


def _up_s(alt_m: float) -> float:
    return max(alt_m, 0.0) / CLIMB_MPS


def _down_s(alt_m: float) -> float:
    top = max(alt_m, RTL_ALT_M)
    final = min(top, LAND_FINAL_M)
    return (top - alt_m) / CLIMB_MPS + (top - final) / DESCENT_MPS + final / LAND_MPS


class _Estimator(NamedTuple):
    home: tuple[float, float]
    speed_mps: float
    copter: bool
    alt_m: float

    def trip_s(self, lat: float, lon: float) -> float:
        return _transit_s(great_circle_m(self.home[0], self.home[1], lat, lon), self.speed_mps, self.copter)


# ------------------------------------------------------------------------------------------ cutting

def _cuts(m: _Mission, states: list[_State], tl: _Timeline) -> list[_Cut]:
    """Every place a sortie may end, in mission order (the body's end included)."""
    out = []
    for j in range(m.start + 1, m.end + 1):
        if j < m.end and not _is_nav(m.items[j]):
            continue
        last = states[j].last_nav
        if last is None or last < m.start or last not in tl.nav_time:
            continue
        out.append(_Cut(j, None, tl.nav_time[last]))
    return out


def _photo_cuts(m: _Mission, tl: _Timeline, after: float, before: float) -> list[_Cut]:
    """Cuts at photo positions taken between `after` and `before` (s), inside the leg flying towards their item."""
    lo, hi = np.searchsorted(tl.photo_times, [after, before], side="right")
    out = []
    for k in tl.order[lo:hi].tolist():
        p = tl.sim.photos[k]
        if 0 <= p.item < m.end and _positional(m.items[p.item]):
            out.append(_Cut(p.item, (p.lat, p.lon, p.alt_m), p.time_s))
    return out


def _start_time(m: _Mission, states: list[_State], tl: _Timeline, begin: _Cut) -> tuple[float, tuple[float, float]]:
    """The whole mission's time and the position where a sortie starting at `begin` joins the tour."""
    if begin.point is not None:
        return begin.time_s, begin.point[:2]
    if begin.index <= m.start:
        return 0.0, (m.takeoff.lat, m.takeoff.lon)
    st = states[begin.index]
    if _camera_on(st.triggers) and st.last_nav is not None:
        it = m.items[st.last_nav]
        return tl.nav_time[st.last_nav], (it.lat, it.lon)
    nxt = next((i for i in range(begin.index, m.end) if _positional(m.items[i]) and i in tl.nav_time), None)
    if nxt is None:
        return begin.time_s, (m.takeoff.lat, m.takeoff.lon)
    it = m.items[nxt]
    return tl.nav_time[nxt], (it.lat, it.lon)


def _end_position(m: _Mission, states: list[_State], end: _Cut) -> tuple[float, float]:
    if end.point is not None:
        return end.point[:2]
    last = states[end.index].last_nav
    it = m.items[last] if last is not None else m.takeoff
    return it.lat, it.lon


def _estimate_s(m: _Mission, states: list[_State], tl: _Timeline, est: _Estimator, begin: _Cut, end: _Cut) -> float:
    if begin.index <= m.start and begin.point is None:
        t0, inbound = 0.0, 0.0
    else:
        t0, (lat, lon) = _start_time(m, states, tl, begin)
        inbound = _up_s(est.alt_m) + est.trip_s(lat, lon)
    lat, lon = _end_position(m, states, end)
    return inbound + (end.time_s - t0) + est.trip_s(lat, lon) + _down_s(est.alt_m)


class Budget(NamedTuple):
    """What one sortie may take: flight seconds (None: no battery limit) and items."""

    flight_s: float | None
    items: int


def as_sortie(compiled: Compiled, items: tuple[MissionItem, ...]) -> Compiled:
    """`compiled` flying only `items` (a sortie), with a re-flight cache of its own."""
    return replace(compiled, items=items, parts=(items,), sorties=(), flight_cache=FlightCache())


def _fits(built: _Built, compiled: Compiled, budget: Budget) -> tuple[bool, Simulation | None]:
    if len(built.items) > budget.items:
        return False, None
    if budget.flight_s is None:
        return True, None
    sim = simulate(as_sortie(compiled, built.items))
    return sim.flight_time_s <= budget.flight_s, sim


def split_sorties(compiled: Compiled, budget: Budget, where: str,
                  whole: Simulation | None = None) -> tuple[Sortie, ...]:
    """The mission as sorties each within `budget`; () when it fits as it is."""
    whole = whole or simulate(compiled)
    over_time = budget.flight_s is not None and whole.flight_time_s > budget.flight_s
    if not over_time and len(compiled.items) <= budget.items:
        return ()
    m = _read_mission(compiled.items, where)
    states = _states(m)
    tl = _timeline(whole, _line_payload(compiled))
    est = _Estimator((compiled.home[0], compiled.home[1]), compiled.speed_mps, compiled.frame == "copter",
                     max((it.z for it in compiled.items if _positional(it)), default=m.takeoff.z))
    cuts = _cuts(m, states, tl)
    cut_index = [c.index for c in cuts]
    begin = _Cut(m.start, None, 0.0)
    out: list[Sortie] = []
    while True:
        built, sim, end = _next_sortie(compiled, m, states, tl, est, cuts, cut_index, begin, budget, where)
        last = end.index >= m.end
        sim = sim or simulate(as_sortie(compiled, built.items))
        first_line, last_line = _lines_flown(tl, begin, end, m)
        out.append(Sortie(len(out) + 1, built.items, built.origin, sim.flight_time_s, len(sim.photos),
                          first_line, last_line, sim))
        if last:
            return tuple(out)
        begin = end


def _latest_fitting(compiled: Compiled, m: _Mission, states: list[_State], tl: _Timeline, est: _Estimator,
                    begin: _Cut, budget: Budget, limit: float, cuts: list[_Cut]
                    ) -> tuple[_Built, Simulation | None, _Cut] | None:
    """The last of `cuts` whose estimate fits and whose sortie, re-flown, fits."""
    for c in reversed([c for c in cuts if _estimate_s(m, states, tl, est, begin, c) <= limit]):
        built = _build(m, states, begin, c, c.index >= m.end and c.point is None)
        fits, sim = _fits(built, compiled, budget)
        if fits:
            return built, sim, c
    return None


def _next_sortie(compiled: Compiled, m: _Mission, states: list[_State], tl: _Timeline, est: _Estimator,
                 cuts: list[_Cut], cut_index: list[int], begin: _Cut, budget: Budget,
                 where: str) -> tuple[_Built, Simulation | None, _Cut]:
    """The longest sortie from `begin` that fits: the last cut whose estimate fits (camera-off cuts first), then
    earlier ones until the re-flight fits; inside a line when no waypoint cut does."""
    # a sortie flies at most its budget of the whole mission's time and of its items: only cuts within both
    first = bisect.bisect_left(cut_index, begin.index + (0 if begin.point is not None else 1))
    last = bisect.bisect_right(cut_index, begin.index + budget.items)
    span_s = budget.flight_s if budget.flight_s is not None else math.inf
    after = [c for c in cuts[first:last] if c.time_s <= begin.time_s + span_s or c.index >= m.end]
    limit = budget.flight_s * (1.0 - ESTIMATE_MARGIN) if budget.flight_s is not None else math.inf
    # a line's end first; a sortie that takes no photo (it ends before its line's first) is no progress
    off = [c for c in after if c.index >= m.end or not _camera_on(states[c.index].triggers)]
    found = _latest_fitting(compiled, m, states, tl, est, begin, budget, limit,
                            [c for c in off if c.index >= m.end or _has_photos(tl, begin, c, m)])
    if found is not None:
        return found
    # else inside a line (a line longer than a battery): at a waypoint on it (a corridor's bend) or a photo
    # position, whichever goes farther (a sortie flies less than its budget of the whole mission's time, so only
    # the photos within it are candidates)
    t0 = begin.time_s
    horizon = t0 + (budget.flight_s or tl.sim.flight_time_s)
    inside = sorted([c for c in after if c not in off] + _photo_cuts(m, tl, t0 + 1e-6, horizon),
                    key=lambda c: c.time_s)
    found = _latest_fitting(compiled, m, states, tl, est, begin, budget, limit,
                            [c for c in inside if c.time_s > t0 + 1e-6])
    if found is not None:
        return found
    raise PlanError(f"no sortie from item {begin.index} fits one battery of {budget.flight_s or 0:.0f} s "
                    f"and {budget.items} items", where=where,
                    hint="the transit to the area and back alone is longer than a battery: raise "
                         "vehicle.endurance_min, lower vehicle.reserve_pct or take off nearer the area")


# ------------------------------------------------------------------------------------------ lines

def _line_numbers(sim: Simulation, payload: str | None) -> dict[int, int]:
    """The whole mission's photo spans of `payload` (None: any) numbered 1.. in flying order: its lines."""
    out: dict[int, int] = {}
    for p in sorted(sim.photos, key=lambda p: p.time_s):
        if (payload is None or payload in p.payloads) and p.span not in out:
            out[p.span] = len(out) + 1
    return out


def _photo_slice(tl: _Timeline, begin: _Cut, end: _Cut, m: _Mission) -> tuple[int, int]:
    """The whole mission's photos (positions in `tl.order`) a sortie from `begin` to `end` takes: those after the
    time at `begin` up to the time at `end` (both the whole mission's). A photo at a cut inside a line is the
    last of one sortie and, shot again on resuming, the first of the next."""
    times = tl.photo_times
    lo = 0 if begin.index <= m.start and begin.point is None else int(
        np.searchsorted(times, begin.time_s, side="left" if begin.point is not None else "right"))
    hi = len(times) if end.index >= m.end else int(np.searchsorted(times, end.time_s, side="right"))
    return lo, max(lo, hi)


def _has_photos(tl: _Timeline, begin: _Cut, end: _Cut, m: _Mission) -> bool:
    lo, hi = _photo_slice(tl, begin, end, m)
    return hi > lo


def _lines_flown(tl: _Timeline, begin: _Cut, end: _Cut, m: _Mission) -> tuple[int | None, int | None]:
    lo, hi = _photo_slice(tl, begin, end, m)
    if hi <= lo:
        return None, None
    lines = tl.photo_lines[lo:hi]
    lines = lines[lines > 0]              # 0: a photo of another payload only
    if not len(lines):
        return None, None
    return int(lines.min()), int(lines.max())


# ------------------------------------------------------------------------------------------ the union

def union_photos(compiled: Compiled, sorties: Sequence[Sortie], sims: Sequence[Simulation]) -> list:
    """Every sortie's re-flown photos in the whole mission's terms: items mapped through `origin`, spans kept
    apart per sortie. With an area every simulation flies in its projection, so positions and headings carry over;
    without one (no area to measure) positions are moved through lat/lon."""
    proj = _projection(compiled)
    out = []
    for s, sim in zip(sorties, sims):
        same = sim.projection == proj
        for p in sim.photos:
            x, y = (p.x, p.y) if same else proj.point_to_xy(p.lat, p.lon)
            out.append(p._replace(x=x, y=y, span=p.span + 1_000_000 * s.number,
                                  item=s.origin[p.item] if 0 <= p.item < len(s.origin) else p.item))
    return out


def warn_text(sorties: Sequence[Sortie], endurance: Endurance, by_items: bool, limit: int) -> PlanWarning:
    why = (f"one battery ({endurance.minutes:g} min less {endurance.reserve_pct:g} % reserve = "
           f"{endurance.usable_s / 60:.1f} min)" if not by_items else f"the vehicle's {limit} mission items")
    return PlanWarning("mission_split", f"the mission is longer than {why}: flown as {len(sorties)} sorties, each "
                       "taking off, flying its lines, returning and landing; upload each (NAME.sortieN.plan) "
                       "on a fresh battery, in order")


def in_sorties(plan, compiled: Compiled) -> Compiled:
    """`compiled` flown as sorties when it is longer than the plan's battery or the vehicle's item limit: its
    `parts` are then the sorties' items (each checked against the firmware) and `sorties` says what each flies.
    Without vehicle.endurance_min the frame's conservative default is only warned about, never split on."""
    from missions.emit.firmware import check_items, profile

    v = plan.vehicle
    endurance = endurance_of(v.frame, v.endurance_min, v.reserve_pct)
    try:
        whole = simulate(compiled)
    except PlanError as e:      # the photo budget of the re-flight: about the plan as a whole
        e.where = e.where or plan.path
        raise
    warnings = list(compiled.warnings)
    if endurance.assumed and whole.flight_time_s > endurance.usable_s:
        warnings.append(PlanWarning(
            "longer_than_battery", f"the flight takes {whole.flight_time_s / 60:.1f} min, longer than one battery "
            f"of a {v.frame} as assumed without vehicle.endurance_min ({endurance.minutes:g} min less "
            f"{endurance.reserve_pct:g} % reserve); give vehicle.endurance_min to fly it as sorties"))
    # ArduPilot stores home as item 0 of every mission it takes, so a sortie leaves it one row of the limit
    rows = compiled.item_limit - (1 if compiled.firmware == "ardupilot" else 0)
    budget = Budget(None if endurance.assumed else endurance.usable_s, rows)
    where = plan.where("vehicle", "endurance_min") if v.endurance_min is not None else plan.where("mission")
    sorties = split_sorties(compiled, budget, where, whole)
    if not sorties:
        return replace(compiled, warnings=tuple(dict.fromkeys(warnings)), endurance=endurance)
    prof = profile(compiled.firmware)
    for s in sorties:
        check_items(s.items, prof, where=f"sortie {s.number}")
    by_items = budget.flight_s is None or whole.flight_time_s <= budget.flight_s
    warnings.append(warn_text(sorties, endurance, by_items, compiled.item_limit))
    return replace(compiled, parts=tuple(s.items for s in sorties), sorties=sorties, endurance=endurance,
                   warnings=tuple(dict.fromkeys(warnings)))
