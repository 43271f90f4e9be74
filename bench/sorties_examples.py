"""The sortie table of every bundled example on a given battery, in one run.

    .venv/bin/python bench/sorties_examples.py [--copter 25] [--plane 60] [--vtol 45] [--reserve 20]

Each examples/*.yaml is compiled with vehicle.endurance_min set for its frame (the examples themselves give
none, so they compile as one mission and only warn `longer_than_battery`), and its sorties printed as
`wiris mission check` prints them, with the union's coverage and overlaps re-measured from the sorties' items
against the single mission's.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
import sys

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--copter", type=float, default=25.0)
    ap.add_argument("--plane", type=float, default=60.0)
    ap.add_argument("--vtol", type=float, default=45.0)
    ap.add_argument("--reserve", type=float, default=20.0)
    args = ap.parse_args()
    from missions.compile import compile_plan
    from missions.measure.report import report
    from missions.measure.seams import table_lines
    from missions.plan.load import load_plan

    for path in sorted((ROOT / "examples").glob("*.yaml")):
        plan = load_plan(path)
        minutes = getattr(args, plan.vehicle.frame)
        plan = dataclasses.replace(plan, vehicle=dataclasses.replace(plan.vehicle, endurance_min=minutes,
                                                                     reserve_pct=args.reserve))
        rep = report(compile_plan(plan))
        print(f"{path.name}: {plan.vehicle.frame}, {rep.flight_time_s / 60:.1f} min in all, battery {minutes:g} min "
              f"less {args.reserve:g} % reserve")
        if rep.sorties is None:
            print("  one sortie (fits one battery and the item limit)")
        else:
            print("\n".join("  " + line for line in table_lines(rep.sorties)))
            for n, c in rep.coverage.items():
                o = rep.overlap[n]
                print(f"  single mission, {n}: coverage {100 * c:.2f} %, minimum overlap front "
                      f"{100 * (o.front_min or 0):.1f} %, side {100 * (o.side_min or 0):.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
