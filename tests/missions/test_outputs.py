"""write_outputs: every file, readable by its own reader and consistent with the report; all or nothing."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
import xml.etree.ElementTree as ET

import pytest

from mission_plans import small_plan
from missions.formats import outputs
from missions.compile import compile_plan
from missions.errors import PlanError
from missions.formats.outputs import write_outputs
from missions.formats.planfile import load_plan as read_plan_file, read_plan
from missions.measure.report import report
from missions.formats.wpl import load_wpl, read_wpl

KML = "{http://www.opengis.net/kml/2.2}"


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    return compile_plan(small_plan(d))


def _snapshot(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())} if d.exists() else {}


def test_every_output_is_written_and_reads_back(small, tmp_path):
    out = tmp_path / "out"
    paths = write_outputs(small, out)
    names = sorted(p.name for p in paths)
    assert names == sorted(f"small.{s}" for s in ("plan", "waypoints", "geojson", "kml", "setup.json", "params",
                                                   "report.json", "lua", "manifest.json"))
    assert sorted(p.name for p in out.iterdir()) == names            # nothing else, no temp folder
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    # the manifest lists every other file with the sha256 of its bytes
    manifest = json.loads((out / "small.manifest.json").read_text())
    assert manifest["name"] == "small"
    assert {r["file"]: r["sha256"] for r in manifest["files"]} == {
        n: hashlib.sha256((out / n).read_bytes()).hexdigest() for n in names if n != "small.manifest.json"}
    # the .plan and .waypoints hold exactly the compiled items
    items, fence, rally, home = read_plan((out / "small.plan").read_text(), "small.plan")
    assert len(items) == len(small.items) and all(a.same_on_wire(b) for a, b in zip(items, small.items))
    w_items, w_home = read_wpl((out / "small.waypoints").read_text(), "small.waypoints")
    assert len(w_items) == len(small.items) and all(a.same_on_wire(b) for a, b in zip(w_items, small.items))
    assert w_home[0] == pytest.approx(small.home[0], abs=1e-7)
    # the report file is the report
    rep = json.loads((out / "small.report.json").read_text())
    assert rep == json.loads(json.dumps(report(small).to_json()))
    # GeoJSON: one photo feature per measured photo, footprints, area, path
    fc = json.loads((out / "small.geojson").read_text())
    kinds = [f["properties"]["kind"] for f in fc["features"]]
    assert kinds.count("photo") == rep["photos"]["thermal"]
    assert kinds.count("footprint") == rep["photos"]["thermal"]
    assert kinds.count("area") == 1 and kinds.count("path") == 1 and kinds.count("home") == 1
    path = next(f for f in fc["features"] if f["properties"]["kind"] == "path")
    assert all(-180 <= c[0] <= 180 and -90 <= c[1] <= 90 for c in path["geometry"]["coordinates"])
    assert path["geometry"]["coordinates"][0][:2] == pytest.approx([small.home[1], small.home[0]], abs=1e-7)
    # KML: the same features
    root = ET.fromstring((out / "small.kml").read_bytes())
    assert len(list(root.iter(KML + "Placemark"))) == len(fc["features"])
    # setup sequence and Lua bridge
    setup = json.loads((out / "small.setup.json").read_text())
    assert setup["plan"] == "small" and len(setup["steps"]) == len(small.setup)
    assert (out / "small.lua").read_text() == small.lua
    assert (out / "small.params").read_text().startswith("#")
    assert oct((out / "small.plan").stat().st_mode & 0o777) == oct((out / "small.kml").stat().st_mode & 0o777)


def test_split_mission_writes_one_file_pair_per_part(tmp_path):
    c = compile_plan(small_plan(tmp_path, name="split", limit=10))
    assert len(c.parts) > 1
    out = tmp_path / "out"
    write_outputs(c, out)
    for k, part in enumerate(c.parts, start=1):
        items, _f, _r, _h = read_plan((out / f"split.sortie{k}.plan").read_text(), "p")
        assert len(items) == len(part) and all(a.same_on_wire(b) for a, b in zip(items, part))
        w, _ = read_wpl((out / f"split.sortie{k}.waypoints").read_text(), "w")
        assert len(w) == len(part)
    assert not (out / f"split.sortie{len(c.parts) + 1}.plan").exists()
    # a later compile without a split removes the stale part files (after success only)
    one = compile_plan(small_plan(tmp_path, name="split", limit=700))
    write_outputs(one, out)
    assert not list(out.glob("split.sortie*"))


def test_a_failing_writer_leaves_the_directory_untouched(small, tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "small.plan").write_text("old plan")
    (out / "small.sortie2.plan").write_text("old part")
    (out / "notes.txt").write_text("mine")
    before = _snapshot(out)

    def boom(fc):
        raise RuntimeError("disk on fire")
    monkeypatch.setattr("missions.formats.kml.render_kml", boom)
    with pytest.raises(RuntimeError):
        write_outputs(small, out)
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_failure_before_the_commit_leaves_the_directory_untouched(small, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_outputs(small, out)
    (out / "notes.txt").write_text("mine")
    before = _snapshot(out)
    real = os.rename

    def full(src, dst):
        if Path(dst).name == ".small.commit":
            raise OSError(28, "No space left on device")
        return real(src, dst)
    monkeypatch.setattr(outputs.os, "rename", full)
    with pytest.raises(PlanError, match="cannot write the outputs: No space left") as e:
        write_outputs(small, out)
    assert "nothing was changed" in e.value.hint
    assert _snapshot(out) == before
    assert sorted(p.name for p in out.iterdir()) == sorted(before)   # no temporary folder either


def test_a_failure_after_the_commit_is_refused_by_readers_and_finished_by_the_next_run(tmp_path, monkeypatch):
    """Once the new set is committed it wins: a failure while moving it in leaves it waiting in .NAME.commit,
    readers refuse NAME's half-moved files meanwhile, and the next compile finishes it (stale parts removed)."""
    split = compile_plan(small_plan(tmp_path, name="m", limit=10))
    whole = compile_plan(small_plan(tmp_path, name="m"))
    out = tmp_path / "out"
    write_outputs(split, out)
    real = os.replace
    calls = {"n": 0}

    def flaky(src, dst):
        if Path(src).parent.name == ".m.commit":
            calls["n"] += 1
            if calls["n"] == 3:
                raise OSError(5, "Input/output error")
        return real(src, dst)
    monkeypatch.setattr(outputs.os, "replace", flaky)
    with pytest.raises(PlanError, match="cannot finish placing the outputs: Input/output error") as e:
        write_outputs(whole, out)
    assert ".m.commit" in e.value.hint and "next compile" in e.value.hint
    monkeypatch.setattr(outputs.os, "replace", real)
    assert (out / ".m.commit").is_dir()
    for fname in ("m.plan", "m.waypoints", "m.sortie1.plan"):
        with pytest.raises(PlanError, match="compile of m into this folder was interrupted"):
            (read_plan_file if fname.endswith(".plan") else load_wpl)(out / fname)
    paths = write_outputs(whole, out)                  # the next run: finishes the committed set, then its own
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in paths)
    assert not list(out.glob("m.sortie*"))
    read_plan_file(out / "m.plan")


