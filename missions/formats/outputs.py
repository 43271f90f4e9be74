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
  NAME.sortieK.plan, NAME.sortieK.waypoints  (K = 1..N) only when the mission is longer than one battery
                       (vehicle.endurance_min) or the vehicle's item limit: each sortie is a complete mission
                       (take-off to landing) to upload and fly in turn on a fresh battery (missions.sorties);
                       NAME.plan still holds the whole mission for review.
  NAME.manifest.json   every file above with its sha256, written last: the set's commit record (below)

One set at a time, also across a SIGKILL or a power cut at any moment. The files are siblings in the user's
folder, so no single rename can swap them; instead the manifest says which bytes belong to the set, and a
committed set is always finished by rolling it forward:

1. Under an exclusive flock on DIR (one compile at a time there), an interrupted earlier compile of NAME is
   finished first: see 3; stale `.NAME.XXXXXXXX.tmp` folders (a compile killed before its commit) are removed.
2. Everything, the manifest included, is written into a fresh `DIR/.NAME.XXXXXXXX.tmp/` and fsynced (files and
   folder). Nothing outside it has changed yet: a kill here leaves DIR's set as it was.
3. Commit: one rename of that folder to `DIR/.NAME.commit` (then DIR is fsynced). From here the new set wins:
   each file is renamed from the commit folder into DIR (a file already moved is skipped, so this can be
   repeated after a kill), files the previous manifest lists and the new set lacks (stale `NAME.sortieK.*`) are
   removed, DIR is fsynced, the manifest is renamed in last, and the empty commit folder is removed.

