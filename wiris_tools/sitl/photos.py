"""Photos a flight really took against the report's prediction: count, where each was taken, and the coverage
the taken ones give, measured the way the report measures its own (missions.measure).

    check = check_photos(compiled, "thermal", [(lat, lon, rel_alt_m), ...])   # e.g. from the emulator's history
    check.predicted, check.captured, check.worst_offset_m, check.coverage_predicted, check.coverage_captured
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from missions.geometry.footprint import Footprint
from missions.geometry.triggers import PhotoPoint
from missions.measure.coverage import coverage_fraction, footprint_polygons
from missions.measure.flight import simulate
from missions.measure.report import measured_ground, report


@dataclass(frozen=True)
class PhotoCheck:
    payload: str
    predicted: int
    captured: int
    worst_offset_m: float        # the farthest any photo (taken or predicted) lies from its nearest counterpart
    median_offset_m: float
    coverage_predicted: float    # the report's figure over the plan's areas (fraction), or nan without an area
    coverage_captured: float     # the same measure over the photos taken

    @property
    def count_ok(self) -> bool:
        """Within 1 % or 2 photos."""
        return abs(self.captured - self.predicted) <= max(2, 0.01 * self.predicted)


def _nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each point of `a`, the distance to the nearest of `b`."""
    if len(a) == 0 or len(b) == 0:
        return np.full(len(a), np.inf)
    d = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
    return d.min(axis=1)


def check_photos(compiled: Any, payload: str, captured: Sequence[tuple[float, float, float]]) -> PhotoCheck:
    """`captured`: (lat, lon, altitude above home m) of each photo `payload` took, in order."""
    sim = simulate(compiled)
    proj = sim.projection
    predicted = [p for p in sim.photos if payload in p.payloads]
    pred_xy = np.array([(p.x, p.y) for p in predicted], dtype=float).reshape(-1, 2)
    if captured:
        x, y = proj.to_xy([c[0] for c in captured], [c[1] for c in captured])
        got_xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    else:
        got_xy = np.zeros((0, 2))
    offsets = np.concatenate([_nearest(got_xy, pred_xy), _nearest(pred_xy, got_xy)])
    rep = report(compiled, sim)
    return PhotoCheck(payload, len(predicted), len(captured),
                      float(offsets.max()) if len(offsets) else 0.0,
                      float(np.median(offsets)) if len(offsets) else 0.0,
                      float(rep.coverage.get(payload, float("nan"))),
                      _captured_coverage(compiled, sim, payload, predicted, pred_xy, got_xy, captured))


def _captured_coverage(compiled: Any, sim: Any, payload: str, predicted: list, pred_xy: np.ndarray,
                       got_xy: np.ndarray, captured: Sequence[tuple[float, float, float]]) -> float:
    """Coverage of the plan's areas by the photos taken: each footprint at the altitude it was taken from, turned
    to the heading of the nearest predicted photo (the camera reports no attitude: Workswell manual §6.4.5)."""
    import shapely   # heavy: only here

    geom = measured_ground(compiled, sim, payload)   # the report's own: the areas less what zones make uncoverable
    if geom is None:
        return float("nan")
    if len(got_xy) == 0 or len(pred_xy) == 0:
        return 0.0
    d = np.hypot(got_xy[:, None, 0] - pred_xy[None, :, 0], got_xy[:, None, 1] - pred_xy[None, :, 1])
    near = d.argmin(axis=1)
    info = compiled.payload(payload)
    points: dict[float, list[PhotoPoint]] = {}
    for k, (x, y) in enumerate(got_xy):
        alt = round(float(captured[k][2]))
        if alt <= 0:
            continue
        p = predicted[int(near[k])]
        points.setdefault(alt, []).append(PhotoPoint(float(x), float(y), p.heading_deg, p.span))
    polys = []
    for alt, pts in points.items():
        polys.append(footprint_polygons(np.array([(p.x, p.y) for p in pts]), np.radians([p.heading_deg for p in pts]),
                                        Footprint(*info.footprint_m(alt))))
    if not polys:
        return 0.0
    if len(polys) == 1:
        (alt, pts), = points.items()
        return coverage_fraction(geom, pts, Footprint(*info.footprint_m(alt)))[1]
    union = shapely.union_all(np.concatenate(polys))
    return float(shapely.intersection(geom, union).area / geom.area)
