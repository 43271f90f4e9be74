#!/usr/bin/env python3
"""MAVSDK's import_qgroundcontrol_mission on the compiled .plan files, measured in one run: each example plan
compiled for ArduPilot and PX4 (a plan one firmware cannot fly is listed as refused), its ComplexItems counted,
and MAVSDK 4.1's importer compared item by item with the compiled mission and fence.

    PYTHONPATH=. python bench/mavsdk_plan_import.py [--corridor-scan]

--corridor-scan compiles corridors as QGC CorridorScan items too (`qgc: {corridor_scan: true}`), which MAVSDK
refuses. Prints one table row per plan and firmware.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import mission_peers  # noqa: E402
from missions.compile import compile_plan  # noqa: E402
from missions.errors import PlanError  # noqa: E402
from missions.formats.planfile import write_plan  # noqa: E402


def _same(a, b) -> bool:
    def eq(x: float, y: float) -> bool:
        return (math.isnan(x) and math.isnan(y)) or abs(x - y) <= 1e-6 * max(1.0, abs(y))

    return (a.command, a.frame, a.x, a.y, a.autocontinue) == (b.command, b.frame, b.x, b.y, b.autocontinue) and all(
        eq(x, y) for x, y in zip((a.param1, a.param2, a.param3, a.param4, a.z),
                                 (b.param1, b.param2, b.param3, b.param4, b.z)))


def check(path: Path, firmware: str, corridor_scan: bool, scratch: Path) -> str:
    try:
        c = compile_plan(path, firmware=firmware)
    except PlanError as err:
        return f"| {path.stem} | {firmware} | refused by the compiler: {err.message[:60]} | | | |"
    if corridor_scan:
        c = dataclasses.replace(c, corridor_scan=True)
    target = scratch / f"{c.name}-{firmware}.plan"
    write_plan(target, c)
    doc = json.loads(target.read_text())
    kinds = [it["complexItemType"] for it in doc["mission"]["items"] if it["type"] == "ComplexItem"]
    res = mission_peers.mavsdk_import_plan(target.read_text(), scratch, autopilot=firmware)
    if not res["ok"]:
        return f"| {path.stem} | {firmware} | {', '.join(kinds) or '-'} | {len(c.items)} | refused: {res['error']} | |"
    got = res["mission"]
    home_row = firmware == "ardupilot" and len(got) == len(c.items) + 1
    got = got[1:] if home_row else got
    exact = len(got) == len(c.items) and all(_same(g, w) for g, w in zip(got, c.items))
    fence = len(res["fence"]) == len(c.fence)
    return (f"| {path.stem} | {firmware} | {', '.join(kinds) or '-'} | {len(c.items)} | "
            f"{'exact' if exact else 'DIFFERS'}{' (+ home row 0)' if home_row else ''} | "
            f"{len(res['fence'])} of {len(c.fence)}{'' if fence else ' DIFFERS'} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--corridor-scan", action="store_true")
    a = ap.parse_args()
    print("| plan | firmware | ComplexItems | compiled items | MAVSDK mission import | fence items |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for path in sorted((ROOT / "examples").glob("*.yaml")):
            for firmware in ("ardupilot", "px4"):
                print(check(path, firmware, a.corridor_scan, Path(tmp)), flush=True)


if __name__ == "__main__":
    main()
