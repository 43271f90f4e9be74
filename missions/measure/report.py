"""The measured report of a compiled mission, from the re-flight of its items (`missions.measure.flight`).

    sim = simulate(compiled)        # missions.measure.flight
    rep = report(compiled, sim)     # the `wiris mission check --json` object (cli.md's binding fields + more)

How the flight is measured:
* Measuring: per survey/corridor step and payload with `missions.measure.coverage`, in one metric plane (the first
  area's projection, so photos on a line stay exactly collinear). Coverage takes every photo whose footprint can
  reach the area, whichever step took it, grouped by altitude (one footprint size per group; coverage is the
  union over all groups). The rest is the step's own, so that a neighbouring step does not blur it: its overlaps,
  photo count and metres outside the area take the photos taken and the path flown while the mission executes
  the step's items (`AreaInfo.items`; the vehicle executes a NAV item while it flies towards it and holds at it,
  so the approach to the step's first waypoint is the step's). Front
  overlap pairs consecutive photos of one camera-on stretch; a turn of more than TURN_SPLIT_DEG starts a new
  stretch (a turnaround is not a front pair; a corridor's gentle bend is, and its lower overlap is real).
  Coverage below COVERAGE_TARGET and overlaps more than OVERLAP_SLACK below the request are warnings, not
  errors: the mission flies, the result is worse than asked.
* Holes and exclusion zones: the whole flown path is measured inside each step's zones as drawn
  (`Area.excluded`, so an exclusion across the boundary counts too), deeper than route.ZONE_EDGE_TOL_M (a
  path along a zone's edge is beside it), split into metres with the camera on (distance or interval
  triggering) and off, with the photos centred inside; more than a metre is the path_over_exclusion warning.
  Unlike the figures above these stay the whole flight's: an exclusion is ground not to fly over or photograph
  (the plan schema's words), and another step flying over it is as real as this one.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from missions.compiled import Compiled, PayloadInfo
from missions.measure.flight import Photo, Simulation, simulate
from missions.plan.schema import MAX_AGL_M

# Coverage below this is worth a warning: the examples and the tests hold the compiler to it.
COVERAGE_TARGET = 0.995
# Measured minimum overlaps within this of the request are rounding at the edges, not a planning fault.
OVERLAP_SLACK = 0.01


def area_geometry(area: Any, proj: Any) -> Any:
    """`area` (missions.geometry.area.Area) as a shapely geometry in projection `proj` (re-projected through
    lat/lon when it was built in another plane; its edges are short enough to stay straight in both)."""
    from shapely.geometry import MultiPolygon, Polygon

    if area.projection == proj:
        return area.geometry
    polys = []
    for rings in area.latlon_rings():
        xy = []
        for ring in rings:
            x, y = proj.to_xy([p[0] for p in ring], [p[1] for p in ring])
            xy.append(list(zip(x.tolist(), y.tolist())))
        polys.append(Polygon(xy[0], xy[1:]))
    return polys[0] if len(polys) == 1 else MultiPolygon(polys)


# --------------------------------------------------------------------------------------------- measuring

def footprint_ring(photo: Photo, payload: PayloadInfo) -> list[tuple[float, float]]:
    """The photo's footprint corners in the simulation's metres (x, y), closed ring."""
    across, along = payload.footprint_m(max(photo.alt_m, 0.0))
    h = math.radians(photo.heading_deg)
    d = np.array([math.sin(h), math.cos(h)])
    n = np.array([math.cos(h), -math.sin(h)])
    c = np.array([photo.x, photo.y])
    pts = [c - d * along / 2 - n * across / 2, c + d * along / 2 - n * across / 2,
           c + d * along / 2 + n * across / 2, c - d * along / 2 + n * across / 2]
    pts.append(pts[0])
    return [(float(p[0]), float(p[1])) for p in pts]


def _measure_area(area_info: Any, payload: PayloadInfo, photos: Sequence[Photo], sim: Simulation,
                  path: np.ndarray | None = None) -> dict:
    """Coverage and overlaps of one payload's photos over one area, in the area's own projection.

    Coverage counts every photo whose footprint can reach the area: a neighbouring step's photo covers ground
    too. The overlaps and the photo count take the photos the step took (`area_info.items`), the metres outside
    the area the path segments it flew (`path`, a mask over the simulation's segments, `_step_paths`): another
    step's photos and path are measured against its own area. Without a range (an AreaInfo built by hand) the
    photos near the area and the whole path stand in for them. The zones are checked against the whole flight:
    an exclusion is ground not to fly over or photograph, whichever step does it."""
    import shapely
    from missions.measure.coverage import coverage_fraction, footprint_polygons, min_front_overlap, min_side_overlap
    from missions.geometry.footprint import Footprint
    from missions.geometry.triggers import PhotoPoint

    proj = sim.projection
    geom = area_geometry(area_info.area, proj)
    result: dict[str, Any] = {"coverage": 0.0, "front_min": None, "side_min": None, "photos": 0}
    if photos:
        x = np.array([p.x for p in photos])
        y = np.array([p.y for p in photos])
        alts = np.array([max(p.alt_m, 0.0) for p in photos])
        # photos whose footprint can reach the area (others cover other ground)
        reach = max(payload.footprint_m(1.0)) * alts        # footprints scale with altitude
        near = np.nonzero(shapely.dwithin(shapely.points(x, y), geom, reach))[0]
    else:
        x = y = alts = np.zeros(0)
        near = np.zeros(0, int)
    if area_info.items is not None:
        first, end = area_info.items
        own = np.array([k for k, p in enumerate(photos) if first <= p.item < end], dtype=int)
    else:
        own = near

    def by_altitude(idx: np.ndarray) -> dict[float, list[int]]:
        """One Footprint per altitude; photos keep their mission order within a group."""
        groups: dict[float, list[int]] = {}
        for k in idx.tolist():
            if alts[k] > 0:
                groups.setdefault(round(float(alts[k]), 2), []).append(k)
        return groups

    def points(ks: list[int]) -> list[PhotoPoint]:
        return [PhotoPoint(float(x[k]), float(y[k]), photos[k].heading_deg, photos[k].span) for k in ks]

    groups = by_altitude(near)
    if len(groups) == 1:
        (alt, ks), = groups.items()
        result["coverage"] = coverage_fraction(geom, points(ks), Footprint(*payload.footprint_m(alt)))[1]
    elif groups and geom.area > 0:
        polys = [footprint_polygons(np.column_stack([x[ks], y[ks]]), np.radians([photos[k].heading_deg for k in ks]),
                                    Footprint(*payload.footprint_m(alt))) for alt, ks in groups.items()]
        union = shapely.union_all(np.concatenate(polys))
        result["coverage"] = float(shapely.intersection(geom, union).area / geom.area)
    fronts, sides = [], []
    for alt, ks in by_altitude(own).items():
        fp = Footprint(*payload.footprint_m(alt))
        fronts.append(min_front_overlap(points(ks), fp))
        sides.append(min_side_overlap(points(ks), fp))
    result["front_min"] = min((f for f in fronts if f is not None), default=None)
    result["side_min"] = min((s for s in sides if s is not None), default=None)
    result["photos"] = int(len(own))
    result["outside_m"] = _outside_m(sim.xy, path, geom)
    zones = _zones(area_info.area, proj)
    result["over_gaps_m"], result["over_gaps_camera_m"] = _over_zones_m(sim, zones)
    result["photos_in_zones"] = _photos_in(zones, photos)
    return result


def _step_paths(compiled: Compiled, sim: Simulation) -> list[np.ndarray | None]:
    """Per area step, the path segments it flew (a mask over the simulation's segments; None: unknown, a
    hand-built AreaInfo). Segment k (vertex k to k + 1) is flown executing the NAV item of vertex k + 1, so a step's
    path is what it flies towards its own waypoints, the approach to its first one included."""
    seg_item = np.array([v.item for v in sim.vertices[1:]], dtype=int)
    return [None if a.items is None else (seg_item >= a.items[0]) & (seg_item < a.items[1]) for a in compiled.areas]


def _outside_m(xy: np.ndarray, path: np.ndarray | None, geom: Any) -> float:
    """Metres of the path segments `path` selects (None: all) outside `geom`, one polyline per run of them."""
    from missions.measure.coverage import outside_length_m

    if path is None:
        return outside_length_m(xy, geom)
    k = np.flatnonzero(path)
    if not len(k):
        return 0.0
    cut = np.flatnonzero(np.diff(k) > 1)
    return sum(outside_length_m(xy[a:b + 2], geom) for a, b in zip(np.r_[k[0], k[cut + 1]], np.r_[k[cut], k[-1]]))


def _zones(area: Any, proj: Any) -> Any:
    """The area's holes and exclusion zones as drawn (`Area.excluded`: an exclusion that touches, crosses or
    splits the boundary is no hole of the surveyed geometry) in projection `proj`. An Area built without that
    record (by hand) has only its geometry's holes."""
    import shapely
    from shapely.geometry import Polygon

    from missions.geometry.geo import leaf_parts

    zones = getattr(area, "excluded", None)
    if zones is None:
        holes = [Polygon(r) for p in leaf_parts(area.geometry, "Polygon") for r in p.interiors]
        zones = shapely.union_all(holes) if holes else Polygon()
    if zones.is_empty or area.projection == proj:
        return zones

    def move(xy: np.ndarray) -> np.ndarray:
        lat, lon = area.projection.to_latlon(xy[:, 0], xy[:, 1])
        return np.column_stack(proj.to_xy(lat, lon))

    return shapely.transform(zones, move)


