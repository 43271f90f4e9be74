"""write_outputs: every file, readable by its own reader and consistent with the report; all or nothing."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
import xml.etree.ElementTree as ET

import pytest

from mission_plans import small_plan
from missions import outputs
from missions.compile import compile_plan
from missions.errors import PlanError
from missions.outputs import write_outputs
from missions.planfile import load_plan as read_plan_file, read_plan
from missions.report import report
from missions.wpl import load_wpl, read_wpl

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
    assert rep == json.loads(json.dumps(report(small)))
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
        items, _f, _r, _h = read_plan((out / f"split.part{k}.plan").read_text(), "p")
        assert len(items) == len(part) and all(a.same_on_wire(b) for a, b in zip(items, part))
        w, _ = read_wpl((out / f"split.part{k}.waypoints").read_text(), "w")
        assert len(w) == len(part)
    assert not (out / f"split.part{len(c.parts) + 1}.plan").exists()
    # a later compile without a split removes the stale part files (after success only)
    one = compile_plan(small_plan(tmp_path, name="split", limit=700))
    write_outputs(one, out)
    assert not list(out.glob("split.part*"))


def test_a_failing_writer_leaves_the_directory_untouched(small, tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "small.plan").write_text("old plan")
    (out / "small.part2.plan").write_text("old part")
    (out / "notes.txt").write_text("mine")
    before = _snapshot(out)

    def boom(fc):
        raise RuntimeError("disk on fire")
    monkeypatch.setattr("missions.kml_out.render_kml", boom)
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
    for fname in ("m.plan", "m.waypoints", "m.part1.plan"):
        with pytest.raises(PlanError, match="compile of m into this folder was interrupted"):
            (read_plan_file if fname.endswith(".plan") else load_wpl)(out / fname)
    paths = write_outputs(whole, out)                  # the next run: finishes the committed set, then its own
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in paths)
    assert not list(out.glob("m.part*"))
    read_plan_file(out / "m.plan")


def test_new_directory_is_not_left_behind_on_failure(small, tmp_path, monkeypatch):
    monkeypatch.setattr("missions.geojson_out.feature_collection",
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
