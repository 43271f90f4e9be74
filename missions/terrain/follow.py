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
   where that is above the band) and within the rates: each straight stretch runs as far as some slope keeps
   it in the band (the interval of such slopes narrows sample by sample) and ends as low as it may. The band's
   top is lowered where the ground falls faster than the vehicle may descend (`ceiling`), so from any point of
   the band the next sample's band is within reach and the stretches never get stuck.
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
    highest_agl_m: float          # the most the flown path rises above the ground (at a sample)


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


def ceiling(target: np.ndarray, tolerance_m: float, floor: np.ndarray, s: np.ndarray,
            descent_slope: float) -> np.ndarray:
    """The band's top: target + tolerance (never below the floor), lowered where the ground falls away faster
    than the vehicle may descend, so that from anywhere in the band the next sample's band is in reach."""
    top = np.maximum(target + tolerance_m, floor)
    ds = np.diff(s)
    for k in range(len(top) - 2, -1, -1):
        top[k] = min(top[k], top[k + 1] + descent_slope * ds[k])
    return top


class _Stretch(NamedTuple):
    end: int              # sample index where the straight stretch ends
    height_m: float       # the height there


def _longest_stretch(s: np.ndarray, lo: np.ndarray, hi: np.ndarray, i: int, z_i: float, last: int,
                     climb_slope: float, descent_slope: float) -> _Stretch:
    """From (s[i], z_i), the farthest sample up to `last` that one straight climb or descent reaches while staying
    within [lo, hi] at every sample on the way and within the rates; it ends as low as it can (near the target).
    The band's construction (`rate_limited`, `ceiling`) guarantees the next sample is always reachable."""
    slope_lo, slope_hi = -descent_slope, climb_slope
    end, end_lo = i + 1, None
    for k in range(i + 1, last + 1):
        run = s[k] - s[i]
        if run <= 0:
            continue
        new_lo = max(slope_lo, (lo[k] - z_i) / run)
        new_hi = min(slope_hi, (hi[k] - z_i) / run)
        if new_lo > new_hi + 1e-12:
            break
        slope_lo, slope_hi, end, end_lo = new_lo, new_hi, k, new_lo
    if end_lo is None:                      # a zero-length step (repeated vertex): stay level
        return _Stretch(end, z_i)
    height = z_i + end_lo * (s[end] - s[i])
    return _Stretch(end, float(min(max(height, lo[end]), hi[end])))


def follow_path(xy: np.ndarray, ground: Callable[[np.ndarray], np.ndarray], settings: FollowSettings,
                step_m: float) -> FollowProfile:
    """The followed profile of the path `xy` (metres); `ground(points)` gives heights above mean sea level."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    p, s, vidx = _samples(xy, step_m)
    g = ground(p)
    target = g + settings.target_agl_m
    z = rate_limited(target, s, settings.climb_slope, settings.descent_slope)
    hi = ceiling(target, settings.tolerance_m, z, s, settings.descent_slope)
    keep, heights = [0], [float(z[0])]
    for a, b in zip(vidx[:-1], vidx[1:]):
        i = int(a)
        while i < int(b):
            st = _longest_stretch(s, z, hi, i, heights[-1], int(b), settings.climb_slope, settings.descent_slope)
            keep.append(st.end)
            heights.append(st.height_m)
            i = st.end
    keep_arr = np.array(keep)
    vertex_of = {int(k): v for v, k in enumerate(vidx.tolist())}
    over = z - target - settings.tolerance_m
    worst = int(np.argmax(over))
    flown = np.interp(s, s[keep_arr], np.array(heights))
    return FollowProfile(p[keep_arr], np.array(heights), np.array([vertex_of.get(int(k), -1) for k in keep_arr]),
                         max(0.0, float(over[worst])),
                         (float(p[worst, 0]), float(p[worst, 1])) if over[worst] > _EPS_M else None,
                         float(np.max(flown - g)))