def test_new_directory_is_not_left_behind_on_failure(small, tmp_path, monkeypatch):
    monkeypatch.setattr("missions.formats.geojson.feature_collection",
                        lambda *a: (_ for _ in ()).throw(ValueError("bad geometry")))
    with pytest.raises(ValueError):
        write_outputs(small, tmp_path / "fresh")
    assert list(tmp_path.iterdir()) == []


def test_output_path_that_is_a_file_is_refused(small, tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(PlanError) as e:
        write_outputs(small, f)
    assert f.read_text() == "x"
    assert e.value.where == str(f) and "-o" in e.value.hint


def test_unusable_output_paths_say_what_to_do(small, tmp_path):
    too_long = tmp_path / ("m" * 300)                      # exists() itself fails: the name is too long
    with pytest.raises(PlanError, match="cannot use the output directory") as e:
        write_outputs(small, too_long)
    assert e.value.where == str(too_long) and "at most 255 bytes" in e.value.hint
    (tmp_path / "file").write_text("x")
    under_a_file = tmp_path / "file" / "out"               # its parent is a file: nothing can be made beside it
    with pytest.raises(PlanError, match="cannot create the output directory") as e:
        write_outputs(small, under_a_file)
    assert e.value.where == str(under_a_file) and "parent must be a writable directory" in e.value.hint
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


# ------------------------------------------------------------------------- nothing the tool did not write

def _tree(d: Path) -> dict[str, object]:
    """Every entry under d: a regular file's bytes, or what else it is (a symlink with its target)."""
    out: dict[str, object] = {}
    for root, dirs, files in os.walk(d):
        for n in dirs + files:
            p = Path(root) / n
            rel = str(p.relative_to(d))
            if p.is_symlink():
                out[rel] = f"symlink -> {os.readlink(p)}"
            elif p.is_dir():
                out[rel] = "directory"
            elif p.is_file():
                out[rel] = p.read_bytes()
            else:
                out[rel] = "other"
    return out


@pytest.mark.parametrize("kind", ["directory", "symlink", "fifo"])
@pytest.mark.parametrize("fname", ["small.kml", "small.manifest.json"])
def test_a_non_regular_file_in_the_way_of_an_output_is_refused_before_anything_is_written(small, tmp_path, kind,
                                                                                        fname):
    out = tmp_path / "out"
    write_outputs(small, out)                     # an earlier set, then the user's thing under an output name
    target = out / fname
    target.unlink()
    if kind == "directory":
        target.mkdir()
        (target / "photo.jpg").write_bytes(b"the user's photo")
    elif kind == "symlink":
        (tmp_path / "elsewhere.txt").write_text("the user's file")
        target.symlink_to(tmp_path / "elsewhere.txt")
    else:
        os.mkfifo(target)
    before = _tree(tmp_path)
    with pytest.raises(PlanError, match="is in the way of an output file; refusing to replace it") as e:
        write_outputs(small, out)
    assert e.value.where == str(target) and "move it away" in e.value.hint
    assert _tree(tmp_path) == before


def test_stale_parts_are_removed_only_when_the_last_manifest_lists_them_as_regular_files(tmp_path):
    split = compile_plan(small_plan(tmp_path, name="s", limit=10))
    whole = compile_plan(small_plan(tmp_path, name="s"))
    assert len(split.parts) >= 3
    out = tmp_path / "out"
    write_outputs(split, out)
    (out / "s.sortie1.plan").unlink()
    (out / "s.sortie1.plan").mkdir()                          # the user's folder where a listed part was
    (out / "s.sortie1.plan" / "keep.txt").write_text("mine")
    (out / "s.sortie2.waypoints").unlink()
    (out / "s.sortie2.waypoints").symlink_to(tmp_path / "s.yaml")
    (out / "s.sortie9.plan").write_text("a part no manifest lists")   # e.g. left by an older wiris-tools
    (out / ".s.photos.tmp").mkdir()                         # hidden, but not a name a compile's mkdtemp makes
    write_outputs(whole, out)
    assert (out / ".s.photos.tmp").is_dir()
    left = sorted(p.name for p in out.glob("s.sortie*"))
    assert left == ["s.sortie1.plan", "s.sortie2.waypoints", "s.sortie9.plan"]
    assert (out / "s.sortie1.plan" / "keep.txt").read_text() == "mine"
    assert (out / "s.sortie9.plan").read_text() == "a part no manifest lists"
    assert (tmp_path / "s.yaml").exists()
    # no reader takes the part the last compile does not list
    with pytest.raises(PlanError, match=r"not a file of the last compile of s \(s.manifest.json does not list it\)"):
        read_plan_file(out / "s.sortie9.plan")


def test_an_output_that_is_an_input_of_the_plan_is_refused(tmp_path):
    """`-o` the plan's own area folder, or any output name that is (a hard link to) the plan, an area or an
    exclusion file: refused naming both, before anything is written."""
    import shutil

    examples = Path(__file__).resolve().parents[2] / "examples"
    shutil.copytree(examples, tmp_path / "ex")
    plan = tmp_path / "ex" / "solar-park.yaml"
    compiled = compile_plan(plan)
    areas = tmp_path / "ex" / "areas"
    assert {Path(p).resolve() for p in compiled.inputs} == {plan.resolve(), areas / "solar-park.geojson",
                                                           areas / "substation.geojson"}
    cases = [(areas, areas / "solar-park.geojson")]           # the finding: -o examples/areas
    linked = tmp_path / "linked"
    linked.mkdir()
    for fname, src in (("solar-park.kml", areas / "substation.geojson"), ("solar-park.setup.json", plan)):
        d = linked / fname.split(".", 1)[1]
        d.mkdir()
        os.link(src, d / fname)                                # a hard link: the same file under an output name
        cases.append((d, src))
    rep = report(compiled)
    for out, victim in cases:
        before = _tree(tmp_path)
        with pytest.raises(PlanError, match="an input of the plan") as e:
            write_outputs(compiled, out, rep=rep)
        assert str(victim) in str(e.value) and e.value.where.startswith(str(out) + os.sep), str(e.value)
        assert _tree(tmp_path) == before


# ------------------------------------------------------------------------------------- readers check


def test_readers_take_a_hand_edited_compiled_file_and_refuse_an_unlisted_part(small, tmp_path):
    out = tmp_path / "out"
    write_outputs(small, out)
    read_plan_file(out / "small.plan")
    load_wpl(out / "small.waypoints")
    text = (out / "small.waypoints").read_text()
    edited = text.replace("\t40\t", "\t45\t", 1)             # the take-off altitude, by hand
    assert edited != text
    (out / "small.waypoints").write_text(edited)
    items, _home = load_wpl(out / "small.waypoints")           # the user's edit is theirs to fly
    assert any(it.z == 45 for it in items)
    from wiris_tools.camera_client import load_setup
    load_setup(out / "small.setup.json")
    # a part file the last compile did not write (an earlier, longer compile's) is never flown
    (out / "small.sortie3.plan").write_bytes((out / "small.plan").read_bytes())
    with pytest.raises(PlanError, match="not a file of the last compile of small") as e:
        read_plan_file(out / "small.sortie3.plan")
    assert e.value.where == str(out / "small.sortie3.plan") and e.value.hint
    # a file no manifest speaks for (QGroundControl's own .plan next to it) is read as before
    (out / "mine.plan").write_bytes((out / "small.plan").read_bytes())
    read_plan_file(out / "mine.plan")


# ---------------------------------------------------------------------------------------------- SIGKILL

KILLS = 40


def _write_forever(sets, out: Path, ready: Path) -> None:
    """The child: write the two sets in turn until killed."""
    ready.touch()
    while True:
        for compiled, rep, sim in sets:
            write_outputs(compiled, out, rep=rep, sim=sim)


def _visible(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir()) if not p.name.startswith(".")}


