"""Contour lines of the DEM for the preview (missions.formats.preview draws them under the path).

    c = contours(dem, projection, (x0, y0, x1, y1))   # Contours(interval_m, segments) in the projection's metres

The DEM is sampled on a GRID x GRID lattice over the box and cut at round levels (marching squares, one straight
segment per cell crossing; a saddle cell gets two). The interval is the round step giving about TARGET_LEVELS
lines between the lowest and the highest ground.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

GRID = 120
TARGET_LEVELS = 12
_STEPS_M = (1, 2, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000)

Segment = tuple[tuple[float, float], tuple[float, float]]


class Contours(NamedTuple):
    interval_m: float
    segments: tuple[tuple[float, Segment], ...]      # (level, segment)


def _interval(lo: float, hi: float) -> float:
    span = max(hi - lo, 1e-9)
    return float(next((s for s in _STEPS_M if span / s <= TARGET_LEVELS), _STEPS_M[-1]))


def _cell_segments(z: np.ndarray, xs: np.ndarray, ys: np.ndarray, level: float) -> list[Segment]:
    """Marching squares of one level: per cell, the crossings of its four edges paired in order."""
    a, b, c, d = z[:-1, :-1], z[:-1, 1:], z[1:, 1:], z[1:, :-1]        # corners: (r, k), (r, k+1), (r+1, k+1), (r+1, k)
    out: list[Segment] = []
    corners = ((a, b, 0, 0, 0, 1), (b, c, 0, 1, 1, 1), (d, c, 1, 0, 1, 1), (a, d, 0, 0, 1, 0))
    pts = []
    for p, q, r0, c0, r1, c1 in corners:
        cross = ((p - level) * (q - level) < 0) & np.isfinite(p) & np.isfinite(q)
        t = np.where(cross, (level - p) / np.where(cross, q - p, 1.0), 0.0)
        pts.append((cross, t, r0, c0, r1, c1))
    n = sum(pp[0].astype(int) for pp in pts)
    for r, k in zip(*np.nonzero(n >= 2)):
        here = []
        for cross, t, r0, c0, r1, c1 in pts:
            if cross[r, k]:
                tt = float(t[r, k])
                x = xs[k + c0] + (xs[k + c1] - xs[k + c0]) * tt
                y = ys[r + r0] + (ys[r + r1] - ys[r + r0]) * tt
                here.append((float(x), float(y)))
        out.append((here[0], here[1]))
        if len(here) == 4:
            out.append((here[2], here[3]))
    return out


def contours(dem: Any, projection: Any, box: tuple[float, float, float, float]) -> Contours:
    x0, y0, x1, y1 = box
    xs, ys = np.linspace(x0, x1, GRID), np.linspace(y0, y1, GRID)
    X, Y = np.meshgrid(xs, ys)
    lat, lon = projection.to_latlon(X.ravel(), Y.ravel())
    z = dem.ground_amsl(lat, lon).reshape(X.shape)
    if not np.isfinite(z).any():
        return Contours(0.0, ())
    lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
    step = _interval(lo, hi)
    levels = np.arange(np.ceil(lo / step) * step, hi, step)
    return Contours(step, tuple((float(L), s) for L in levels for s in _cell_segments(z, xs, ys, float(L))))
