"""Print the agreement table: the real parsers (MAVSDK 4.1.0 camera plugin over HTTP, MAVProxy's
CameraDefinition) vs `wiris cdf validate` in each profile, for the 23 public CDFs in ../shared/corpus/cdf.

    .venv/bin/python bench/corpus_agreement.py [--workers N]

MAVSDK column: accepts / drops N (loads but silently skips N parameters) / rejects / crash.
Profile columns: valid, or ERR with the rule ids of the errors.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tests")]

import peers  # noqa: E402

CORPUS = REPO.parent / "shared" / "corpus" / "cdf"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=3)
    args = ap.parse_args()
    paths = sorted(CORPUS.rglob("*.xml")) + sorted(CORPUS.rglob("*.xml.xz"))
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="cdf-agreement-") as tmp:
        rows = peers.corpus_agreement(paths, Path(tmp), workers=args.workers)
    print(peers.format_agreement(rows))
    print()
    for r in rows:
        if r.mavsdk.dropped or r.predicted_drops:
            same = "same as predicted" if set(r.mavsdk.dropped) == set(r.predicted_drops) else \
                f"PREDICTED {', '.join(r.predicted_drops)}"
            print(f"{r.file}: MAVSDK dropped {', '.join(r.mavsdk.dropped)} ({same})")
        if not r.mavproxy.accepted:
            print(f"{r.file}: MAVProxy: {r.mavproxy.error}")
    print(f"\n{len(rows)} files in {time.monotonic() - t0:.0f} s")


if __name__ == "__main__":
    main()