def _over_zones_m(sim: Simulation, zones: Any) -> tuple[float, float]:
    """Metres of the flown path inside `zones`, and how many of them with the camera on. Inside means deeper than
    route.ZONE_EDGE_TOL_M: a path along a zone's edge (a detour inside the area) is beside it."""
    import shapely
    from missions.geometry.route import ZONE_EDGE_TOL_M

    xy = sim.xy
    if zones.is_empty or len(xy) < 2:
        return 0.0, 0.0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    shapely.prepare(core)
    segs = shapely.linestrings(np.stack([xy[:-1], xy[1:]], axis=1))
    inside = np.zeros(len(segs))
    hit = shapely.intersects(core, segs)
    if hit.any():
        inside[hit] = shapely.length(shapely.intersection(segs[hit], core))
    on = np.zeros(len(segs), bool)
    for s0, s1 in sim.camera_on:
        on[s0:s1] = True
    return float(inside.sum()), float(inside[on].sum())


def _photos_in(zones: Any, photos: Sequence[Photo]) -> int:
    """Photos centred inside `zones` (deeper than the edge tolerance, as for the path)."""
    import shapely
    from missions.geometry.route import ZONE_EDGE_TOL_M

    if zones.is_empty or not photos:
        return 0
    core = zones.buffer(-ZONE_EDGE_TOL_M, join_style="mitre")
    return int(shapely.contains_xy(core, [p.x for p in photos], [p.y for p in photos]).sum())


