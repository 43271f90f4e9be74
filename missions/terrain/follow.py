"""Terrain following: the altitudes (above mean sea level) a survey's or corridor's lines fly at over a DEM.

    profile = follow_path(xy, ground, FollowSettings(target_agl_m=60, tolerance_m=6, climb_slope=0.5,
                                                      descent_slope=0.3), step_m=2.5)

The horizontal path is kept exactly (its vertices are the planner's turnarounds, entries, exits and photo stops);
waypoints are added along its segments where the ground asks for them. The rule, in this order:
1. The target: the camera `target_agl_m` above the ground directly below it, at every sample (every `step_m`,
   at most half the DEM's pixel). The target is a floor: the requested overlaps are sized for it, and lower
   would shrink the footprints and the clearance.
2. Climb and descent: the vehicle flying at its survey speed climbs at most `climb_slope` metres per metre
   flown (climb rate / speed) and descends at most `descent_slope`. Where the ground rises faster it starts
   climbing earlier; where it falls away faster the vehicle comes down later (higher than the target: a coarser
   GSD there, reported by `FollowProfile.over_tolerance_m`, never lower).
3. Waypoints: between two kept vertices as few as needed so that flying straight from one to the next keeps
   the height above ground within [target, target + tolerance] at every sample (or at the rate-limited height
   where that is above the band). Chords between points of a rate-limited profile are within the rates too.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, NamedTuple

import numpy as np

# Heights within this of a bound count as on it (the DEM's bilinear surface and float rounding).
_EPS_M = 0.01


@dataclass(frozen=True)
class FollowSettings:
    target_agl_m: float
    tolerance_m: float
    climb_slope: float          # metres of climb per metre flown, at most
    descent_slope: float        # metres of descent per metre flown, at most


class FollowProfile(NamedTuple):
    """The followed path: its points (the path's vertices and the added ones), their altitude above mean sea level,
    which input vertex each is (-1: added), and how far above the band the rates forced it at worst."""

    xy: np.ndarray                # (n, 2)
    amsl_m: np.ndarray            # (n,)
    vertex: np.ndarray            # (n,) int: index into the input path, or -1
    over_tolerance_m: float       # max over samples of (height above ground - target - tolerance), >= 0
    over_at_xy: tuple[float, float] | None


def _samples(xy: np.ndarray, step_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points every <= step_m along the path, their distance along it, and the sample index of each vertex."""
    pts = [xy[:1]]
    vidx = [0]
    for a, b in zip(xy[:-1], xy[1:]):
        n = max(1, int(math.ceil(math.hypot(*(b - a)) / step_m)))
        t = np.arange(1, n + 1)[:, None] / n
        pts.append(a + (b - a) * t)
        vidx.append(vidx[-1] + n)
    p = np.concatenate(pts)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    return p, s, np.array(vidx)


def rate_limited(target: np.ndarray, s: np.ndarray, climb_slope: float, descent_slope: float) -> np.ndarray:
    """The lowest profile >= target whose slopes stay within the climb and descent limits."""
    z = target.astype(float).copy()
    ds = np.diff(s)
    for k in range(1, len(z)):                      # cannot come down faster than descent_slope
        z[k] = max(z[k], z[k - 1] - descent_slope * ds[k - 1])
    for k in range(len(z) - 2, -1, -1):             # must start climbing early enough
        z[k] = max(z[k], z[k + 1] - climb_slope * ds[k])
    return z


def _chord_ok(s: np.ndarray, z: np.ndarray, lo: np.ndarray, hi: np.ndarray, i: int, j: int) -> bool:
    if j - i < 2:
        return True
    f = (s[i + 1:j] - s[i]) / (s[j] - s[i]) if s[j] > s[i] else np.zeros(j - i - 1)
    line = z[i] + (z[j] - z[i]) * f
    return bool(np.all(line >= lo[i + 1:j] - _EPS_M) and np.all(line <= hi[i + 1:j] + _EPS_M))


def _breakpoints(s: np.ndarray, z: np.ndarray, lo: np.ndarray, hi: np.ndarray, a: int, b: int) -> list[int]:
    """Sample indices in (a, b] where straight flight from the previous one keeps within [lo, hi], greedily
    as far as possible each time."""
    out: list[int] = []
    i = a
    while i < b:
        j = i + 1
        while j < b and _chord_ok(s, z, lo, hi, i, j + 1):
            j += 1
        out.append(j)
        i = j
    return out


def follow_path(xy: np.ndarray, ground: Callable[[np.ndarray], np.ndarray], settings: FollowSettings,
                step_m: float) -> FollowProfile:
    """The followed profile of the path `xy` (metres); `ground(points)` gives heights above mean sea level."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    p, s, vidx = _samples(xy, step_m)
    g = ground(p)
    target = g + settings.target_agl_m
    z = rate_limited(target, s, settings.climb_slope, settings.descent_slope)
    hi = np.maximum(target + settings.tolerance_m, z)
    keep = [0]
    for a, b in zip(vidx[:-1], vidx[1:]):
        keep.extend(_breakpoints(s, z, target, hi, int(a), int(b)))
    keep_arr = np.array(keep)
    vertex_of = {int(k): v for v, k in enumerate(vidx.tolist())}
    over = z - target - settings.tolerance_m
    worst = int(np.argmax(over))
    return FollowProfile(p[keep_arr], z[keep_arr], np.array([vertex_of.get(int(k), -1) for k in keep_arr]),
                         max(0.0, float(over[worst])),
                         (float(p[worst, 0]), float(p[worst, 1])) if over[worst] > _EPS_M else None)
