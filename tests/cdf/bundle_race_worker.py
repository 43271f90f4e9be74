"""One side of test_bundle's concurrent-build test: `python bundle_race_worker.py WHO TABLES WORK ROUNDS`.

Round k: say ready (WORK/ready-k-WHO), wait for the barrier (WORK/go-k), build wiris-pro into WORK/out-k from
the catalogue in TABLES, and leave the outcome in WORK/result-k-WHO ("ok" or "error: MESSAGE")."""

from __future__ import annotations

import sys
import time
from pathlib import Path


def wait_for(path: Path) -> None:
    for _ in range(600_000):          # bounded by count; the parent's own time-out ends a stuck run first
        if path.exists():
            return
        time.sleep(0.0001)
    raise SystemExit(f"no {path}")


def main(who: str, tables: str, work: str, rounds: int) -> None:
    from cdf.bundle import build_bundle
    from cdf.catalogue import load_catalogue
    from cdf.errors import CdfError

    cat = load_catalogue(Path(tables))
    work_dir = Path(work)
    for k in range(rounds):
        (work_dir / f"ready-{k}-{who}").touch()
        wait_for(work_dir / f"go-{k}")
        try:
            build_bundle(work_dir / f"out-{k}", ["wiris-pro"], cat=cat)
            outcome = "ok"
        except CdfError as err:
            outcome = f"error: {err}"
        result = work_dir / f"result-{k}-{who}"
        result.with_suffix(".tmp").write_text(outcome, encoding="utf-8")
        result.with_suffix(".tmp").rename(result)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]))
