"""The sorties of a mission measured as flown: each sortie's own re-flight (time, photos, items) and the union
of their photos measured against the plan's areas, so that a gap or a thin overlap at a seam shows.

    table = measure_sorties(compiled)     # None when the mission is flown as one
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from missions.compiled import Compiled
from missions.measure.flight import self_triggering, simulate
from missions.sorties import as_sortie, union_photos


def sortie_file(name: str, number: int) -> str:
    return f"{name}.sortie{number}.plan"


@dataclass(frozen=True)
class SortieTable:
    """Per sortie its row (`Sortie.to_json`), and per payload the union's coverage and lowest overlaps."""

    rows: tuple[dict, ...]
    coverage: Mapping[str, float]
    overlap: Mapping[str, Any]              # report.OverlapMin (rounded)
    endurance: dict | None
    # each sortie's re-flown path as (lat, lon, metres above home), for the maps (GeoJSON/KML, preview)
    paths: tuple[tuple[tuple[float, float, float], ...], ...] = ()

    def to_json(self) -> dict:
        return {"rows": list(self.rows), "coverage": dict(self.coverage),
                "overlap": {n: o.to_json() for n, o in self.overlap.items()}, "endurance": self.endurance}


def measure_sorties(compiled: Compiled) -> SortieTable | None:
    from missions.measure import report as rp

    if not compiled.sorties:
        return None
    sims = [s.flight if s.flight is not None else simulate(as_sortie(compiled, s.items)) for s in compiled.sorties]
    photos = union_photos(compiled, compiled.sorties, sims)
    projection = sims[0].projection
    own = self_triggering(compiled)
    steps = []
    for a in compiled.areas:
        if not a.payloads:
            continue
        geom = rp.area_geometry(a.area, projection)
        zones = rp.photo_zones(a.area, projection)
        if getattr(a, "zones", None) is not None:      # the ground the step can cover (missions.measure.zones)
            photos_of = {p.name: [q for q in photos if p.name in q.payloads] for p in compiled.payloads}
            geom = rp._zone_table(compiled, a, geom, photos_of, sims[0]).coverable
        measured = tuple(rp._measure_payload(a, geom, zones, n, compiled.payload(n),
                                             [p for p in photos if n in p.payloads], self_shooting=n in own)
                         for n in a.payloads)
        steps.append(rp.StepMeasure(a, measured, None))
    rows = tuple(s.to_json(sortie_file(compiled.name, s.number)) | {"flight_time_s": round(sim.flight_time_s, 1)}
                 for s, sim in zip(compiled.sorties, sims))
    endurance = compiled.endurance.to_json() if compiled.endurance is not None else None
    paths = tuple(tuple((lat, lon, v.alt_m) for (lat, lon), v in zip(sim.latlon, sim.vertices)) for sim in sims)
    return SortieTable(rows, rp._mission_coverage(steps), rp._mission_overlap(steps), endurance, paths)


def table_lines(table: SortieTable) -> list[str]:
    """The sortie table of `wiris mission check`."""
    head = f"{'sortie':<8}{'file':<34}{'flight':>9}{'photos':>8}{'items':>7}  lines"
    out = [head]
    for k, r in enumerate(table.rows, start=1):
        lines = "-" if r["first_line"] is None else f"{r['first_line']}..{r['last_line']}"
        out.append(f"{k:<8}{r['file']:<34}{r['flight_time_s'] / 60:>6.1f} min{r['photos']:>8}{r['items']:>7}  {lines}")
    for n, c in table.coverage.items():
        o = table.overlap[n]
        f = "-" if o.front_min is None else f"{100 * o.front_min:.1f} %"
        s = "-" if o.side_min is None else f"{100 * o.side_min:.1f} %"
        out.append(f"union of the sorties, {n}: coverage {100 * c:.2f} %, minimum overlap front {f}, side {s}")
    return out
