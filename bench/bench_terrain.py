"""Terrain benchmark: the same survey planned for flat ground and over the DEM, both measured over the DEM.

    .venv/bin/python bench/bench_terrain.py

Ground: synthetic DEM GeoTIFFs (tests/terrain_dems.py, 5 m pixels, UTM 33N): a 30 % slope rising east (across
the north-south lines), the same rising north (along them), and a hill 80 m high (Gaussian, sigma 150 m). Survey: a 300 m x 300 m square over it, WIRIS Pro 13 mm at 60 m, 80/70 %
overlap, north-south lines, 5 m/s, copter (climb 2.5 m/s, descent 1.5 m/s), take-off 60 m, home 250 m south.
flat:    the plan without `terrain:` (home's elevation from the DEM), its photos re-flown over the DEM;
terrain: the plan with `terrain: {dem: ...}` (frame amsl, tolerance 10 % = 6 m, clearance 20 m).
Both are measured by the report's own re-flight over the DEM (missions.terrain.reflight): coverage, minimum
front and side overlap, GSD range, heights above ground of the photos (and how many fall outside
[60, 66] m), minimum clearance of the whole path, flight time (missions.measure.flight).
Targets (issue 28): coverage >= 99.5 %, overlaps within 2 points of 80/70, every photo within the tolerance.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import terrain_dems as T  # noqa: E402
from missions.compile import compile_plan  # noqa: E402
from missions.measure.report import report  # noqa: E402


def _row(name: str, compiled, terrain) -> list[str]:
    measured = compiled if compiled.terrain is not None else dataclasses.replace(compiled, terrain=terrain)
    rep = report(measured)
    g, t = rep.gsd_cm["thermal"], rep.terrain
    s = t.steps[0]
    ov = rep.overlap["thermal"]
    pct = lambda v: "–" if v is None else f"{100 * v:.1f}"   # noqa: E731
    return [name, f"{100 * rep.coverage['thermal']:.2f}", pct(ov.front_min), pct(ov.side_min),
            f"{g.min_cm:.2f}–{g.max_cm:.2f} ({100 * (g.max_cm / g.min_cm - 1):.0f} %)",
            f"{s.hag_min_m:.1f}–{s.hag_max_m:.1f}", str(s.outside_tolerance), f"{t.clearance.min_m:.1f}",
            f"{rep.flight_time_s / 60:.1f}", str(rep.mission_items), str(rep.photos["thermal"])]


def main() -> None:
    header = ["ground / plan", "cov %", "front %", "side %", "GSD cm/px (spread)", "AGL m", "off-tol",
              "clear m", "time min", "items", "photos"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for label, shape in (("slope 30 % across lines", T.slope(30)), ("slope 30 % along lines", T.slope(30, 0.0)),
                             ("hill 80 m", T.hill(80, 150))):
            T.write_dem(d / "dem.tif", shape, half_m=900.0)
            terrain_plan = d / "terrain.yaml"
            terrain_plan.write_text(T.plan_text("dem.tif", T.square(150)))
            followed = compile_plan(terrain_plan)
            flat_plan = d / "flat.yaml"
            flat_plan.write_text(T.plan_text(None, T.square(150), home_alt=followed.home[2]))
            flat = compile_plan(flat_plan)
            rows.append(_row(f"{label}: flat", flat, followed.terrain))
            rows.append(_row(f"{label}: terrain", followed, followed.terrain))
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
