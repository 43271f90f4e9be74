"""Photo positions: planned (on the leg grid) and re-derived from a flown path as the autopilot triggers.

`simulate_distance_trigger` is what the report uses on the path rebuilt from the emitted mission items:
it models DO_SET_CAM_TRIGG_DIST as ArduPilot (AP_Camera) and PX4 (camera_trigger) execute it —
  * on start (distance > 0): the reference position is the current position; with param3 = 1 one photo
    is taken at once;
  * while on: a photo whenever the straight-line distance from the last photo's position (or the
    reference) reaches the distance — both firmwares compare positions, not distance travelled along the
    path, which differs only where the path bends while the camera is on;
  * on stop (distance 0): with param3 = 1 one more photo.
The firmware samples positions at the navigation rate; this model fires at the exact crossing, so real
photos lag by up to speed / rate (0.6 m at 6 m/s and 10 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import NamedTuple, Sequence

import numpy as np

# A photo due exactly at a waypoint (the leg end sits on the photo grid) must not be lost to rounding.
_REL_TOL = 1e-9


class PhotoPoint(NamedTuple):
    """One photo. A NamedTuple, not a frozen dataclass: a 100 km² survey has ~10^6 of them and a frozen
    dataclass costs ~3 µs per instance to build against ~0.3 µs here; it is just as immutable."""

    x: float
    y: float
    heading_deg: float      # direction of travel, degrees clockwise from north
    span: int               # index of the camera-on span (leg) it belongs to
    lat: float = math.nan
    lon: float = math.nan


@dataclass(frozen=True)
class TriggerSpan:
    """The camera distance-triggers from path vertex `start_index` to `stop_index` (inclusive)."""

    start_index: int
    stop_index: int
    distance_m: float
    shoot_at_start: bool = True      # DO_SET_CAM_TRIGG_DIST param3 = 1 on the start item
    shoot_at_stop: bool = False      # param3 = 1 on the stop item


def heading_deg(dx: float, dy: float) -> float:
    return math.degrees(math.atan2(dx, dy)) % 360.0


def simulate_distance_trigger(path: Sequence[tuple[float, float]] | np.ndarray, spans: Sequence[TriggerSpan],
                              distance_m: float | None = None) -> list[PhotoPoint]:
    """Photo positions produced by distance triggering along `path` (x/y metres) during `spans`.

    `distance_m`, when given, overrides each span's own distance (the common case of one trigger distance).
    """
    pts = np.asarray(path, dtype=float).reshape(-1, 2)
    photos: list[PhotoPoint] = []
    for s_idx, span in enumerate(spans):
        d = float(distance_m if distance_m is not None else span.distance_m)
        if not (0 <= span.start_index <= span.stop_index < len(pts)):
            raise ValueError(f"span {s_idx} indices {span.start_index}..{span.stop_index} outside the path")
        seg = pts[span.start_index:span.stop_index + 1]
        photos.extend(_span_photos(seg, d, span.shoot_at_start, span.shoot_at_stop, s_idx))
    return photos


def _first_heading(seg: np.ndarray, i: int, forward: bool = True) -> float:
    n = len(seg)
    rng = range(i, n - 1) if forward else range(i - 1, -1, -1)
    for j in rng:
        dx, dy = seg[j + 1] - seg[j]
        if abs(dx) + abs(dy) > 1e-9:
            return heading_deg(dx, dy)
    return 0.0


def _span_photos(seg: np.ndarray, d: float, at_start: bool, at_stop: bool, span: int) -> list[PhotoPoint]:
    """The photos of one camera-on span over the path vertices `seg`, one whenever the straight-line distance
    from the last reaches `d`."""
    out: list[PhotoPoint] = []
    ref = seg[0].copy()
    if at_start:
        out.append(PhotoPoint(float(ref[0]), float(ref[1]), _first_heading(seg, 0), span))
    if d > 0:
        for i in range(len(seg) - 1):
            ref = _segment_photos(seg[i], seg[i + 1], ref, d, span, out)
    if at_stop:
        end = seg[-1]
        out.append(PhotoPoint(float(end[0]), float(end[1]), _first_heading(seg, len(seg) - 1, forward=False), span))
    return out


def _segment_photos(p: np.ndarray, q: np.ndarray, ref: np.ndarray, d: float, span: int,
                    out: list[PhotoPoint]) -> np.ndarray:
    """Append to `out` the photos on the straight segment p -> q, the last photo before it being at `ref`;
    return where the last photo now is."""
    D = q - p
    a = float(D @ D)
    if a < 1e-18:
        return ref
    hd = heading_deg(float(D[0]), float(D[1]))
    t = 0.0
    while True:
        tau = _next_crossing(p, q, D, a, ref, d, t)
        if tau is None:
            return ref
        X = p + tau * D
        out.append(PhotoPoint(float(X[0]), float(X[1]), hd, span))
        ref = X
        if tau >= 1.0:
            return ref
        # once the last photo lies on this straight segment, the straight-line distance is the
        # distance along it: the remaining photos on the segment are equally spaced (vectorised)
        step = d / math.sqrt(a)
        k = int(math.floor((1.0 - tau) / step * (1.0 + _REL_TOL) + _REL_TOL))
        if k > 0:
            ts = tau + step * np.arange(1, k + 1)
            ts[-1] = min(ts[-1], 1.0)
            xs = p[0] + ts * D[0]
            ys = p[1] + ts * D[1]
            out.extend(PhotoPoint(x_, y_, hd, span) for x_, y_ in zip(xs.tolist(), ys.tolist()))
            tau = float(ts[-1])
            ref = p + tau * D
            if tau >= 1.0:
                return ref
        t = tau


def _next_crossing(p: np.ndarray, q: np.ndarray, D: np.ndarray, a: float, ref: np.ndarray, d: float,
                   t: float) -> float | None:
    """Where on p + τ·D (τ in [t, 1], D = q - p, a = D·D) the next photo is due: where the path leaves the circle
    of radius d around the last photo `ref`. None when it is not due on this segment."""
    thresh = d * (1.0 - _REL_TOL)
    w = p - ref
    b = 2.0 * float(D @ w)
    c = float(w @ w) - d * d
    disc = b * b - 4.0 * a * c
    # larger root of |p + τD − ref| = d: where the path leaves the circle around the last photo
    tau = (-b + math.sqrt(disc)) / (2.0 * a) if disc >= 0 else -math.inf
    if tau < t:
        # already beyond d (a jump in the path): fire at the current point, or stop if not
        X = p + t * D
        if float(np.hypot(*(X - ref))) < thresh:
            return None
        tau = t
    if tau > 1.0:
        # the crossing lies beyond q; still fire at q when q is within rounding of d
        if float(np.hypot(*(q - ref))) < thresh:
            return None
        tau = 1.0
    return tau


def photos_along(path: Sequence[tuple[float, float]] | np.ndarray, distance_m: float, span: int = 0) -> list[PhotoPoint]:
    """Photos every `distance_m` along a polyline measured along the path (corridor planning), first at the start."""
    pts = np.asarray(path, dtype=float).reshape(-1, 2)
    seglen = np.hypot(*np.diff(pts, axis=0).T)
    total = float(seglen.sum())
    n = int(math.floor(total / distance_m * (1 + _REL_TOL))) + 1
    cum = np.concatenate([[0.0], np.cumsum(seglen)])
    out = []
    for k in range(n):
        s = min(k * distance_m, total)
        i = int(np.searchsorted(cum, s, side="right") - 1)
        i = min(max(i, 0), len(seglen) - 1)
        while i < len(seglen) - 1 and seglen[i] < 1e-12:
            i += 1
        f = 0.0 if seglen[i] < 1e-12 else (s - cum[i]) / seglen[i]
        X = pts[i] + f * (pts[i + 1] - pts[i])
        dx, dy = pts[i + 1] - pts[i]
        out.append(PhotoPoint(float(X[0]), float(X[1]), heading_deg(float(dx), float(dy)), span))
    return out
