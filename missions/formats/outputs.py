"""Write a compiled mission's files, all or nothing.

    paths = write_outputs(compiled, "build/missions")

Files, named after the plan (NAME = compiled.name):
  NAME.plan            QGroundControl plan (missions.formats.planfile) — the whole mission
  NAME.waypoints       QGC WPL 110 (missions.formats.wpl): Mission Planner, MAVProxy `wp load`, pymavlink
  NAME.geojson         area, holes/exclusions, flown path, waypoints, photo points, footprints (geojson_out)
  NAME.kml             the same features as KML (kml_out)
  NAME.setup.json      the pre-flight command sequence (`wiris camera apply`)
  NAME.lua             the ArduPilot Lua bridge, only when the mission needs it (copy to the SD card's APM/scripts)
  NAME.params          autopilot parameters the mission relies on, with the reason for each
  NAME.report.json     the measured report, identical to `wiris mission check --json`
  NAME.partK.plan, NAME.partK.waypoints  (K = 1..N) only when the mission exceeds the vehicle's item limit:
                       each part is a complete mission to upload and fly in turn; NAME.plan still holds the
                       whole mission for review.

All or nothing: every file is first written into a fresh temporary directory next to DIR (same file system,
so the final step is a rename), then moved in one by one with os.replace; a file already in DIR is set aside
first and put back if any later step fails. When the report or any writer raises, DIR is left exactly as it
was. Part files of an earlier compile of the same NAME that this compile does not produce are removed (after
success only), so a stale `NAME.part3.plan` cannot be flown by mistake.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
import re
import shutil
import tempfile
from typing import Callable

from missions.compiled import Compiled
from missions.errors import PlanError


def _json_text(obj) -> str:
    from missions.formats.jsonfinite import finite
    return json.dumps(finite(obj), indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def setup_document(compiled: Compiled) -> dict:
    """NAME.setup.json: the ordered pre-flight steps in missions.emit.setup's format (what `wiris camera apply` reads)."""
    from missions.emit.setup import setup_json
    return setup_json(compiled.name, compiled.setup)


def _params_text(compiled: Compiled) -> str:
    try:
        from missions.emit.params import format_params
    except ImportError:   # the compiler core's formatter; the fallback is Mission Planner's "NAME,VALUE" form
        lines = [f"# {compiled.name}: autopilot parameters this mission relies on ({compiled.firmware})"]
        for name, value, why in compiled.params:
            lines.append(f"# {why}")
            lines.append(f"{name},{value:g}")
        return "\n".join(lines) + "\n"
    return format_params(compiled)


def _writers(compiled: Compiled, rep: dict, sim) -> list[tuple[str, Callable[[Path], None]]]:
    from missions.formats import planfile, wpl
    from missions.formats.geojson import dumps_collection, feature_collection
    from missions.formats.kml import render_kml

    name = compiled.name
    fc = feature_collection(compiled, sim, rep)
    out: list[tuple[str, Callable[[Path], None]]] = [
        (f"{name}.plan", lambda p: planfile.write_plan(p, compiled)),
        (f"{name}.waypoints", lambda p: wpl.write_wpl(p, compiled.items, home=compiled.home,
                                                      firmware=compiled.firmware)),
        (f"{name}.geojson", lambda p: p.write_text(dumps_collection(fc), encoding="utf-8")),
        (f"{name}.kml", lambda p: p.write_text(render_kml(fc), encoding="utf-8")),
        (f"{name}.setup.json", lambda p: p.write_text(_json_text(setup_document(compiled)), encoding="utf-8")),
        (f"{name}.params", lambda p: p.write_text(_params_text(compiled), encoding="utf-8")),
        (f"{name}.report.json", lambda p: p.write_text(_json_text(rep), encoding="utf-8")),
    ]
    if compiled.lua:
        out.append((f"{name}.lua", lambda p: p.write_text(compiled.lua, encoding="utf-8")))
    if len(compiled.parts) > 1:
        for k, part in enumerate(compiled.parts, start=1):
            out.append((f"{name}.part{k}.plan", lambda p, part=part: planfile.write_plan(p, compiled, items=part)))
            out.append((f"{name}.part{k}.waypoints",
                        lambda p, part=part: wpl.write_wpl(p, part, home=compiled.home, firmware=compiled.firmware)))
    return out


def _stale_parts(out_dir: Path, name: str, keep: set[str]) -> list[Path]:
    pat = re.compile(re.escape(name) + r"\.part\d+\.(plan|waypoints)$")
    if not out_dir.is_dir():
        return []
    return [p for p in out_dir.iterdir() if pat.match(p.name) and p.name not in keep]


def write_outputs(compiled: Compiled, out_dir: str | Path, rep: dict | None = None, sim=None) -> list[Path]:
    """Write every output file of `compiled` into `out_dir`; return their paths (in the order above)."""
    from missions.formats.planfile import new_file_mode
    from missions.measure.flight import simulate
    from missions.measure.report import report

    out_dir = Path(out_dir)
    try:
        if out_dir.exists() and not out_dir.is_dir():
            raise PlanError("the output path exists and is not a directory", where=str(out_dir),
                            hint="give a directory for -o")
    except OSError as e:  # exists() answers only "no such file"; a name too long raises
        raise PlanError(f"cannot use the output directory: {e.strerror}", where=str(out_dir),
                        hint="give -o a path you may access, each name in it at most 255 bytes") from None
    if sim is None:
        sim = simulate(compiled)
    if rep is None:
        rep = report(compiled, sim)
    writers = _writers(compiled, rep, sim)
    parent = out_dir.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{compiled.name}.", suffix=".tmp", dir=parent))
    except OSError as e:
        raise PlanError(f"cannot write next to the output directory: {e.strerror}", where=str(out_dir),
                        hint="the files are first written beside it: its parent must be a writable directory") from None
    created_dir = False
    placed: list[Path] = []
    backups: list[tuple[Path, Path]] = []
    try:
        new_dir = tmp / "new"
        old_dir = tmp / "old"
        new_dir.mkdir()
        old_dir.mkdir()
        mode = new_file_mode()
        for fname, write in writers:
            write(new_dir / fname)
            os.chmod(new_dir / fname, mode)     # temp files are 0600; outputs are ordinary files
        if not out_dir.exists():
            out_dir.mkdir(parents=True)
            created_dir = True
        names = {fname for fname, _ in writers}
        for stale in _stale_parts(out_dir, compiled.name, names):
            backup = old_dir / stale.name
            os.replace(stale, backup)
            backups.append((stale, backup))
        for fname, _ in writers:
            target = out_dir / fname
            if target.exists():
                backup = old_dir / fname
                os.replace(target, backup)
                backups.append((target, backup))
            os.replace(new_dir / fname, target)
            placed.append(target)
    except BaseException as err:
        for p in placed:
            try:
                p.unlink()
            except OSError:
                pass
        for target, backup in reversed(backups):
            try:
                os.replace(backup, target)
            except OSError:
                pass
        if created_dir:
            try:
                out_dir.rmdir()
            except OSError:
                pass
        if isinstance(err, OSError):
            raise PlanError(f"cannot write the outputs: {err.strerror or err}", where=str(out_dir),
                            hint="nothing was changed in the output directory") from None
        raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return placed