def test_a_sigkill_at_any_moment_leaves_one_complete_set_after_the_next_run(tmp_path):
    """A real child process writes a split mission (parts) and an unsplit one of the same NAME in turn, and is
    SIGKILLed at 40 random moments (seeded). After each kill, readers take no file that is not the manifest's;
    and after recovery, what the next run does first, the folder holds exactly one of the two sets, nothing else,
    no temporary folder."""
    import gc
    import multiprocessing
    import random
    import time

    from missions.formats.outputs import check_output, recover_outputs
    from missions.measure.flight import simulate

    split = compile_plan(small_plan(tmp_path, name="k", limit=10))
    whole = compile_plan(small_plan(tmp_path, name="k"))
    sets = []
    for c in (split, whole):
        sim = simulate(c)
        sets.append((c, report(c, sim), sim))
    expected = []
    for i, (c, rep, sim) in enumerate(sets):
        write_outputs(c, tmp_path / f"ref{i}", rep=rep, sim=sim)
        expected.append(_visible(tmp_path / f"ref{i}"))
    assert expected[0].keys() != expected[1].keys()
    out = tmp_path / "out"
    write_outputs(*sets[1][:1], out, rep=sets[1][1], sim=sets[1][2])
    rng = random.Random(20240611)
    fork = multiprocessing.get_context("fork")
    seen = {"pending commit": 0, "temp folder": 0, "clean": 0}
    for kill in range(KILLS):
        ready = tmp_path / f"ready-{kill}"
        child = fork.Process(target=_write_forever, args=(sets, out, ready), daemon=True)
        # Frozen, the parent's objects are left out of the child's collections: a full collection the child
        # inherits due would otherwise copy the parent's whole heap page by page (copy-on-write) and outlast the
        # kill window, so that whether any kill lands mid-write hung on the parent's allocation count.
        gc.freeze()
        try:
            child.start()
        finally:
            gc.unfreeze()
        for _ in range(20_000):
            if ready.exists() or not child.is_alive():
                break
            time.sleep(0.001)
        assert ready.exists(), "the writer did not start"
        time.sleep(rng.uniform(0.0, 0.3))
        child.kill()                                 # SIGKILL
        child.join(30)
        assert child.exitcode == -9, child.exitcode
        hidden = sorted(p.name for p in out.iterdir() if p.name.startswith("."))
        if ".k.commit" in hidden:
            seen["pending commit"] += 1
        elif hidden:
            seen["temp folder"] += 1
            # not committed: the folder's set is exactly as it was
            assert _visible(out) in expected, (kill, hidden)
        else:
            seen["clean"] += 1
            assert _visible(out) in expected, kill
        # before any recovery, a reader takes only files of the set the manifest names, and only when complete
        manifest = (out / "k.manifest.json").read_bytes()
        owner = next(e for e in expected if e["k.manifest.json"] == manifest)
        for p in sorted(out.glob("k*.plan")) + sorted(out.glob("k*.waypoints")):
            data = p.read_bytes()
            try:
                check_output(p)
            except PlanError:
                continue
            assert ".k.commit" not in hidden and data == owner[p.name], (kill, p.name)
        recover_outputs(out, "k")                   # what the next run does first
        assert _visible(out) in expected, kill
        assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [], kill
    # the kills landed at different stages (the seed and the machine decide which; most land mid-write)
    assert seen["pending commit"] + seen["temp folder"] > 0, seen
    paths = write_outputs(*sets[0][:1], out, rep=sets[0][1], sim=sets[0][2])    # and the next run completes
    assert _visible(out) == expected[0] and sorted(p.name for p in out.iterdir()) == sorted(p.name for p in paths)
