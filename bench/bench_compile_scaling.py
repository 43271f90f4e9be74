"""Compile time per 1000 emitted mission items, square survey areas from 1 ha to 10 km², in one run.

    .venv/bin/python bench/bench_compile_scaling.py [--quick] [--report]

Each size is a square area north-east of home, flown by a WIRIS Pro 13 mm at 60 m with 75/70 % overlap
(a realistic thermal mapping set-up), the item limit raised to 65535 so nothing is split. Every size is
compiled REPEAT times after one warm-up compile (imports, the camera catalogue); the best time counts.
Printed: emitted items, the planner's photo count, seconds, ms per 1000 items (and per 1000 photos: the cost
follows the photos, which grow with the area, while items grow with its square root), and how much the per-item
cost grows from a size to any larger one — raw, and with the fixed cost of compiling a plan (a takeoff/waypoint/RTL plan, measured here) taken
off, which is the one that shows whether a stage grows faster than the mission. Target: ≤ 2×.
Peak Python memory (tracemalloc) is measured in a second pass, per size, because tracing slows the code.
`--report` also times `missions.measure.report.report` (simulation + coverage measurement) the same way.
"""

from __future__ import annotations

import argparse
import gc
import math
from pathlib import Path
import sys
import tempfile
import time
import tracemalloc

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from areas import square_ring  # noqa: E402

# 1 ha, 10 ha, 1 km², 10 km² in one mission (item limit 65535); bench_big_areas.py flies 1 to 100 km² in sorties
SIZES_M2 = (1e4, 1e5, 1e6, 1e7)
REPEAT = 3
HOME = (50.0000, 14.5000)

PLAN = """\
version: 1
name: bench-{tag}
vehicle: {{firmware: ardupilot, frame: copter, speed_mps: 7, max_mission_items: 65535}}
home: {{lat: {lat}, lon: {lon}, alt_amsl_m: 300}}
payloads:
  thermal: {{camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}}
mission:
  - takeoff: {{alt_m: 60}}
{body}
  - rtl: {{}}
"""


def square_plan(directory: Path, area_m2: float) -> Path:
    ring = square_ring(HOME, math.sqrt(area_m2))
    body = (f"  - survey:\n      area: {ring}\n      payloads: [thermal]\n      altitude_m: 60\n"
            f"      overlap: {{front: 75, side: 70}}\n      angle_deg: 0\n")
    path = directory / f"sq{int(area_m2)}.yaml"
    path.write_text(PLAN.format(tag=int(area_m2), lat=HOME[0], lon=HOME[1], body=body), encoding="utf-8")
    return path


def trivial_plan(directory: Path) -> Path:
    body = f"  - waypoint: {{lat: {HOME[0] + 0.001}, lon: {HOME[1] + 0.001}, alt_m: 60}}\n"
    path = directory / "trivial.yaml"
    path.write_text(PLAN.format(tag="trivial", lat=HOME[0], lon=HOME[1], body=body), encoding="utf-8")
    return path


def best_time(fn, repeat: int) -> tuple[float, object]:
    best, result = math.inf, None
    for _ in range(repeat):
        gc.collect()
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="stop at 10 km² (for a fast look)")
    ap.add_argument("--report", action="store_true", help="also time the measured report")
    args = ap.parse_args()
    from missions.compile import compile_plan
    from missions.measure.report import report

    sizes = SIZES_M2[:-1] if args.quick else SIZES_M2
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        plans = {a: square_plan(d, a) for a in sizes}
        compile_plan(trivial_plan(d))                            # warm-up: imports, catalogue
        fixed, _ = best_time(lambda: compile_plan(trivial_plan(d)), 5)
        rows = []
        for a in sizes:
            secs, c = best_time(lambda: compile_plan(plans[a]), REPEAT)
            n = len(c.items)
            # the planner's own photo count (what it simulates internally), to show what the cost follows
            photos = sum(len(getattr(g, "photos", ())) for g in c.intent)
            rsecs = None
            if args.report:
                rsecs, _ = best_time(lambda: report(c), 1)
            rows.append((a, n, secs, rsecs, photos))
        mem = []
        for a in sizes:
            gc.collect()
            tracemalloc.start()
            compile_plan(plans[a])
            _cur, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            mem.append(peak)

    def label(a: float) -> str:
        return f"{a / 1e4:g} ha" if a < 1e6 else f"{a / 1e6:g} km²"

    print(f"fixed cost of compiling a plan (takeoff, waypoint, RTL): {fixed * 1000:.1f} ms")
    head = (f"{'area':>9} {'items':>7} {'photos':>8} {'compile s':>10} {'ms/1000 items':>14} {'marginal ms/1000':>17}"
            f" {'ms/1000 photos':>15} {'peak MB':>8}")
    if args.report:
        head += f" {'report s':>9}"
    print(head)
    per, marginal = [], []
    for (a, n, secs, rsecs, photos), peak in zip(rows, mem):
        p = 1000 * secs / n * 1000
        m = 1000 * max(secs - fixed, 0.0) / n * 1000
        per.append(p)
        marginal.append(m)
        pp = 1000 * max(secs - fixed, 0.0) / photos * 1000 if photos else float("nan")
        line = f"{label(a):>9} {n:>7} {photos:>8} {secs:>10.3f} {p:>14.1f} {m:>17.1f} {pp:>15.2f} {peak / 2**20:>8.1f}"
        if args.report:
            line += f" {rsecs:>9.2f}"
        print(line)
    def growth(costs: list[float]) -> float:
        """The most the per-item cost grows from any size to any larger one (1.0 = never grows)."""
        return max(costs[j] / costs[i] for i in range(len(costs)) for j in range(i, len(costs)))

    print(f"per-item cost growth across sizes (max over smaller -> larger pairs): raw {growth(per):.2f}x, "
          f"marginal {growth(marginal):.2f}x; largest area vs smallest: raw {per[-1] / per[0]:.2f}x, "
          f"marginal {marginal[-1] / marginal[0]:.2f}x")
    print("target: growth <= 2x (a cost that falls with size is within target: the fixed cost spreads)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
