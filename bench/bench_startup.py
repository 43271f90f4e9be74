"""Start-up time of `wiris --help` relative to `python -c "import click"` (the floor: Python plus click).

Both commands run side by side in one process of this script, interleaved (A B A B ...) so that machine
load affects both alike; the medians are compared. Target: at most 1.5x.

    .venv/bin/python bench/bench_startup.py [--reps 30]

If the ratio is above target, `python -X importtime -c "from wiris_tools.cli import cli"` shows what
is imported at start-up; heavy modules belong inside the command functions (tests/test_cli_startup.py).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

TARGET = 1.5


def wiris_command() -> list[str]:
    script = Path(sys.executable).with_name("wiris")
    if script.exists():
        return [str(script), "--help"]
    found = shutil.which("wiris")
    if found:
        return [found, "--help"]
    return [sys.executable, "-c", "import sys; from wiris_tools.cli import main; sys.argv[0]='wiris'; main()", "--help"]


def run(cmd: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True,
                   env=dict(os.environ, PYTHONDONTWRITEBYTECODE="0"))
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=30)
    args = parser.parse_args()
    commands = {
        'python -c "import click"': [sys.executable, "-c", "import click"],
        "wiris --help": wiris_command(),
    }
    for cmd in commands.values():   # warm the page cache and the bytecode caches
        run(cmd)
    times: dict[str, list[float]] = {k: [] for k in commands}
    for _ in range(args.reps):
        for name, cmd in commands.items():
            times[name].append(run(cmd))
    base = statistics.median(times['python -c "import click"'])
    print(f"{'command':<28} {'median ms':>10} {'min ms':>8} {'max ms':>8} {'ratio':>6}")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:<28} {med * 1000:>10.1f} {min(ts) * 1000:>8.1f} {max(ts) * 1000:>8.1f} {med / base:>6.2f}")
    ratio = statistics.median(times["wiris --help"]) / base
    verdict = "OK" if ratio <= TARGET else "ABOVE TARGET"
    print(f"wiris --help / import click = {ratio:.2f}x (target <= {TARGET}x, {args.reps} interleaved runs): {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
