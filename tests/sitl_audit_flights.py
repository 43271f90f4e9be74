"""SITL flights of compiled plans with faults injected the way they happen in the field (the emulator misses
every n-th capture or stops capturing, the pilot cuts the mission short with RTL), audited from the tlog and
the DataFlash log they leave. Used by tests/sitl/test_sitl_audit.py and bench/sitl_audit.py."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path

from click.testing import CliRunner

from wiris_tools.emulate.wiris import CaptureFaults
from wiris_tools.sitl.flight import fly_compiled


@dataclass(frozen=True)
class Flown:
    name: str
    requests: int              # captures the camera was asked for (each a trigger of the autopilot)
    taken: int                 # images the emulator took
    dropped: tuple[int, ...]   # request numbers (from 1) the emulator missed
    tlog: Path
    bins: tuple[Path, ...]


def compile_to(plan: Path, out: Path) -> None:
    from wiris_tools.cli import cli
    res = CliRunner().invoke(cli, ["mission", "compile", str(plan), "-o", str(out)])
    assert res.exit_code == 0, res.output


def _rtl_after(flight, requests: int, stop: threading.Event) -> None:
    """Switch to RTL once the camera has been asked for `requests` captures (a pilot cutting the mission)."""
    state = flight.emulator.state
    while not stop.is_set():
        with flight.emulator.lock:
            n = state.capture_requests
        if n >= requests:
            flight.sitl.set_mode("RTL")
            return
        time.sleep(0.05)


def fly(sitl_dir, work: Path, plan: Path, faults: CaptureFaults = CaptureFaults(), rtl_after: int | None = None,
        speedup: float = 20.0, sortie: int | None = None) -> Flown:
    """Fly `plan` (with `sortie`: its NAME.sortieN.plan, on a freshly started SITL as after a battery swap)."""
    import shutil
    out = work / "out"
    compile_to(plan, out)
    name = plan.stem if sortie is None else f"{plan.stem}.sortie{sortie}"
    for ext in (".params", ".lua"):      # a sortie flies with the plan's parameters and camera bridge
        if sortie is not None and (out / f"{plan.stem}{ext}").exists():
            shutil.copy(out / f"{plan.stem}{ext}", out / f"{name}{ext}")
    stop = threading.Event()

    def before(flight) -> None:
        with flight.emulator.lock:
            flight.emulator.state.capture_faults = faults
        if rtl_after is not None:
            threading.Thread(target=_rtl_after, args=(flight, rtl_after, stop), daemon=True).start()

    try:
        with fly_compiled(sitl_dir, out, name, cam_type=6, workdir=work / "sitl", speedup=speedup,
                          before_flight=before) as flight:
            with flight.emulator.lock:
                requests = flight.emulator.state.capture_requests
                taken = len(flight.emulator.state.history)
            tlog, bins = flight.sitl.tlog, tuple(flight.sitl.dataflash_logs())
    finally:
        stop.set()
    dropped = tuple(k for k in range(1, requests + 1) if faults.drops(k))
    return Flown(name, requests, taken, dropped, tlog, bins)
