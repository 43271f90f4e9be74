"""Photos the real firmware takes against the report's prediction, per bundled example: each example compiled
for ArduPilot, NAME.params loaded as written into ArduPilot SITL, flown in AUTO with the WIRIS emulator on
SERIAL2 (CAMn_TYPE as NAME.params sets it, or --cam-type), and the emulator's photos compared with the report.

    python bench/sitl_photos.py [--speedup 40] [--cam-type 5|6] [--lines] [EXAMPLE.yaml ...]

Without plans: every bundled example (copters) and bench/plans/*.yaml (a fixed-wing survey, flown by arduplane).

Needs ArduPilot SITL ($WIRIS_SITL_DIR or ../shared/sitl). Prints one row per example and payload; with --lines
also each camera-on stretch (survey line) whose photo count differs, each photo taken counted on the stretch of
its nearest predicted photo.
"""

from __future__ import annotations

import argparse
import collections
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from click.testing import CliRunner  # noqa: E402

from missions.compile import compile_plan  # noqa: E402
from missions.measure.flight import simulate  # noqa: E402
from missions.plan.load import load_plan  # noqa: E402
from wiris_tools.cli import cli  # noqa: E402
from wiris_tools.sitl import find_sitl_dir, missing_sitl_reason  # noqa: E402
from wiris_tools.sitl.flight import fly_compiled  # noqa: E402
from wiris_tools.sitl.photos import check_photos  # noqa: E402


def captured_in_tlog(tlog: Path, component: int) -> dict[int, tuple[float, float, float]]:
    """image_index -> (lat, lon, altitude above home m) of every CAMERA_IMAGE_CAPTURED the camera at `component`
    sent, as the ground station heard it through the autopilot's routing (the tlog keeps them all; the
    emulator's own history keeps the last 1000)."""
    from pymavlink import mavutil

    log = mavutil.mavlink_connection(str(tlog))
    out: dict[int, tuple[float, float, float]] = {}
    try:
        while (m := log.recv_match(type="CAMERA_IMAGE_CAPTURED", blocking=False)) is not None:
            if m.get_srcComponent() == component:
                out[m.image_index] = (m.lat / 1e7, m.lon / 1e7, m.relative_alt / 1e3)
    finally:
        log.close()
    return out


def photos_taken(flight, component: int) -> list[tuple[float, float, float]]:
    """(lat, lon, altitude above home m) of each photo the emulator took, in order: from its history when that
    holds them all, else from the tlog with the history's own entries on top."""
    kept = {p.index: (p.position.lat / 1e7, p.position.lon / 1e7, p.position.relative_alt / 1e3)
            for p in flight.photos}
    if not kept or len(kept) == max(kept) + 1:
        return [kept[i] for i in sorted(kept)]
    every = {**captured_in_tlog(flight.sitl.tlog, component), **kept}
    return [every[i] for i in sorted(every)]


def line_rows(compiled, payload: str, caps: list[tuple[float, float, float]]) -> list[str]:
    """One row per camera-on stretch whose count differs: predicted and taken (the nearest predicted photo's)."""
    import numpy as np

    sim = simulate(compiled)
    pred = [p for p in sim.photos if payload in p.payloads]
    if not pred or not caps:
        return []
    px, py = np.array([p.x for p in pred]), np.array([p.y for p in pred])
    gx, gy = sim.projection.to_xy([c[0] for c in caps], [c[1] for c in caps])
    taken = collections.Counter(pred[int(np.argmin(np.hypot(px - x, py - y)))].span
                                for x, y in zip(np.asarray(gx, float), np.asarray(gy, float)))
    predicted = collections.Counter(p.span for p in pred)
    return [f"    stretch {s:4d}: predicted {predicted[s]:4d} taken {taken[s]:4d}"
            for s in sorted(set(predicted) | set(taken)) if predicted[s] != taken[s]]


def fly_example(sitl_dir: Path, plan: Path, scratch: Path, speedup: float, cam_type: int | None,
                lines: bool = False) -> list[str]:
    out = scratch / plan.stem
    res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "--firmware", "ardupilot", "-o", str(out)])
    if res.exit_code != 0:
        return [f"{plan.stem:22s} compile failed: {res.output.strip()[:80]}"]
    compiled = compile_plan(plan, firmware="ardupilot")
    payload = next(p for p in load_plan(plan).payloads if p.camera.startswith("wiris"))
    name, component = payload.name, payload.component_id
    t0 = time.monotonic()
    vehicle = "copter" if compiled.frame == "copter" else "plane"    # a VTOL's survey lines are flown as a plane's
    # a loaded machine runs SITL at a fraction of the speed-up asked (2.5x of 40 measured with 8 users on 2 cores)
    timeout = 600.0 + simulate(compiled).flight_time_s / 2.0
    with fly_compiled(sitl_dir, out, compiled.name, component=component, cam_type=cam_type, speedup=speedup,
                      home=compiled.home, workdir=scratch / f"{plan.stem}-sitl", vehicle=vehicle,
                      mission_timeout_s=timeout) as flight:
        pass
    caps = photos_taken(flight, component)       # after SITL has stopped: its tlog is complete
    wall = time.monotonic() - t0
    c = check_photos(compiled, name, caps)
    row = (f"{plan.stem:22s} {name:9s} {c.predicted:9d} {c.captured:8d} {c.worst_offset_m:9.2f} {c.median_offset_m:8.2f} "
           f"{c.coverage_predicted * 100:9.2f} {c.coverage_captured * 100:9.2f} {'yes' if c.count_ok else 'NO':>5s} "
           f"{wall:7.1f}")
    return [row, *(line_rows(compiled, name, caps) if lines else [])]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plans", nargs="*", type=Path)
    ap.add_argument("--speedup", type=float, default=40.0)
    ap.add_argument("--cam-type", type=int, choices=(5, 6), default=None)
    ap.add_argument("--lines", action="store_true", help="also the stretches whose photo count differs")
    args = ap.parse_args()
    sitl_dir = find_sitl_dir(near=ROOT)
    if sitl_dir is None:
        print(missing_sitl_reason())
        return 1
    plans = args.plans or sorted((ROOT / "examples").glob("*.yaml")) + sorted((ROOT / "bench" / "plans").glob("*.yaml"))
    print(f"ArduPilot SITL ({sitl_dir}), speed-up {args.speedup:g}, CAMn_TYPE "
          f"{args.cam_type or 'as NAME.params sets it'}")
    print(f"{'example':22s} {'payload':9s} {'predicted':>9s} {'captured':>8s} {'worst m':>9s} {'median m':>8s} "
          f"{'cov pred%':>9s} {'cov got%':>9s} {'count':>5s} {'wall s':>7s}")
    with tempfile.TemporaryDirectory(prefix="wiris-sitl-photos-") as scratch:
        for plan in plans:
            for row in fly_example(sitl_dir, plan, Path(scratch), args.speedup, args.cam_type, args.lines):
                print(row, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
