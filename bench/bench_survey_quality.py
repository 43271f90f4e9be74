"""Survey quality benchmark: missions.geometry.survey against a QGroundControl-style baseline, side by side.

    .venv/bin/python bench/bench_survey_quality.py [--md | --compact]

Footprint: WIRIS Pro 640×512, 17 µm pixels, 13 mm lens at 60 m (GSD 7.85 cm, 50.2 m × 40.2 m),
front/side overlap 80/70 %, turnaround 10 m, 6 m/s. Areas: bench/areas.py (22 areas, deterministic).

Planners:
  qgc@0     QGroundControl's Survey as survey-planners-and-mission-protocol.md §1.3/§1.6 describes it:
            angle 0 (the default); lines laid from the bounding-rectangle centre − (max(w, h) + 2000)/2 at
            the spacing (arbitrary offset from the edge); each line keeps only the farthest two crossings
            with the polygon (one segment, across any concavity); < 2 lines → one line through the centre;
            holes cannot be expressed (the outer ring is surveyed); one survey per polygon of a
            multipolygon; lawn-mower order; 10 m turnaround stubs; DO_SET_CAM_TRIGG_DIST with param3 = 1
            at entry and exit (images in turnarounds off), photos from distance triggering.
  ours@0    missions.geometry.survey.plan_survey at the same fixed angle 0 (isolates the algorithm).
  ours@auto missions.geometry.survey.plan_survey with the optimised angle.
Both are measured by the same functions (missions.measure.coverage.measure) on photos re-derived with
missions.geometry.triggers.simulate_distance_trigger from each planner's own path.

Columns: cov = area covered by ≥ 1 footprint (%), side/front = minimum achieved overlap (%),
path/LB = path length ÷ (area / spacing), time = path/speed + 2·v/a per leg end (a = 2 m/s², the
angle search's objective), photos/LB = photos ÷ (area / (spacing · trigger distance)),
out = metres of path outside the area (turnarounds included), cam-out = metres of camera-on legs outside
the area (flying and shooting over what is not to be surveyed).
Targets: cov ≥ 99.5 %, side ≥ 69 %, front ≥ 79 % (requested − 1 point), path/LB ≤ 1.10 on convex areas.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from areas import bench_areas, built_area  # noqa: E402
from missions.measure.coverage import measure  # noqa: E402
from missions.geometry.footprint import Footprint, transect_spacing_m, trigger_distance_m  # noqa: E402
from missions.geometry.objectives import estimated_time_s  # noqa: E402
from missions.geometry.survey import plan_survey  # noqa: E402
from missions.geometry.swaths import frame  # noqa: E402
from missions.geometry.triggers import TriggerSpan, simulate_distance_trigger  # noqa: E402

GSD_M = 60.0 * 17e-6 / 13e-3
FP = Footprint(640 * GSD_M, 512 * GSD_M)
FRONT, SIDE = 80.0, 70.0
TURNAROUND_M = 10.0
SPEED_MPS = 6.0


# ----------------------------------------------------------------------------------- QGC-style baseline

def _far_crossings(poly, c, d, off_n, n, half):
    """QGC: intersect the line with every polygon edge, keep the two farthest intersection points."""
    from shapely.geometry import LineString
    p0 = c + off_n * n - half * d
    p1 = c + off_n * n + half * d
    line = LineString([p0, p1])
    hit = line.intersection(poly.exterior)
    pts = []
    for g in getattr(hit, "geoms", [hit]):
        if g.is_empty:
            continue
        pts.extend(g.coords)
    if len(pts) < 2:
        return None
    ts = sorted(float((np.asarray(p) - c) @ d) for p in pts)
    if ts[-1] - ts[0] < 1e-9:
        return None
    a = c + off_n * n + ts[0] * d
    b = c + off_n * n + ts[-1] * d
    return a, b


def qgc_transects(poly, angle_deg: float, spacing: float) -> list[tuple[np.ndarray, np.ndarray]]:
    from shapely.geometry import Polygon
    outer = Polygon(poly.exterior)               # QGC's survey polygon has no holes
    x0, y0, x1, y1 = outer.bounds
    c = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    half = (max(x1 - x0, y1 - y0) + 2000.0) / 2.0
    d, n = frame(angle_deg)
    out = []
    k = 0
    while -half + k * spacing <= half:
        seg = _far_crossings(outer, c, d, -half + k * spacing, n, half)
        if seg is not None:
            out.append(seg)
        k += 1
    if len(out) < 2:                              # QGC PR #5301: a single line through the centre
        seg = _far_crossings(outer, c, d, 0.0, n, half)
        out = [seg] if seg is not None else []
    return out


def qgc_plan(geom, angle_deg: float, spacing: float, trig: float, turnaround: float):
    parts = list(geom.geoms) if geom.geom_type == "MultiPolygon" else [geom]
    path: list[np.ndarray] = []
    spans: list[TriggerSpan] = []
    for part in parts:                                   # one QGC survey per polygon
        tr = qgc_transects(part, angle_deg, spacing)
        for i, (a, b) in enumerate(tr):
            if i % 2 == 1:                               # lawn-mower
                a, b = b, a
            u = (b - a) / np.hypot(*(b - a))
            if turnaround > 0:
                path.append(a - u * turnaround)
            s = len(path)
            path.append(a)
            path.append(b)
            spans.append(TriggerSpan(s, s + 1, trig, shoot_at_start=True, shoot_at_stop=True))
            if turnaround > 0:
                path.append(b + u * turnaround)
    xy = np.array(path).reshape(-1, 2)
    return xy, spans, simulate_distance_trigger(xy, spans)


# ----------------------------------------------------------------------------------- measurement

def camera_on_outside_m(xy: np.ndarray, spans, geom) -> float:
    from shapely.geometry import LineString
    total = 0.0
    for s in spans:
        seg = xy[s.start_index:s.stop_index + 1]
        if len(seg) > 1 and np.hypot(*(seg[-1] - seg[0])) > 1e-9:
            total += LineString(seg).difference(geom).length
    return total


def row(name, kind, planner, geom, xy, spans, photos, spacing, trig, legs, secs):
    c = measure(geom, photos, FP, xy, spacing, trig)
    return {
        "area": name, "kind": kind, "planner": planner,
        "cov": 100 * c.coverage,
        "side": None if c.min_side_overlap is None else 100 * c.min_side_overlap,
        "front": None if c.min_front_overlap is None else 100 * c.min_front_overlap,
        "path_lb": c.path_ratio, "photos_lb": c.photo_ratio, "photos": c.photo_count,
        "out": c.outside_m, "cam_out": camera_on_outside_m(xy, spans, geom), "legs": legs, "secs": secs,
        # the angle search's objective, applied to every planner alike: cruise + brake/accelerate per turn
        "time_min": estimated_time_s(c.path_length_m, 2 * legs, SPEED_MPS) / 60.0,
    }


def fmt(v, spec):
    return "—" if v is None else format(v, spec)


def main(argv: list[str]) -> int:
    md = "--md" in argv
    spacing = transect_spacing_m(FP, SIDE)
    trig = trigger_distance_m(FP, FRONT)
    print(f"footprint {FP.across_m:.1f} × {FP.along_m:.1f} m, spacing {spacing:.2f} m, trigger {trig:.2f} m, "
          f"overlap {FRONT:.0f}/{SIDE:.0f} %, turnaround {TURNAROUND_M:.0f} m")
    rows = []
    for a in bench_areas():
        area = built_area(a)
        geom = area.geometry
        t = time.perf_counter()
        xy, spans, photos = qgc_plan(geom, 0.0, spacing, trig, TURNAROUND_M)
        rows.append(row(a.name, a.kind, "qgc@0", geom, xy, spans, photos, spacing, trig, len(spans),
                        time.perf_counter() - t))
        for label, ang in (("ours@0", 0.0), ("ours@auto", "auto")):
            t = time.perf_counter()
            p = plan_survey(area, FP, FRONT, SIDE, angle_deg=ang, turnaround_m=TURNAROUND_M, speed_mps=SPEED_MPS)
            secs = time.perf_counter() - t
            rows.append(row(a.name, a.kind, label, geom, p.path_xy, p.camera_spans, p.photos, spacing, trig,
                            len(p.legs), secs))
    head = ["area", "kind", "planner", "cov %", "side %", "front %", "path/LB", "time min", "photos/LB", "out m",
            "cam-out m", "legs"]
    lines = []
    for r in rows:
        lines.append([r["area"], r["kind"], r["planner"], fmt(r["cov"], ".2f"), fmt(r["side"], ".1f"),
                      fmt(r["front"], ".1f"), fmt(r["path_lb"], ".3f"), fmt(r["time_min"], ".1f"),
                      fmt(r["photos_lb"], ".3f"), fmt(r["out"], ".0f"), fmt(r["cam_out"], ".0f"), str(r["legs"])])
    if "--compact" in argv:
        compact(rows)
    elif md:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for l in lines:
            print("| " + " | ".join(l) + " |")
    else:
        w = [max(len(h), *(len(l[i]) for l in lines)) for i, h in enumerate(head)]
        print("  ".join(h.ljust(w[i]) for i, h in enumerate(head)))
        for l in lines:
            print("  ".join(v.ljust(w[i]) if i < 3 else v.rjust(w[i]) for i, v in enumerate(l)))

    print("\nsummary (targets: cov ≥ 99.5 %, side ≥ 69 %, front ≥ 79 %, path/LB ≤ 1.10 on convex non-tiny areas)")
    n_areas = len(rows) // 3
    for planner in ("qgc@0", "ours@0", "ours@auto"):
        rs = [r for r in rows if r["planner"] == planner]
        cov_ok = sum(r["cov"] >= 99.5 for r in rs)
        side_ok = sum(r["side"] is None or r["side"] >= SIDE - 1 for r in rs)
        front_ok = sum(r["front"] is None or r["front"] >= FRONT - 1 for r in rs)
        convex = [r for r in rs if r["kind"] in ("convex", "large") and
                  next(a for a in bench_areas() if a.name == r["area"]).convex]
        ratios = [r["path_lb"] for r in convex]
        ratio_ok = sum(x <= 1.10 for x in ratios)
        print(f"  {planner:10s} cov ok {cov_ok}/{n_areas} (min {min(r['cov'] for r in rs):.2f} %), "
              f"side ok {side_ok}/{n_areas}, front ok {front_ok}/{n_areas}, "
              f"path/LB ≤ 1.10 on {ratio_ok}/{len(ratios)} convex (mean {np.mean(ratios):.3f}), "
              f"est. time {sum(r['time_min'] for r in rs):.0f} min, "
              f"photos {sum(r['photos'] for r in rs)}, outside {sum(r['out'] for r in rs):.0f} m "
              f"(camera on {sum(r['cam_out'] for r in rs):.0f} m), plan time {sum(r['secs'] for r in rs):.2f} s")
    if "--compact" not in argv:
        low_overlap_section()
    return 0


def compact(rows: list[dict]) -> None:
    """One line per area: QGC-style → ours@auto (coverage, overlaps: see the summary)."""
    by = {(r["area"], r["planner"]): r for r in rows}
    print(f"{'area':20s} {'kind':8s} {'path/LB':>13s} {'time min':>11s} {'photos/LB':>13s} {'out m':>11s} "
          f"{'cam-out m':>11s}  cov/side/front % (qgc | ours)")
    for a in dict.fromkeys(r["area"] for r in rows):
        q, o = by[(a, "qgc@0")], by[(a, "ours@auto")]
        cso = lambda r: f"{r['cov']:.1f}/{fmt(r['side'], '.0f')}/{fmt(r['front'], '.0f')}"  # noqa: E731
        print(f"{a:20s} {q['kind']:8s} {q['path_lb']:6.3f}→{o['path_lb']:6.3f} {q['time_min']:5.1f}→{o['time_min']:5.1f} "
              f"{q['photos_lb']:6.3f}→{o['photos_lb']:6.3f} "
              f"{q['out']:5.0f}→{o['out']:5.0f} {q['cam_out']:5.0f}→{o['cam_out']:5.0f}  {cso(q)} | {cso(o)}")


def low_overlap_section() -> None:
    """Edge coverage when the overlaps leave little slack (QGC #5193): coverage % per planner."""
    from missions.measure.coverage import coverage_fraction
    configs = ((60.0, 20.0), (40.0, 10.0))
    print("\ncoverage % at low overlap (front/side): QGC's arbitrary first-line offset and one segment per "
          "line against ours")
    head = ["area"] + [f"{p} {f:.0f}/{s:.0f}" for f, s in configs for p in ("qgc@0", "ours@0", "ours@auto")]
    print("  ".join(h.rjust(16) if i else h.ljust(20) for i, h in enumerate(head)))
    mins = [100.0] * (3 * len(configs))
    for a in bench_areas():
        area = built_area(a)
        geom = area.geometry
        vals = []
        for front, side in configs:
            spacing = transect_spacing_m(FP, side)
            trig = trigger_distance_m(FP, front)
            _, _, photos = qgc_plan(geom, 0.0, spacing, trig, TURNAROUND_M)
            vals.append(100 * coverage_fraction(geom, photos, FP)[1])
            for ang in (0.0, "auto"):
                p = plan_survey(area, FP, front, side, angle_deg=ang, turnaround_m=TURNAROUND_M, speed_mps=SPEED_MPS)
                vals.append(100 * coverage_fraction(geom, p.photos, FP)[1])
        mins = [min(m, v) for m, v in zip(mins, vals)]
        print(a.name.ljust(20) + "  " + "  ".join(f"{v:16.2f}" for v in vals))
    print("minimum".ljust(20) + "  " + "  ".join(f"{v:16.2f}" for v in mins))


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
