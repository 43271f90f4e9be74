"""Compile time against the number of polygon parts of a survey area, in one run.

    .venv/bin/python bench/bench_survey_scaling.py [--parts 10,100,300,1000,3000] [--angle auto|0] [--profile N]

The area is a GeoJSON MultiPolygon of small separated triangles on a grid near Prague (what a parcel export,
a tree-crown or solar-table digitisation gives): `triangle_grid` draws them deterministically, 20 to 60 m across
(the smaller ones fit in one photo, the larger take two or three lines), 80 m apart, each turned from its
neighbour so the parts do not all share one edge direction. The
plan flies a WIRIS Pro 13 mm at 60 m with 75/70 % overlap and angle_deg auto, so the angle search, the leg
order and the route all see every part.

Printed per part count: the compile's wall-clock and CPU seconds, CPU milliseconds per part, and that per-part
cost as a ratio to the smallest count's (measured in the same run; 1.0 = linear; it may fall below 1 as the fixed
cost spreads). CPU time is the one to compare on a shared machine: other processes stretch the wall clock.
`--profile N` prints the cProfile top 25 of one compile of N parts instead.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
from pathlib import Path
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from areas import metres_per_degree  # noqa: E402

PARTS = (10, 100, 300, 1000, 3000)
SITE = (50.08, 14.42)          # Prague
PITCH_M = 80.0

PLAN = """\
version: 1
name: bench-parts-{n}
vehicle: {{firmware: ardupilot, frame: copter, speed_mps: 6, max_mission_items: 65535}}
home: {{lat: {lat}, lon: {lon}, alt_amsl_m: 300}}
payloads:
  thermal: {{camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}}
mission:
  - takeoff: {{alt_m: 60}}
  - survey:
      area: {area}
      payloads: [thermal]
      altitude_m: 60
      overlap: {{front: 75, side: 70}}
      angle_deg: {angle}
  - rtl: {{}}
"""


def triangle_grid(n: int, pitch_m: float = PITCH_M) -> dict:
    """A GeoJSON MultiPolygon of n separated triangles on a square grid (lon/lat, RFC 7946)."""
    cols = max(1, math.ceil(math.sqrt(n)))
    m_lat, m_lon = metres_per_degree(SITE[0])
    polys = []
    for k in range(n):
        r, c = divmod(k, cols)
        cx, cy = c * pitch_m, r * pitch_m
        turn = math.radians((k * 37) % 120)          # deterministic variety of edge directions and sizes
        size_m = 20.0 + (k * 7) % 41
        ring = []
        for j in range(3):
            a = turn + j * 2.0 * math.pi / 3.0
            x, y = cx + size_m / 2.0 * math.sin(a), cy + size_m / 2.0 * math.cos(a)
            ring.append([round(SITE[1] + x / m_lon, 8), round(SITE[0] + y / m_lat, 8)])
        ring.append(ring[0])
        polys.append([ring])
    return {"type": "Feature", "properties": {"name": f"{n} triangles"},
            "geometry": {"type": "MultiPolygon", "coordinates": polys}}


def write_plan(directory: Path, n: int, angle: str = "auto") -> Path:
    area = directory / f"triangles-{n}.geojson"
    area.write_text(json.dumps(triangle_grid(n)), encoding="utf-8")
    path = directory / f"parts-{n}.yaml"
    path.write_text(PLAN.format(n=n, lat=SITE[0] - 0.001, lon=SITE[1] - 0.001, area=area.name, angle=angle),
                    encoding="utf-8")
    return path


def timed(fn) -> tuple[float, float, object]:
    """(wall s, CPU s, result)"""
    gc.collect()
    t0, c0 = time.perf_counter(), time.process_time()
    result = fn()
    return time.perf_counter() - t0, time.process_time() - c0, result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default=",".join(map(str, PARTS)), help="comma-separated part counts")
    ap.add_argument("--angle", default="auto", help="the survey's angle_deg (auto or degrees)")
    ap.add_argument("--profile", type=int, metavar="N", help="profile one compile of N parts")
    args = ap.parse_args()
    from missions.compile import compile_plan

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        compile_plan(write_plan(d, 3, args.angle))            # warm-up: imports, catalogue
        if args.profile:
            import cProfile
            import pstats
            plan = write_plan(d, args.profile, args.angle)
            prof = cProfile.Profile()
            prof.runcall(compile_plan, plan)
            pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
            return 0
        counts = [int(s) for s in args.parts.split(",") if s.strip()]
        print(f"{'parts':>6} {'items':>7} {'wall s':>8} {'CPU s':>8} {'CPU ms/part':>12} {'ratio':>7}")
        base = None
        for n in counts:
            plan = write_plan(d, n, args.angle)
            wall, cpu, c = timed(lambda: compile_plan(plan))
            per = 1000.0 * cpu / n
            base = base if base is not None else per
            print(f"{n:>6} {len(c.items):>7} {wall:>8.2f} {cpu:>8.2f} {per:>12.2f} {per / base:>7.2f}", flush=True)
    print(f"ratio: CPU ms per part against the {counts[0]}-part area's in this run (1.0 = linear)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