Readers of compiled files (`load_plan`, `load_wpl`, `wiris camera apply`'s setup loader) call check_output():
no `.NAME.commit` may be pending, and a file named like a part of NAME must be listed by its manifest; so a
half-moved set, or a part file an earlier compile left that the last one does not list, is refused, never
flown.

Nothing the tool did not write is replaced or removed: an output name that is a directory, a symlink or any
other non-regular file is refused before anything is written, as is an output name that is one of the
plan's inputs (the plan, an area or exclusion file; the same file also through a hard link). Stale part files
are removed only when the previous manifest lists them and they are regular files; an unlisted one is left
alone (and refused by the readers above once a manifest of NAME exists). When the report or any writer
raises, DIR is left exactly as it was.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
from pathlib import Path
import re
import shutil
import stat
import tempfile
from typing import Callable, Iterable, Iterator, NamedTuple

from cdf.paths import require_directory
from missions.compiled import Compiled
from missions.emit.params import format_params
from missions.emit.setup import setup_json
from missions.errors import PlanError
from missions.formats import geojson, kml, planfile, wpl
from missions.formats.jsonfinite import finite
from missions.measure.flight import simulate
from missions.measure.report import MissionReport, report


def _json_text(obj) -> str:
    return json.dumps(finite(obj), indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def setup_document(compiled: Compiled) -> dict:
    """NAME.setup.json: the ordered pre-flight steps in missions.emit.setup's format (what `wiris camera apply` reads)."""
    return setup_json(compiled.name, compiled.setup)


def _writers(compiled: Compiled, rep: MissionReport, sim) -> list[tuple[str, Callable[[Path], None]]]:
    name = compiled.name
    fc = geojson.feature_collection(compiled, sim, rep)
    out: list[tuple[str, Callable[[Path], None]]] = [
        (f"{name}.plan", lambda p: planfile.write_plan(p, compiled)),
        (f"{name}.waypoints", lambda p: wpl.write_wpl(p, compiled.items, home=compiled.home,
                                                      firmware=compiled.firmware)),
        (f"{name}.geojson", lambda p: p.write_text(geojson.dumps_collection(fc), encoding="utf-8")),
        (f"{name}.kml", lambda p: p.write_text(kml.render_kml(fc), encoding="utf-8")),
        (f"{name}.setup.json", lambda p: p.write_text(_json_text(setup_document(compiled)), encoding="utf-8")),
        (f"{name}.params", lambda p: p.write_text(format_params(compiled), encoding="utf-8")),
        (f"{name}.report.json", lambda p: p.write_text(_json_text(rep.to_json()), encoding="utf-8")),
    ]
    if compiled.lua:
        out.append((f"{name}.lua", lambda p: p.write_text(compiled.lua, encoding="utf-8")))
    if len(compiled.parts) > 1:     # sorties (missions.sorties): one complete mission each
        for k, part in enumerate(compiled.parts, start=1):
            out.append((f"{name}.sortie{k}.plan", lambda p, part=part: planfile.write_plan(p, compiled, items=part)))
            out.append((f"{name}.sortie{k}.waypoints",
                        lambda p, part=part: wpl.write_wpl(p, part, home=compiled.home, firmware=compiled.firmware)))
    return out


MAX_MANIFEST_BYTES = 1 << 20
_READ_SUFFIXES = (".plan", ".waypoints", ".setup.json", ".geojson", ".kml", ".lua", ".params", ".report.json")
_SHA256 = re.compile(r"[0-9a-f]{64}")
_AGAIN = "compile the plan again into this folder: that finishes or replaces the set"


class Manifest(NamedTuple):
    """NAME.manifest.json: the files of one compiled set, each with the sha256 of its bytes, in writing order."""

    name: str
    files: dict[str, str]


def manifest_name(name: str) -> str:
    return f"{name}.manifest.json"


def _commit_dir(out_dir: Path, name: str) -> Path:
    return out_dir / f".{name}.commit"


def _manifest_bytes(manifest: Manifest) -> bytes:
    rows = [{"file": f, "sha256": h} for f, h in manifest.files.items()]
    return (json.dumps({"name": manifest.name, "files": rows}, indent=1) + "\n").encode("utf-8")


def _is_own_file_name(name: str, fname: object) -> bool:
    """Whether a manifest row may name `fname`: one of NAME's files, in DIR itself (never a path elsewhere)."""
    return (isinstance(fname, str) and fname.startswith(name + ".") and fname != manifest_name(name)
            and not any(c in fname for c in "/\\\0"))


def read_manifest(path: Path, name: str) -> Manifest | None:
    """The manifest of NAME at `path`, None when there is none; PlanError when it cannot be trusted."""
    hint = f"{_AGAIN} (or move {path.name} away)"
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            raise PlanError("the manifest is not a regular file", where=str(path), hint=hint)
        with open(path, "rb") as fh:
            raw = fh.read(MAX_MANIFEST_BYTES + 1)
        doc = json.loads(raw.decode("utf-8")) if len(raw) <= MAX_MANIFEST_BYTES else None
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise PlanError(f"cannot read the manifest: {getattr(err, 'strerror', None) or err}", where=str(path),
                        hint=hint) from None
    rows = doc.get("files") if isinstance(doc, dict) and doc.get("name") == name else None
    if not isinstance(rows, list) or not all(isinstance(r, dict) and _is_own_file_name(name, r.get("file"))
                                             and isinstance(r.get("sha256"), str) and _SHA256.fullmatch(r["sha256"])
                                             for r in rows):
        raise PlanError(f"this is not a manifest `wiris mission compile` wrote for {name}", where=str(path), hint=hint)
    return Manifest(name, {r["file"]: r["sha256"] for r in rows})


def _previous_manifest(out_dir: Path, name: str) -> Manifest | None:
    """The manifest of the set in DIR; an unreadable one lists nothing (so nothing is removed by it)."""
    try:
        return read_manifest(out_dir / manifest_name(name), name)
    except PlanError:
        return None


def _candidate_names(fname: str) -> list[str]:
    """The plan names whose outputs `fname` could be, most specific first ("a.sortie2.plan": "a.sortie2", "a")."""
    names = []
    for suffix in _READ_SUFFIXES:
        if fname.endswith(suffix) and len(fname) > len(suffix):
            stem = fname[: -len(suffix)]
            names.append(stem)
            part = re.fullmatch(r"(.+)\.sortie\d+", stem)
            if part and suffix in (".plan", ".waypoints"):
                names.append(part.group(1))
    return names


def check_output(path: str | Path) -> None:
    """Refuse `path` when it is a file of a compiled set that is not the last complete compile's: a compile of its
    NAME is pending in that folder, or NAME's manifest there does not list it (a part left by an earlier, longer
    compile). A file no manifest speaks for passes, and so does a listed file the user has edited since: its
    bytes are theirs to fly (QGroundControl saves a .plan in place, `mission download -o` may write under the
    compile's name), and a half-switched set cannot show up here, since from the commit on the pending folder
    refuses every file of NAME."""
    p = Path(path)
    folder = p.parent
    for name in _candidate_names(p.name):
        if os.path.lexists(_commit_dir(folder, name)):
            raise PlanError(f"a compile of {name} into this folder was interrupted and is not finished",
                            where=str(p), hint=f"{_AGAIN}; until then its files are not used")
        manifest = read_manifest(folder / manifest_name(name), name)
        if manifest is None:
            continue
        if p.name not in manifest.files:
            raise PlanError(f"not a file of the last compile of {name} ({manifest_name(name)} does not list it)",
                            where=str(p), hint=f"a file left by an earlier compile: use the files "
                                               f"{manifest_name(name)} lists, or move this one away")
        return


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISLNK(mode):
        return "a symlink"
    return "not a regular file"


class Changes(NamedTuple):
    """The file names of DIR a compile replaces (its outputs and manifest) and removes (stale files of the
    previous set)."""

    replaced: list[str]
    removed: list[str]


def _changes(out_dir: Path, name: str, names: list[str]) -> Changes:
    previous = _previous_manifest(out_dir, name)
    return Changes(names + [manifest_name(name)], [f for f in (previous.files if previous else ()) if f not in names])


def _refuse_what_is_in_the_way(out_dir: Path, changes: Changes, inputs: Iterable[str]) -> None:
    """PlanError unless every path to be replaced is absent or a regular file, and no path to be replaced or
    removed is one of the plan's inputs (compared by device and inode: a hard link to an input is that input).
    A non-regular file where a stale file was is not in the way: it is left alone."""
    inputs_by_inode = {}
    for src in inputs:
        with contextlib.suppress(OSError):
            st = os.stat(src)
            inputs_by_inode[(st.st_dev, st.st_ino)] = src
    for fname in changes.replaced + changes.removed:
        target = out_dir / fname
        try:
            st = os.lstat(target)
        except FileNotFoundError:
            continue
        except OSError as err:
            raise PlanError(f"cannot look at an output path: {err.strerror}", where=str(target),
                            hint="give -o a directory you may read and write") from None
        if not stat.S_ISREG(st.st_mode):
            if fname in changes.removed:
                continue
            raise PlanError(f"{_kind(st.st_mode)} is in the way of an output file; refusing to replace it",
                            where=str(target), hint="move it away, or choose another -o: a compile replaces only "
                                                    "regular files")
        same = inputs_by_inode.get((st.st_dev, st.st_ino))
        if same is not None:
            what = (f"removing this stale file of the previous compile would remove {same}" if fname in changes.removed
                    else f"this output would overwrite {same}")
            raise PlanError(f"{what}, an input of the plan", where=str(target),
                            hint="choose another -o directory: the plan's own files are never written")


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _synced_sha256(path: Path) -> str:
    with open(path, "rb") as fh:
        digest = hashlib.sha256(fh.read()).hexdigest()
        os.fsync(fh.fileno())
    return digest


@contextlib.contextmanager
def _locked(out_dir: Path) -> Iterator[None]:
    """One compile at a time in DIR: an exclusive flock on the folder (released when the process ends, however)."""
    fd = os.open(out_dir, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _roll_forward(out_dir: Path, name: str) -> None:
    """Finish a committed set (`.NAME.commit`): step 3 of the module docstring, repeatable after a kill."""
    commit = _commit_dir(out_dir, name)
    try:
        if not stat.S_ISDIR(os.lstat(commit).st_mode):
            raise PlanError("this is not the folder an interrupted compile leaves", where=str(commit),
                            hint="move it away; a compile of this plan uses that name")
    except FileNotFoundError:
        return
    staged = commit / manifest_name(name)
    if os.path.lexists(staged):        # else the manifest is in place: only the empty folder was left
        new = read_manifest(staged, name)
        previous = _previous_manifest(out_dir, name)
        for fname in new.files:
            if os.path.lexists(commit / fname):
                os.replace(commit / fname, out_dir / fname)
        for fname in (previous.files if previous else ()):
            if fname not in new.files:
                _remove_if_regular(out_dir / fname)
        _fsync_dir(out_dir)
        os.replace(staged, out_dir / manifest_name(name))
        _fsync_dir(out_dir)
    shutil.rmtree(commit)
    _fsync_dir(out_dir)


def _remove_if_regular(path: Path) -> None:
    """Remove a file of the previous set that the new one lacks; anything else put there since is left alone."""
    try:
        if stat.S_ISREG(os.lstat(path).st_mode):
            path.unlink()
    except FileNotFoundError:
        pass


def _remove_stale_temp_dirs(out_dir: Path, name: str) -> None:
    """`.NAME.XXXXXXXX.tmp` folders (mkdtemp's names) of compiles killed before their commit."""
    pattern = re.compile(r"\." + re.escape(name) + r"\.[a-z0-9_]{8}\.tmp")
    for entry in os.scandir(out_dir):
        if pattern.fullmatch(entry.name) and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path)


def _recover(out_dir: Path, name: str) -> None:
    try:
        _roll_forward(out_dir, name)
        _remove_stale_temp_dirs(out_dir, name)
    except OSError as err:
        raise PlanError(f"cannot finish an interrupted compile of {name}: {err.strerror or err}", where=str(out_dir),
                        hint=f"its new files wait in {_commit_dir(out_dir, name).name}; free the cause and compile "
                             "again") from None


def recover_outputs(out_dir: str | Path, name: str) -> None:
    """What every compile of NAME into DIR does first: finish a set an interrupted compile committed, and remove
    the temporary folders of compiles killed before their commit. Nothing to do leaves DIR as it is."""
    out_dir = Path(out_dir)
    if out_dir.is_dir():
        with _locked(out_dir):
            _recover(out_dir, name)


def _write_temp_set(out_dir: Path, name: str, writers: list[tuple[str, Callable[[Path], None]]]) -> Path:
    """Step 2: every file and the manifest in a fresh `.NAME.XXXXXXXX.tmp` folder of DIR, fsynced."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}.", suffix=".tmp", dir=out_dir))
    try:
        mode = planfile.new_file_mode()
        files: dict[str, str] = {}
        for fname, write in writers:
            write(tmp / fname)
            os.chmod(tmp / fname, mode)     # temp files are 0600; outputs are ordinary files
            files[fname] = _synced_sha256(tmp / fname)
        staged = tmp / manifest_name(name)
        staged.write_bytes(_manifest_bytes(Manifest(name, files)))
        os.chmod(staged, mode)
        _synced_sha256(staged)
        _fsync_dir(tmp)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return tmp


def _make_output_dir(out_dir: Path) -> None:
    try:
        out_dir.mkdir(parents=True)
    except OSError as e:
        raise PlanError(f"cannot create the output directory: {e.strerror}", where=str(out_dir),
                        hint="its parent must be a writable directory") from None


def write_outputs(compiled: Compiled, out_dir: str | Path, rep: MissionReport | None = None, sim=None) -> list[Path]:
    """Write every output file of `compiled` into `out_dir`; return their paths (in the order above, the
    manifest last)."""
    out_dir = Path(out_dir)
    require_directory(out_dir, PlanError, missing_ok=True, hint="give a directory for -o",
                      access_hint="give -o a path you may access, each name in it at most 255 bytes")
    if sim is None:
        sim = simulate(compiled)
    if rep is None:
        rep = report(compiled, sim)
    writers = _writers(compiled, rep, sim)
    name = compiled.name
    names = [fname for fname, _ in writers]
    if out_dir.is_dir():                # refused before anything is written, DIR included
        _refuse_what_is_in_the_way(out_dir, _changes(out_dir, name, names), compiled.inputs)
    created = False
    committed = False
    try:
        if not out_dir.is_dir():
            _make_output_dir(out_dir)
            created = True
        with _locked(out_dir):
            _recover(out_dir, name)
            _refuse_what_is_in_the_way(out_dir, _changes(out_dir, name, names), compiled.inputs)
            tmp = _write_temp_set(out_dir, name, writers)
            try:
                os.rename(tmp, _commit_dir(out_dir, name))      # the commit: this set wins, now or next run
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)
                raise
            committed = True
            _fsync_dir(out_dir)
            _roll_forward(out_dir, name)
    except BaseException as err:
        if created and not committed:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        if not isinstance(err, OSError):
            raise
        if committed:
            raise PlanError(f"cannot finish placing the outputs: {err.strerror or err}", where=str(out_dir),
                            hint=f"the new files wait in {_commit_dir(out_dir, name).name} and the next compile "
                                 f"into this folder finishes them; until then {name}'s files are refused by "
                                 "upload and apply") from None
        raise PlanError(f"cannot write the outputs: {err.strerror or err}", where=str(out_dir),
                        hint="nothing was changed in the output directory") from None
    return [out_dir / fname for fname in names] + [out_dir / manifest_name(name)]
