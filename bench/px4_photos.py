"""Photos PX4 SITL fires against the report's prediction, per bundled example compiled for PX4 (one run).

    WIRIS_PX4_SITL_DIR=../shared/px4-sitl python bench/px4_photos.py [EXAMPLE ...] [--speedup 6]

Each example is compiled with --firmware px4, flown in AUTO.MISSION to landing in PX4 SITL (SIH) with the
WIRIS emulator at the plan's WIRIS component on the payload link, NAME.params given at boot, home where the
plan puts it. Printed per
example: the report's predicted photos of that WIRIS, the shots camera_trigger fired (its ULog topic, with
pyulog), the shots the camera heard (distinct sequence numbers of its IMAGE_START_CAPTURE), the images the WIRIS saved (two commands per camera_trigger shot), the
farthest any shot lies from its predicted position, the report's coverage and the coverage of the shots, the
ULog, and the wall time. Not run by the test command: the examples fly 25 to 47 simulated minutes.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def ulog_triggers(path) -> int | None:
    """Shots camera_trigger fired, from the ULog's camera_trigger topic (pyulog, the audit's reader; None
    without it). The camera may have heard fewer: the payload link (4 kB/s in SITL) drops commands."""
    try:
        from pyulog import ULog
    except ImportError:
        return None
    log = ULog(str(path), ["camera_trigger"])
    seqs = {int(s) for d in log.data_list for s in d.data["seq"]}
    return len(seqs)


def main() -> int:
    from click.testing import CliRunner

    from missions.compile import compile_plan
    from wiris_tools.cli import cli
    from wiris_tools.sitl import find_px4_dir, missing_px4_reason
    from wiris_tools.sitl.photos import check_photos
    from wiris_tools.sitl.px4_flight import fly_compiled_px4, shot_positions as shots

    ap = argparse.ArgumentParser()
    ap.add_argument("examples", nargs="*")
    ap.add_argument("--speedup", type=float, default=6.0)
    args = ap.parse_args()
    px4_dir = find_px4_dir(near=ROOT)
    if px4_dir is None:
        print(missing_px4_reason())
        return 1
    names = args.examples or [p.stem for p in sorted((ROOT / "examples").glob("*.yaml"))]
    print("images: the emulator keeps the last 1000 (wiris_tools.emulate), so past 1000 the image, shot and coverage "
          "columns are of the last 1000 only")
    print(f"{'example':22} {'payload':10} {'predicted':>9} {'ulog':>6} {'heard':>6} {'images':>6} {'shots':>6} "
          f"{'worst m':>7} {'cov pred':>8} {'cov shots':>9} {'wall s':>7}  ulog")
    for name in names:
        plan = ROOT / "examples" / f"{name}.yaml"
        out = Path(tempfile.mkdtemp(prefix=f"px4-{name}-"))
        res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "--firmware", "px4", "-o", str(out)])
        if res.exit_code != 0:
            print(f"{name:22} refused at compile: {res.output.strip().splitlines()[0]}")
            continue
        compiled = compile_plan(plan, firmware="px4")
        wiris = [p for p in compiled.payloads if p.camera_id.startswith("wiris")]
        if not wiris:
            print(f"{name:22} no WIRIS payload to emulate")
            continue
        pay = wiris[0]
        t0 = time.monotonic()
        with fly_compiled_px4(px4_dir, out, name, component=pay.component_id, speedup=args.speedup,
                              home=compiled.home, workdir=out / "px4", timeout=3600) as f:
            images = [(p.position.lat / 1e7, p.position.lon / 1e7, p.position.relative_alt / 1e3) for p in f.photos]
            fired = f.trigger_shots(pay.component_id)
            ulog = f.sitl.ulogs()[-1] if f.sitl.ulogs() else None
        wall = time.monotonic() - t0
        c = check_photos(compiled, pay.name, shots(images))
        in_log = ulog_triggers(ulog) if ulog else None
        print(f"{name:22} {pay.name:10} {c.predicted:9d} {in_log if in_log is not None else '-':>6} {fired:6d} "
              f"{len(images):6d} {c.captured:6d} "
              f"{c.worst_offset_m:7.1f} {100 * c.coverage_predicted:7.1f}% {100 * c.coverage_captured:8.1f}% "
              f"{wall:7.0f}  {ulog}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