def _r(v: float | None, nd: int = 4) -> float | None:
    return None if v is None else round(float(v), nd)


def report(compiled: Compiled, sim: Simulation | None = None, plan_path: str | None = None) -> dict:
    """The measured report (`wiris mission check --json`)."""
    sim = sim or simulate(compiled)
    warnings: list[dict] = [{"code": w.code, "message": w.message} for w in compiled.warnings]
    errors: list[dict] = []
    names = [p.name for p in compiled.payloads]
    photos_of = {n: [p for p in sim.photos if n in p.payloads] for n in names}
    seq_base = 1 if compiled.firmware == "ardupilot" else 0

    # areas: coverage and overlap per payload, measured against what each step must cover
    area_rows = []
    cov_acc: dict[str, list[tuple[float, float]]] = {}
    ov_acc: dict[str, dict[str, list[float]]] = {}
    for a, path in zip(compiled.areas, _step_paths(compiled, sim)):
        row: dict[str, Any] = {"step": a.step, "kind": a.kind, "area_m2": _r(a.area.area_m2, 1),
                               "altitude_m": _r(a.altitude_m, 2), "trigger": a.trigger,
                               "requested": {"front": a.front_overlap, "side": a.side_overlap},
                               "coverage": {}, "overlap": {}, "photos": {}}
        for pname in a.payloads:
            pay = compiled.payload(pname)
            m = _measure_area(a, pay, photos_of.get(pname, []), sim, path)
            row["coverage"][pname] = _r(m["coverage"], 5)
            row["overlap"][pname] = {"front_min": _r(m["front_min"]), "side_min": _r(m["side_min"])}
            row["photos"][pname] = m["photos"]
            row["outside_m"] = _r(m["outside_m"], 1)
            row["over_gaps_m"] = _r(m["over_gaps_m"], 1)
            row["over_gaps_camera_m"] = _r(m["over_gaps_camera_m"], 1)
            row.setdefault("photos_in_zones", {})[pname] = m["photos_in_zones"]
            cov_acc.setdefault(pname, []).append((m["coverage"], a.area.area_m2))
            acc = ov_acc.setdefault(pname, {"front": [], "side": []})
            if m["front_min"] is not None:
                acc["front"].append(m["front_min"])
            if m["side_min"] is not None:
                acc["side"].append(m["side_min"])
            where = f"step {a.step} ({a.kind}), payload {pname}"
            if m["coverage"] < COVERAGE_TARGET:
                warnings.append({"code": "coverage_low",
                                 "message": f"{where}: measured coverage {100 * m['coverage']:.2f} % "
                                            f"(target {100 * COVERAGE_TARGET:.1f} %)"})
            if a.trigger != "hover" and m["front_min"] is not None and m["front_min"] < a.front_overlap - OVERLAP_SLACK:
                warnings.append({"code": "front_overlap_low",
                                 "message": f"{where}: minimum front overlap {100 * m['front_min']:.1f} % "
                                            f"< requested {100 * a.front_overlap:.0f} %"})
            if m["side_min"] is not None and m["side_min"] < a.side_overlap - OVERLAP_SLACK:
                warnings.append({"code": "side_overlap_low",
                                 "message": f"{where}: minimum side overlap {100 * m['side_min']:.1f} % "
                                            f"< requested {100 * a.side_overlap:.0f} %"})
        if row.get("over_gaps_m", 0) > 1.0:
            warnings.append({"code": "path_over_exclusion", "message": _over_zones_text(a, row)})
        area_rows.append(row)
    coverage = {n: _r(sum(c * A for c, A in v) / sum(A for _, A in v), 5) if sum(A for _, A in v) > 0 else 0.0
                for n, v in cov_acc.items()}
    overlap = {n: {"front_min": _r(min(v["front"])) if v["front"] else None,
                   "side_min": _r(min(v["side"])) if v["side"] else None} for n, v in ov_acc.items()}

    gsd = {}
    for n in names:
        ph = photos_of[n]
        if ph:
            pay = compiled.payload(n)
            alts = [p.alt_m for p in ph if p.alt_m > 0]
            gsd[n] = [_r(pay.gsd_cm(min(alts)), 3), _r(pay.gsd_cm(max(alts)), 3)] if alts else None
        else:
            gsd[n] = None

    # safety and feasibility
    max_alt = max((v.alt_m for v in sim.vertices), default=0.0)
    high = [v for v in sim.vertices if v.alt_m > MAX_AGL_M + 1e-6]
    # the compiler already warned with the plan's file:line:col when the plan asks for it
    if high and not any(w.code == "altitude_above_120m" for w in compiled.warnings):
        v = max(high, key=lambda v: v.alt_m)
        warnings.append({"code": "altitude_above_120m",
                         "message": f"item {v.item + seq_base} flies at {v.alt_m:.1f} m above home, above the "
                                    f"{MAX_AGL_M:.0f} m most rules allow without a permit"})
    for code, msg in sim.notes:
        warnings.append({"code": code, "message": msg})
    if compiled.items and not sim.ends_on_ground:
        warnings.append({"code": "no_landing", "message": "the mission ends in the air (no RTL or LAND): the "
                                                           "vehicle will hold at the last waypoint"})
    if len(compiled.parts) > 1 and not any(w["code"] == "mission_split" for w in warnings):
        warnings.append({"code": "mission_split",
                         "message": f"{len(compiled.items)} items exceed the limit of {compiled.item_limit}: "
                                    f"split into {len(compiled.parts)} parts, flown one after another"})
    for k, part in enumerate(compiled.parts):
        if len(part) > compiled.item_limit:
            errors.append({"code": "item_limit",
                           "message": f"part {k + 1} has {len(part)} items, more than the limit of {compiled.item_limit}"})
    if not compiled.items:
        errors.append({"code": "empty_mission", "message": "the mission has no items"})
    fast: dict[str, list[tuple[float, int]]] = {}
    for pname, _value, secs, src in sim.trigger_intervals:
        pay = compiled.payload(pname)
        if pay.min_interval_s and secs < pay.min_interval_s - 1e-9:
            fast.setdefault(pname, []).append((secs, src))
    for pname, spans in fast.items():
        secs, src = min(spans)
        pay = compiled.payload(pname)
        warnings.append({"code": "trigger_interval_short",
                         "message": f"{pname} would shoot every {secs:.2f} s ("
                                    + (f"item {src + seq_base}" if src >= 0 else "its own overlap mode")
                                    + (f" and {len(spans) - 1} more camera-on legs" if len(spans) > 1 else "")
                                    + f"), faster than the camera's minimum of {pay.min_interval_s:g} s at "
                                      f"{compiled.speed_mps:g} m/s — photos will be lost; fly slower or reduce "
                                      "the front overlap"})
    if not any(w["code"] == "assumed_optics" for w in warnings):
        warnings.extend(_optics_warnings(compiled))

    return {
        "plan": plan_path or compiled.name,
        "name": compiled.name,
        "firmware": compiled.firmware,
        "frame": compiled.frame,
        "mission_items": len(compiled.items),
        "item_limit": compiled.item_limit,
        "parts": len(compiled.parts),
        "part_items": [len(p) for p in compiled.parts],
        "photos": {n: len(photos_of[n]) for n in names},
        "path_length_m": _r(sim.path_length_m, 1),
        "climb_m": _r(sim.climb_m, 1),
        "flight_time_s": _r(sim.flight_time_s, 1),
        "flight_time_qgc_s": _r(sim.flight_time_qgc_s, 1),
        "max_altitude_m": _r(max_alt, 2),
        "area_m2": _r(sum(a.area.area_m2 for a in compiled.areas), 1),
        "gsd_cm": gsd,
        "coverage": coverage,
        "overlap": overlap,
        "areas": area_rows,
        "warnings": warnings,
        "errors": errors,
    }


