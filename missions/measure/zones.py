"""The zone table of a survey or corridor step, measured on the re-flown mission (missions.measure.report).

For each zone near the step (`AreaInfo.zones`, missions.geometry.zones.StepZones), as drawn:
  * area_m2: the zone's area;
  * flown_inside_m: metres of the whole flight's path inside it (deeper than route.ZONE_EDGE_TOL_M);
  * photographed_m2: its ground under any photo's footprint, whichever payload or step took it (must be 0 for
    no_photo and exclude zones);
  * lost_m2: the part of the step's area (as drawn, less the no-photo and exclude zones) within the zone's reach
    (its margin plus the step's largest footprint side) that no photo of the step's lead payload covers: ground
    the zone keeps from being covered.
The coverable area is the step's area as drawn less the no-photo and exclude zones and less every zone's lost part:
coverage is measured on it, and what was lost is in the table, never hidden.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from missions.geometry.route import ZONE_EDGE_TOL_M


@dataclass(frozen=True)
class ZoneRow:
    """One zone as the report shows it (rounded)."""

    name: str
    kind: str
    area_m2: float
    flown_inside_m: float
    photographed_m2: float
    lost_m2: float
    margin_m: float

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "area_m2": self.area_m2, "flown_inside_m": self.flown_inside_m,
                "photographed_m2": self.photographed_m2, "lost_m2": self.lost_m2, "margin_m": self.margin_m}


@dataclass(frozen=True)
class ZoneMeasure:
    """A step's zone table and the area its coverage is measured on (shapely, the simulation's metres)."""

    rows: tuple[ZoneRow, ...]
    coverable: Any
    margin_m: float


def moved(geom: Any, src: Any, dst: Any) -> Any:
    """`geom` in metres of projection `src`, in metres of `dst` (through lat/lon)."""
    import shapely   # heavy: loads only when a plan has zones
    if geom.is_empty or src == dst:
        return geom

    def move(xy: np.ndarray) -> np.ndarray:
        lat, lon = src.to_latlon(xy[:, 0], xy[:, 1])
        return np.column_stack(dst.to_xy(lat, lon))

    return shapely.transform(geom, move)


def _inside_m(path_xy: np.ndarray, zone: Any) -> float:
    import shapely
    if len(path_xy) < 2:
        return 0.0
    core = zone.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    segs = shapely.linestrings(np.stack([path_xy[:-1], path_xy[1:]], axis=1))
    return float(shapely.length(shapely.intersection(segs, core)).sum())


def measure_zones(step_zones: Any, area: Any, proj: Any, path_xy: np.ndarray, lead_covered: Any,
                  all_covered: Any) -> ZoneMeasure:
    """The zone table of one step. `area`: its Area; `proj`: the simulation's projection; `lead_covered`: the union
    of the lead payload's footprints near the area, `all_covered`: of every photo of the flight (both in `proj`)."""
    import shapely
    from shapely.geometry import Polygon

    drawn = moved(area.drawn if area.drawn is not None else area.geometry, area.projection, proj)
    placed = [(z, z.xy(proj)) for z in step_zones.zones]
    no_photo = [g for z, g in placed if z.keeps_photos_out]
    wanted = drawn.difference(shapely.union_all(no_photo)) if no_photo else drawn
    rows, lost_parts = [], []
    for z, g in placed:
        reach = g.buffer(z.margin_m + step_zones.reach_m)
        lost = wanted.intersection(reach).difference(lead_covered) if not lead_covered.is_empty \
            else wanted.intersection(reach)
        lost_parts.append(lost)
        rows.append(ZoneRow(z.name, z.kind, round(float(g.area), 1), round(_inside_m(path_xy, g), 1),
                            round(float(all_covered.intersection(g).area), 1) if not all_covered.is_empty else 0.0,
                            round(float(lost.area), 1), z.margin_m))
    coverable = wanted.difference(shapely.union_all(lost_parts)) if lost_parts else wanted
    margins = {z.margin_m for z, _g in placed}
    return ZoneMeasure(tuple(rows), coverable if not coverable.is_empty else Polygon(),
                       max(margins) if margins else 0.0)


def photographed_warnings(step: int, kind: str, rows: Sequence[ZoneRow]) -> list[tuple[str, str]]:
    """(code, message) for a no-photo zone photographed or a no-fly zone flown over (the compiler prevents both:
    a hand-built mission, or a RedEdge shooting by itself, can still do it)."""
    out = []
    for r in rows:
        if r.kind in ("no_photo", "exclude") and r.photographed_m2 > 0.05:
            out.append(("zone_photographed", f"step {step} ({kind}): {r.photographed_m2:.1f} m² of {r.kind} zone "
                                             f"'{r.name}' are under a photo's footprint"))
        if r.kind in ("no_fly", "exclude") and r.flown_inside_m > 0.05:
            out.append(("zone_flown_over", f"step {step} ({kind}): the path runs {r.flown_inside_m:.1f} m inside "
                                           f"{r.kind} zone '{r.name}'"))
    return out
