"""Areas of any size flown in sorties: compile and report time per photo, peak memory, from 1 km² to 100 km².

    .venv/bin/python bench/bench_big_areas.py [--sizes 1,25,100]

Each size (km²) is a square north-east of home, flown by a VTOL (90 min battery, 20 % reserve, 12 m/s; blur_px 2
so a WIRIS Pro 13 mm at 60 m stays within its blur budget at that speed) with 65/70 % overlap (a photo every 1.2 s), split into the
sorties its battery and ArduPilot's 700 items allow. Each size runs in a fresh child process (so its peak
resident memory, ru_maxrss, is its own), after a warm-up compile there (imports, catalogue). Printed per size:
photos, sorties, compile seconds (load, plan, emit, the re-flight and the sortie split with every sortie
re-flown), report seconds (the whole flight's coverage and overlaps and the union of the sorties', re-measured
from their own items), µs per photo for both, peak MB, and that the union covers what the single mission does.
Targets (issue 24): compile time per photo at 100 km² within 2x of 1 km², peak memory <= 2 GB at 100 km².
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
import subprocess
import sys
import tempfile

sys.path.insert(0, str(Path(__file__).resolve().parent))

from areas import square_ring  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
HOME = (50.0000, 14.5000)
PLAN = """\
version: 1
name: big-{tag}
vehicle: {{firmware: ardupilot, frame: vtol, speed_mps: 12, endurance_min: 90}}
home: {{lat: {lat}, lon: {lon}, alt_amsl_m: 300}}
payloads:
  thermal: {{camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}}
mission:
  - takeoff: {{alt_m: 60}}
  - survey:
      area: {ring}
      payloads: [thermal]
      altitude_m: 60
      overlap: {{front: 65, side: 70}}
      angle_deg: 0
      blur_px: 2
  - rtl: {{}}
"""

CHILD = r"""
import json, resource, sys, time
sys.path.insert(0, sys.argv[1])
from missions.compile import compile_plan
from missions.measure.report import report
compile_plan(sys.argv[3])                       # warm-up: imports, catalogue (a small plan)
t0 = time.perf_counter()
c = compile_plan(sys.argv[2])
t1 = time.perf_counter()
r = report(c)
t2 = time.perf_counter()
photos = len(c.flight_cache.sim.photos)
print(json.dumps({"photos": photos, "items": len(c.items), "sorties": len(c.sorties),
                  "longest_s": max((s.flight_time_s for s in c.sorties), default=r.flight_time_s),
                  "usable_s": c.endurance.usable_s, "compile_s": t1 - t0, "report_s": t2 - t1,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "coverage": r.coverage["thermal"],
                  "union": r.sorties.coverage["thermal"] if r.sorties else r.coverage["thermal"],
                  "side_min": r.overlap["thermal"].side_min,
                  "union_side_min": (r.sorties.overlap["thermal"] if r.sorties else r.overlap["thermal"]).side_min}))
"""


def square_plan(directory: Path, km2: float) -> Path:
    ring = square_ring(HOME, math.sqrt(km2 * 1e6))
    path = directory / f"sq{km2:g}.yaml"
    path.write_text(PLAN.format(tag=f"{km2:g}", lat=HOME[0], lon=HOME[1], ring=ring), encoding="utf-8")
    return path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1,25,100", help="km², comma-separated (the first is the reference)")
    args = ap.parse_args()
    sizes = [float(s) for s in args.sizes.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        warm = square_plan(d, 0.01)
        for km2 in sizes:
            out = subprocess.run([sys.executable, "-c", CHILD, str(ROOT), str(square_plan(d, km2)), str(warm)],
                                 capture_output=True, text=True)
            if out.returncode:
                print(out.stderr, file=sys.stderr)
                return 1
            rows.append((km2, json.loads(out.stdout.strip().splitlines()[-1])))
    print(f"{'km²':>5} {'photos':>8} {'items':>6} {'sorties':>7} {'longest/usable':>14} {'compile s':>9} "
          f"{'µs/photo':>8} {'report s':>8} {'µs/photo':>8} {'peak MB':>7} {'coverage':>8} {'union':>8} "
          f"{'side min':>8} {'union side':>10}")
    for km2, r in rows:
        print(f"{km2:>5g} {r['photos']:>8} {r['items']:>6} {r['sorties']:>7} "
              f"{r['longest_s'] / r['usable_s']:>14.3f} {r['compile_s']:>9.1f} "
              f"{1e6 * r['compile_s'] / r['photos']:>8.1f} {r['report_s']:>8.1f} {1e6 * r['report_s'] / r['photos']:>8.1f} "
              f"{r['peak_mb']:>7.0f} {r['coverage']:>8.5f} {r['union']:>8.5f} {r['side_min']:>8.4f} "
              f"{r['union_side_min']:>10.4f}")
    ref = rows[0][1]
    per_ref = ref["compile_s"] / ref["photos"]
    for km2, r in rows[1:]:
        print(f"compile time per photo at {km2:g} km² / at {rows[0][0]:g} km²: "
              f"{(r['compile_s'] / r['photos']) / per_ref:.2f}x (target <= 2x); peak {r['peak_mb']:.0f} MB "
              f"(target <= 2048 MB at 100 km²)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
