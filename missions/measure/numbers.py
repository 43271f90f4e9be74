"""The numbers a pilot reads per survey or corridor step: what the compiler chose (angle, line spacing, lines,
trigger distance, footprint, capture files; `Compiled.step_facts`) with what the re-flight measures (photos, GSD
range, storage needed, flight time), and every assumption they rest on.

    numbers = step_numbers(compiled, sim)      # one StepNumbers per survey/corridor step, in mission order

Photos and flight time are the step's own: the photos taken and the path flown while the mission executes the
step's items (`AreaInfo.items`, as the report measures overlaps), the approach to its first waypoint included.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from missions.compiled import AreaInfo, Compiled, StepFacts
from missions.measure.flight import Simulation


@dataclass(frozen=True)
class PayloadNumbers:
    """One payload's photos over one step and the storage they need."""

    name: str
    photos: int
    gsd_cm: tuple[float, float] | None      # at the lowest and the highest photo; None: no photo
    formats: str                            # the files each photo writes
    mb_per_photo: float | None              # None: no published size
    size_source: str

    @property
    def storage_mb(self) -> float | None:
        return None if self.mb_per_photo is None else self.photos * self.mb_per_photo

    def to_json(self) -> dict[str, Any]:
        return {"photos": self.photos, "gsd_cm": None if self.gsd_cm is None else list(self.gsd_cm),
                "capture_formats": self.formats, "mb_per_photo": self.mb_per_photo,
                "storage_mb": None if self.storage_mb is None else round(self.storage_mb, 1),
                "size_source": self.size_source}

    def text(self) -> str:
        gsd = ("no photo" if self.gsd_cm is None else f"GSD {self.gsd_cm[0]:.2f} cm/px" if
               abs(self.gsd_cm[1] - self.gsd_cm[0]) < 0.005 else f"GSD {self.gsd_cm[0]:.2f}–{self.gsd_cm[1]:.2f} cm/px")
        files = f" ({self.formats})" if self.formats else ""
        storage = (f"storage {_mb_text(self.storage_mb)}{files}" if self.storage_mb is not None else
                   f"storage unknown{files}: {self.size_source}")
        return f"{self.photos} photos, {gsd}, {storage}"


@dataclass(frozen=True)
class StepNumbers:
    """One survey or corridor step as a pilot reads it."""

    facts: StepFacts
    altitude_m: float
    payloads: tuple[PayloadNumbers, ...]
    flight_time_s: float

    def to_json(self) -> dict[str, Any]:
        f = self.facts
        interval = f.photo_interval_s
        return {"step": f.step, "kind": f.kind, "where": f.where, "lead": f.lead,
                "angle_deg": None if f.angle_deg is None else round(f.angle_deg, 2), "angle_auto": f.angle_auto,
                "line_spacing_m": round(f.spacing_m, 2), "lines": f.lines, "trigger": f.trigger,
                "trigger_distance_m": round(f.trigger_distance_m, 2),
                "photo_interval_s": None if interval is None else round(interval, 3), "speed_mps": f.speed_mps,
                "altitude_m": round(self.altitude_m, 2),
                "footprint_m": {"across": round(f.footprint_m[0], 2), "along": round(f.footprint_m[1], 2)},
                "payloads": {p.name: p.to_json() for p in self.payloads},
                "flight_time_s": round(self.flight_time_s, 1), "assumptions": list(f.assumptions)}

    def rows(self) -> list[tuple[str, str]]:
        """(label, text) rows for the text report."""
        f = self.facts
        angle = ("along its centre line" if f.angle_deg is None else
                 f"angle {f.angle_deg:.1f}°" + (" (chosen: auto)" if f.angle_auto else ""))
        rows = [("lines", f"{f.lines} at {f.spacing_m:.1f} m spacing, {angle}"),
                ("trigger", _trigger_text(f)),
                ("footprint", f"{f.footprint_m[0]:.1f} × {f.footprint_m[1]:.1f} m (across × along) at "
                              f"{self.altitude_m:g} m")]
        rows += [(p.name, p.text()) for p in self.payloads]
        rows.append(("flight time", f"{self.flight_time_s / 60:.1f} min"))
        rows += [("assumes", a) for a in f.assumptions]
        return rows

    def summary(self) -> str:
        """One line for `wiris mission compile`."""
        f = self.facts
        angle = "" if f.angle_deg is None else f", angle {f.angle_deg:.0f}°" + (" (auto)" if f.angle_auto else "")
        photos = "; ".join(f"{p.name} {p.text()}" for p in self.payloads)
        return (f"step {f.step} {f.kind}: {f.lines} lines at {f.spacing_m:.1f} m{angle}, {_trigger_text(f)}, "
                f"footprint {f.footprint_m[0]:.0f} × {f.footprint_m[1]:.0f} m, {self.flight_time_s / 60:.1f} min; "
                f"{photos}")


def _mb_text(mb: float) -> str:
    return f"{mb / 1000:.2f} GB" if mb >= 1000 else f"{mb:.0f} MB"


def _trigger_text(f: StepFacts) -> str:
    if f.trigger == "hover":
        return f"hover photos {f.trigger_distance_m:.1f} m apart"
    return f"a photo every {f.trigger_distance_m:.1f} m = {f.photo_interval_s:.2f} s at {f.speed_mps:g} m/s"


def step_numbers(compiled: Compiled, sim: Simulation) -> tuple[StepNumbers, ...]:
    """Per survey or corridor step with facts, its numbers (see the module doc)."""
    areas = {a.step: a for a in compiled.areas}
    seg_time = np.diff(np.asarray(sim.vertex_times_s, dtype=float))
    seg_item = np.array([v.item for v in sim.vertices[1:]], dtype=int)
    return tuple(_numbers(compiled, sim, f, areas[f.step], seg_time, seg_item)
                 for f in compiled.step_facts if f.step in areas)


def _numbers(compiled: Compiled, sim: Simulation, facts: StepFacts, area: AreaInfo, seg_time: np.ndarray,
             seg_item: np.ndarray) -> StepNumbers:
    first, end = area.items if area.items is not None else (0, len(compiled.items))
    own = [p for p in sim.photos if first <= p.item < end]
    payloads = []
    for size in facts.capture:
        shots = [p for p in own if size.payload in p.payloads]
        payloads.append(PayloadNumbers(size.payload, len(shots), _gsd(compiled, size.payload, shots),
                                       size.formats, size.mb_per_photo, size.source))
    flown = (seg_item >= first) & (seg_item < end)
    return StepNumbers(facts, area.altitude_m, tuple(payloads), float(seg_time[flown].sum()))


def _gsd(compiled: Compiled, name: str, shots: list) -> tuple[float, float] | None:
    """GSD at the lowest and highest photo above the ground; None without a photo or known optics."""
    info = next((p for p in compiled.payloads if p.name == name), None)
    alts = [p.alt_m for p in shots if p.alt_m > 0]
    if info is None or not alts:
        return None
    return round(info.gsd_cm(min(alts)), 3), round(info.gsd_cm(max(alts)), 3)
