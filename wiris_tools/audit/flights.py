"""Several logs of one plan audited together: a plan split into sorties flown on fresh batteries (one log
each), or a mission resumed after a battery swap. Each log is audited on its own against the sortie it flew
(found from where its photos lie: the sortie whose planned photos its captures meet most), and all of them as
one flight: the union's coverage, overlaps and gaps decide whether the plan is done, and its refly covers what
none of the flights captured.

    multi = audit_flights(compiled, [read_log("sortie1.tlog"), read_log("sortie2.tlog")], "plan.yaml")
    multi.flights[0].sortie, multi.flights[0].audit.steps[0].missing_planned, multi.union.complete
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from missions.compiled import Compiled
from wiris_tools.audit.logs import FlightLog
from wiris_tools.audit.measure import Audit, FlightAudit, audit_flight, format_audit


@dataclass(frozen=True)
class SortieFlight:
    """One log of the plan: the sortie it flew (None: the plan is one mission) and its own audit."""

    sortie: int | None
    audit: Audit

    def to_json(self) -> dict:
        return {"sortie": self.sortie, **self.audit.to_json()}


@dataclass(frozen=True)
class MultiAudit:
    plan: str
    flights: tuple[SortieFlight, ...]
    union: Audit                       # every log's captures together against the plan's areas
    sorties_planned: int               # the plan's sorties (0: one mission)
    notes: tuple[str, ...]

    @property
    def complete(self) -> bool:
        return self.union.complete

    def to_json(self) -> dict:
        return {"plan": self.plan, "sorties_planned": self.sorties_planned,
                "flights": [f.to_json() for f in self.flights], "union": self.union.to_json(),
                "complete": self.complete, "notes": list(self.notes)}


def _shots(log: FlightLog) -> list:
    ok = [s for s in log.captures if s.ok]
    return ok or list(log.triggers)


def _sortie_of(compiled: Compiled, log: FlightLog, taken: set[int]) -> int | None:
    """The sortie whose planned photos this log's photos meet most (within half a trigger distance); a sortie
    already given to another log loses a tie."""
    from missions.measure.flight import simulate
    from wiris_tools.audit.measure import sortie_photos
    if not compiled.sorties:
        return None
    proj = simulate(compiled).projection
    shots = _shots(log)
    if not shots:
        return None
    x, y = proj.to_xy(np.array([s.pose.lat for s in shots]), np.array([s.pose.lon for s in shots]))
    xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    reach = min((a.trigger_distance_m or compiled.payload(a.payloads[0]).footprint_m(a.altitude_m)[1]) / 2
                for a in compiled.areas) if compiled.areas else 5.0
    best, best_key = None, None
    for s in compiled.sorties:
        planned = np.array([(p.x, p.y) for p in sortie_photos(compiled, s)], float).reshape(-1, 2)
        if not len(planned):
            continue
        d = np.hypot(planned[:, None, 0] - xy[None, :, 0], planned[:, None, 1] - xy[None, :, 1])
        key = (int((d.min(axis=1) <= reach).sum()), s.number not in taken)
        if best_key is None or key > best_key:
            best, best_key = s, key
    return None if best is None or best_key[0] == 0 else best.number


def _merged(logs: Sequence[FlightLog]) -> FlightLog:
    """One record of every log's photos (triggers left out: their pairing with captures is each log's)."""
    def own(shots, k):
        return tuple(dataclasses.replace(s, flight=k) for s in shots)
    captures = tuple(c for k, l in enumerate(logs) for c in own(l.captures, k))
    triggers = tuple(t for k, l in enumerate(logs) for t in own(l.triggers, k)) if not captures else ()
    return FlightLog(" + ".join(l.path for l in logs), "+".join(dict.fromkeys(l.kind for l in logs)),
                     captures, triggers, tuple(p for l in logs for p in l.track), (), (), ())


def _sum(values: Sequence[int | None]) -> int | None:
    known = [v for v in values if v is not None]
    return sum(known) if known else None


def audit_flights(compiled: Compiled, logs: Sequence[FlightLog], plan_path: str = "", mount: str = "gimbal",
                  images: Sequence[Any] | None = None) -> MultiAudit:
    """Each log against the sortie it flew, and all of them as one flight. `images` are matched against the
    union's captures (by sequence where the numbers are unique across the logs, else by time)."""
    taken: set[int] = set()
    flights = []
    for log in logs:
        number = _sortie_of(compiled, log, taken)
        if number is not None:
            taken.add(number)
        sortie = next((s for s in compiled.sorties if s.number == number), None)
        flights.append(SortieFlight(number, audit_flight(compiled, log, plan_path, mount, sortie=sortie)))
    union = audit_flight(compiled, _merged(logs), plan_path, mount, images=images)
    audits = [f.audit for f in flights]
    left = tuple(f"{'sortie ' + str(f.sortie) if f.sortie is not None else f.audit.log}: {s}"
                 for f in flights for s in f.audit.flight.left_plan)
    union = dataclasses.replace(
        union, triggered=_sum([a.triggered for a in audits]), captured=_sum([a.captured for a in audits]),
        failed=sum(a.failed for a in audits), triggered_not_captured=(), captured_not_triggered=(),
        flight=FlightAudit(tuple(m for a in audits for m in a.flight.modes), sum(a.flight.sorties for a in audits),
                           None, len(compiled.items), left),
        notes=tuple(n for n in union.notes if n not in {n2 for a in audits for n2 in a.notes}))
    notes = []
    numbers = [f.sortie for f in flights if f.sortie is not None]
    if compiled.sorties:
        flown = sorted(set(numbers))
        missing = [s.number for s in compiled.sorties if s.number not in flown]
        if missing:
            notes.append(f"no log of sortie(s) {', '.join(map(str, missing))} of {len(compiled.sorties)}")
        again = sorted({n for n in numbers if numbers.count(n) > 1})
        if again:
            notes.append(f"sortie(s) {', '.join(map(str, again))} flown more than once (a refly after an abort?)")
    return MultiAudit(plan_path or compiled.name, tuple(flights), union, len(compiled.sorties), tuple(notes))


def format_multi(multi: MultiAudit) -> str:
    head = (f"audit of {len(multi.flights)} flights against {multi.plan}"
            + (f" (planned as {multi.sorties_planned} sorties)" if multi.sorties_planned else ""))
    lines = [head]
    order = sorted(enumerate(multi.flights, 1), key=lambda kf: (kf[1].sortie is None, kf[1].sortie or 0, kf[0]))
    for k, f in order:                   # in the plan's sortie order, whatever order the logs came in
        label = f"sortie {f.sortie}" if f.sortie is not None else f"flight {k}"
        first, *rest = format_audit(f.audit, verdict=False).split("\n")
        lines += [f"{label}: {first.removeprefix('audit of ')}", *rest]
    lines.append("all flights together:")
    f = multi.union.flight
    lines += [ln if not ln.startswith("  flight: modes") else
              f"  flights: {len(multi.flights)} logs, {f.sorties} armed period(s)"
              for ln in format_audit(multi.union).split("\n")[1:]]
    lines += [f"  note: {n}" for n in multi.notes]
    return "\n".join(lines)