def _over_zones_text(a: Any, row: dict) -> str:
    """The path_over_exclusion message: how much, and on what — camera-on legs or the flight between them."""
    total, cam = row["over_gaps_m"], row.get("over_gaps_camera_m") or 0.0
    shots = ", ".join(f"{n} {k}" for n, k in (row.get("photos_in_zones") or {}).items() if k)
    parts = []
    if cam > 0.05:
        parts.append(f"{cam:.1f} m on camera-on legs" + (f" (photos centred inside: {shots})" if shots else ""))
    if total - cam > 0.05:
        parts.append(f"{total - cam:.1f} m with the camera off: turnarounds, connections, transits, take-off or "
                     "return")
    return (f"step {a.step} ({a.kind}): the flown path runs {total:.0f} m inside the area's holes or exclusion "
            f"zones — {'; '.join(parts)}. Check that overflight is allowed")


def _optics_warnings(compiled: Compiled) -> list[dict]:
    out = []
    try:
        from cdf.catalogue import catalogue
        cat = catalogue()
    except Exception:  # the catalogue is checked by its own tests; a report still comes out without it
        return out
    for p in compiled.payloads:
        try:
            imager = cat.get(p.camera_id).imager(p.imager)
        except Exception:
            continue
        if imager is not None and imager.assumed:
            out.append({"code": "assumed_optics",
                        "message": f"{p.name}: {', '.join(imager.assumed)} of {p.camera_id}/{p.imager} are assumed, "
                                   "not from a published source — footprints, GSD and overlap depend on them; "
                                   "check them against your camera's datasheet"})
    return out


# --------------------------------------------------------------------------------------------- text forms

def summary_lines(rep: dict) -> list[str]:
    """A few lines for `wiris mission compile`."""
    mins, secs = divmod(int(round(rep["flight_time_s"] or 0)), 60)
    lines = [f"{rep['name']}: {rep['firmware']} {rep['frame']}, {rep['mission_items']} items "
             f"(limit {rep['item_limit']}, {rep['parts']} part{'s' if rep['parts'] != 1 else ''}), "
             f"{rep['path_length_m'] / 1000:.2f} km, ~{mins} min {secs:02d} s"]
    for name, n in rep["photos"].items():
        extra = ""
        if name in rep["coverage"]:
            ov = rep["overlap"][name]
            f = "–" if ov["front_min"] is None else f"{100 * ov['front_min']:.1f} %"
            s = "–" if ov["side_min"] is None else f"{100 * ov['side_min']:.1f} %"
            extra = f", coverage {100 * rep['coverage'][name]:.2f} %, min overlap front {f} side {s}"
        lines.append(f"  {name}: {n} photos{extra}")
    for w in rep["warnings"]:
        lines.append(f"warning [{w['code']}]: {w['message']}")
    for e in rep["errors"]:
        lines.append(f"error [{e['code']}]: {e['message']}")
    return lines


def format_report(rep: dict) -> str:
    """The human-readable report of `wiris mission check`."""
    rows = [("plan", rep["plan"]), ("firmware", f"{rep['firmware']} {rep['frame']}"),
            ("mission items", f"{rep['mission_items']} (limit {rep['item_limit']}; "
                              + ("fits in one upload)" if rep["parts"] == 1 else
                                 f"{rep['parts']} parts of {', '.join(str(n) for n in rep['part_items'])} items)")),
            ("path length", f"{rep['path_length_m']:.0f} m (climb {rep['climb_m']:.0f} m)"),
            ("flight time", f"{rep['flight_time_s'] / 60:.1f} min (QGC's estimate: {rep['flight_time_qgc_s'] / 60:.1f} min)"),
            ("highest point", f"{rep['max_altitude_m']:.1f} m above home"),
            ("area", f"{rep['area_m2']:.0f} m² ({rep['area_m2'] / 10000:.2f} ha)" if rep["area_m2"] else
                     "none (no survey or corridor)")]
    for name, n in rep["photos"].items():
        g = rep["gsd_cm"].get(name)
        gs = "" if not g else (f", GSD {g[0]:.2f} cm/px" if abs(g[1] - g[0]) < 0.005 else f", GSD {g[0]:.2f}–{g[1]:.2f} cm/px")
        rows.append((f"photos {name}", f"{n}{gs}"))
    for name, c in rep["coverage"].items():
        ov = rep["overlap"][name]
        f = "–" if ov["front_min"] is None else f"{100 * ov['front_min']:.1f} %"
        s = "–" if ov["side_min"] is None else f"{100 * ov['side_min']:.1f} %"
        rows.append((f"coverage {name}", f"{100 * c:.2f} % (minimum overlap: front {f}, side {s})"))
    for a in rep.get("areas", []):
        rows.append((f"step {a['step']} {a['kind']}", f"{a['area_m2']:.0f} m² at {a['altitude_m']:g} m, "
                                                      f"{a.get('outside_m', 0):.0f} m flown outside the area"))
    width = max(len(k) for k, _ in rows)
    out = [f"{k.ljust(width)}  {v}" for k, v in rows]
    for w in rep["warnings"]:
        out.append(f"warning [{w['code']}]: {w['message']}")
    for e in rep["errors"]:
        out.append(f"error [{e['code']}]: {e['message']}")
    if not rep["warnings"] and not rep["errors"]:
        out.append("no warnings")
    return "\n".join(out)


def error_report(plan_path: str, err: Exception) -> dict:
    """`check --json` for a plan that does not compile: the binding keys, nothing measured, the errors located."""
    problems = getattr(err, "problems", None) or [err]
    errors = [{"code": "plan", "message": getattr(p, "message", str(p)), "where": getattr(p, "where", None),
               "hint": getattr(p, "hint", None)} for p in problems]
    return {"plan": plan_path, "firmware": None, "mission_items": 0, "item_limit": None, "parts": 0, "photos": {},
            "path_length_m": None, "flight_time_s": None, "area_m2": None, "gsd_cm": {}, "coverage": {},
            "overlap": {}, "warnings": [], "errors": errors}
