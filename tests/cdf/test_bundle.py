"""The hosting bundle: files named by vendor/model/version, xz twins, manifest, byte-identical rebuilds,
immutability of published versions, URI length, strict validation before writing, atomic writes, CLI."""

from __future__ import annotations

import hashlib
import json
import lzma
import os
import re
import shutil
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

import cdf.generate
from cdf.bundle import MANIFEST, URI_MAX, build_bundle, definition_uri, xz_bytes
from cdf.catalogue import TABLES_DIR, catalogue, load_catalogue
from cdf.errors import CdfError
from wiris_tools.cli import cli

BASE = "http://127.0.0.1:8000/cdf"
MODELS = sorted(c.id for c in catalogue().cameras if c.has_cdf)
FIELDS = ["id", "vendor", "model", "version", "file", "uri", "sha256", "bytes"]


def snapshot(directory: Path) -> dict[str, bytes]:
    if not directory.exists():
        return {}
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def table_copy(tmp_path: Path) -> Path:
    tables = tmp_path / "tables"
    shutil.copytree(TABLES_DIR, tables)
    return tables


def edit_yaml(path: Path, change) -> None:
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    change(data)
    path.write_text(yaml.safe_dump(data, allow_unicode=True, sort_keys=False), encoding="utf-8")


# --------------------------------------------------------------------------------------------- layout

def test_all_builds_every_definition_and_the_manifest(tmp_path):
    out = tmp_path / "cdf"
    result = build_bundle(out, all_models=True, base_url=BASE, xz=True)
    assert sorted(e.id for e in result.entries) == MODELS
    assert dict(result.skipped).keys() == {"rededge-mx", "rededge-m"}
    manifest = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
    rows = manifest["models"]
    assert list(manifest) == ["models"]
    assert [r["id"] for r in rows] == MODELS
    for r in rows:
        assert list(r) == FIELDS
        cam = catalogue().get(r["id"])
        data = (out / r["file"]).read_bytes()
        assert r["file"] == f"workswell_{r['id']}_v{cam.definition_version}.xml"
        assert (r["vendor"], r["model"], r["version"]) == (cam.vendor, cam.model, cam.definition_version)
        assert r["uri"] == f"{BASE}/{r['file']}" and len(r["uri"]) <= URI_MAX
        assert r["sha256"] == hashlib.sha256(data).hexdigest() and r["bytes"] == len(data)
        assert data == cdf.generate.definition_xml(cam)
        assert lzma.decompress((out / (r["file"] + ".xz")).read_bytes()) == data
    assert sorted(snapshot(out)) == sorted([MANIFEST] + [r["file"] for r in rows] + [r["file"] + ".xz" for r in rows])


def test_xz_twins_are_valid_single_xz_streams_under_strict():
    validation = pytest.importorskip("cdf.validation")
    data = cdf.generate.definition_xml(catalogue().get("wiris-pro"))
    packed = xz_bytes(data)
    assert packed.startswith(b"\xfd7zXZ\x00") and packed == xz_bytes(data)
    assert validation.validate_bytes(packed, "x.xml.xz", "strict").valid


def test_rebuilding_unchanged_tables_reproduces_identical_bytes(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    build_bundle(a, all_models=True, base_url=BASE, xz=True)
    build_bundle(b, all_models=True, base_url=BASE, xz=True, cat=load_catalogue(table_copy(tmp_path)))
    assert snapshot(a) == snapshot(b)
    before = {p: os.stat(a / p).st_mtime_ns for p in snapshot(a)}
    again = build_bundle(a, all_models=True, base_url=BASE, xz=True)
    assert again.written == () and len(again.unchanged) == 2 * len(MODELS)
    assert {p: os.stat(a / p).st_mtime_ns for p in snapshot(a)} == before   # nothing rewritten


def test_building_models_one_by_one_merges_the_manifest(tmp_path):
    build_bundle(tmp_path / "d", ["wiris-pro"], base_url=BASE)
    build_bundle(tmp_path / "d", ["gis-320"], base_url=BASE)
    rows = json.loads((tmp_path / "d" / MANIFEST).read_text())["models"]
    assert [r["id"] for r in rows] == ["gis-320", "wiris-pro"]
    build_bundle(tmp_path / "all", ["wiris-pro", "gis-320"], base_url=BASE)
    assert (tmp_path / "d" / MANIFEST).read_bytes() == (tmp_path / "all" / MANIFEST).read_bytes()


def test_without_base_url_the_uri_is_the_file_name(tmp_path):
    result = build_bundle(tmp_path / "d", ["wiris-pro"])
    assert result.entries[0].uri == "workswell_wiris-pro_v1.xml"
    assert definition_uri("mftp://", "x.xml") == "mftp://x.xml"
    assert definition_uri("http://h/cdf/", "x.xml") == "http://h/cdf/x.xml"


# ------------------------------------------------------------------------------------- immutability

def test_changed_table_without_new_version_is_refused_then_accepted_with_one(tmp_path):
    out = tmp_path / "cdf"
    build_bundle(out, all_models=True, base_url=BASE)
    published = snapshot(out)
    tables = table_copy(tmp_path)

    def relabel(data):
        for s in data["groups"]["radiometry"]:
            if s["key"] == "emissivity":
                s["label"] = "Object emissivity"
    edit_yaml(tables / "workswell.yaml", relabel)
    cat = load_catalogue(tables)
    de = dict(cdf.generate.load_locales()[1].strings)
    assert "Object emissivity" not in de   # left English in the new file; not the point here
    with pytest.raises(CdfError) as err:
        build_bundle(out, ["wiris-pro"], base_url=BASE, cat=cat)
    msg = str(err.value)
    assert "wiris-pro" in msg and "definition_version" in msg and "wiris-pro.yaml" in msg
    assert snapshot(out) == published   # nothing changed on disk

    def bump(data):
        data["models"][0]["definition_version"] = 2
    edit_yaml(tables / "wiris-pro.yaml", bump)
    result = build_bundle(out, ["wiris-pro"], base_url=BASE, cat=load_catalogue(tables))
    assert result.written == ("workswell_wiris-pro_v2.xml",)
    rows = json.loads((out / MANIFEST).read_text())["models"]
    assert [(r["id"], r["version"]) for r in rows if r["id"] == "wiris-pro"] == [("wiris-pro", 1), ("wiris-pro", 2)]
    assert (out / "workswell_wiris-pro_v1.xml").read_bytes() == published["workswell_wiris-pro_v1.xml"]


def test_a_different_file_under_a_published_name_is_refused(tmp_path):
    out = tmp_path / "cdf"
    build_bundle(out, ["wiris-security"], base_url=BASE, xz=True)
    (out / "workswell_wiris-security_v1.xml.xz").write_bytes(b"\xfd7zXZ\x00 something else")
    before = snapshot(out)
    with pytest.raises(CdfError, match="wiris-security.*already exists.*\n.*definition_version"):
        build_bundle(out, ["wiris-security"], base_url=BASE, xz=True)
    assert snapshot(out) == before


def test_a_manifest_entry_with_another_sha256_for_the_version_is_refused(tmp_path):
    out = tmp_path / "cdf"
    build_bundle(out, ["wiris-agro"], base_url=BASE)
    manifest = json.loads((out / MANIFEST).read_text())
    manifest["models"][0]["sha256"] = "0" * 64
    (out / MANIFEST).write_text(json.dumps(manifest))
    (out / "workswell_wiris-agro_v1.xml").unlink()   # only the manifest remembers the published content
    before = snapshot(out)
    with pytest.raises(CdfError, match="wiris-agro: definition version 1 is already published"):
        build_bundle(out, ["wiris-agro"], base_url=BASE)
    assert snapshot(out) == before


def test_an_unreadable_manifest_is_an_error_not_overwritten(tmp_path):
    out = tmp_path / "cdf"
    out.mkdir()
    (out / MANIFEST).write_text("{not json")
    with pytest.raises(CdfError, match="existing manifest"):
        build_bundle(out, ["wiris-pro"])
    assert snapshot(out) == {MANIFEST: b"{not json"}


# ------------------------------------------------------------------------------------------ refusals

def test_a_uri_longer_than_139_characters_is_refused_and_nothing_written(tmp_path):
    out = tmp_path / "cdf"
    base = "http://example.com/" + "x" * (URI_MAX - len("http://example.com/") - len("/workswell_wiris-pro_v1.xml") + 1)
    assert len(definition_uri(base, "workswell_wiris-pro_v1.xml")) == URI_MAX + 1
    with pytest.raises(CdfError, match=r"wiris-pro: URI is 140 characters"):
        build_bundle(out, ["wiris-pro"], base_url=base)
    assert not out.exists()
    base_ok = base[:-1]
    build_bundle(out, ["wiris-pro"], base_url=base_ok)   # exactly 139 fits
    with pytest.raises(CdfError, match="URI is 142"):     # the .xz twin's URI must fit too
        build_bundle(tmp_path / "x", ["wiris-pro"], base_url=base_ok, xz=True)


@pytest.mark.parametrize("base,text", [
    ("ftp://host/cdf", "must start with"), ("mavlinkftp://cdf", "must start with"), ("file:///tmp", "must start with"),
    ("http://h/a b", "without spaces"), ("http://h/c?x=1", "query or fragment"),
    # these four were written into every URI of the bundle
    ("http://[::1/cdf", "malformed: Invalid IPv6 URL"), ("http://h:99999/cdf", "malformed: Port out of range"),
    ("http:///cdf", "names no host"), ("http://h/%zz", "% not followed by two hex digits"),
])
def test_bad_base_urls_are_refused(tmp_path, base, text):
    with pytest.raises(CdfError, match=re.escape(f"base URL {base!r}") + ".*" + re.escape(text)):
        build_bundle(tmp_path / "o", ["wiris-pro"], base_url=base)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("base", ["http://[::1]:8000/cdf", "http://h/a%20b", "mftp://"])
def test_unusual_but_sound_base_urls_are_taken(tmp_path, base):
    build_bundle(tmp_path / "o", ["wiris-pro"], base_url=base)
    assert (tmp_path / "o" / "manifest.json").exists()


def test_rededge_named_explicitly_is_an_error_with_a_hint(tmp_path):
    with pytest.raises(CdfError) as err:
        build_bundle(tmp_path / "o", ["wiris-pro", "rededge-mx"])
    assert "rededge-mx" in str(err.value) and "--all" in err.value.hint
    assert not (tmp_path / "o").exists()


def test_unknown_model_and_no_model_are_errors(tmp_path):
    with pytest.raises(CdfError, match="did you mean 'wiris-pro'"):
        build_bundle(tmp_path / "o", ["wiris-pr"])
    with pytest.raises(CdfError, match="no model named"):
        build_bundle(tmp_path / "o", [])


def test_a_file_failing_strict_validation_stops_the_whole_build(tmp_path, monkeypatch):
    pytest.importorskip("cdf.validation")
    real = cdf.generate.definition_xml

    def broken(camera, locales=None):
        data = real(camera, locales)
        if camera.id == "wiris-security":   # the MAVSDK crash case of reference §D: an empty description
            data = data.replace(b"<description>Storage</description>", b"<description></description>")
        return data
    monkeypatch.setattr(cdf.generate, "definition_xml", broken)
    out = tmp_path / "cdf"
    with pytest.raises(CdfError, match="wiris-security: the generated definition fails the strict validation"):
        build_bundle(out, all_models=True, base_url=BASE)
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".wiris-build-")]
    build_bundle(out, ["wiris-pro"], base_url=BASE)
    before = snapshot(out)
    with pytest.raises(CdfError):
        build_bundle(out, all_models=True, base_url=BASE)
    assert snapshot(out) == before


def test_a_failure_while_moving_files_rolls_back(tmp_path, monkeypatch):
    out = tmp_path / "cdf"
    build_bundle(out, ["wiris-pro"], base_url=BASE)
    before = snapshot(out)
    real_replace = os.replace

    def failing(src, dst):
        if Path(dst).name == MANIFEST:
            raise OSError(28, "No space left on device")
        return real_replace(src, dst)
    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(CdfError, match="cannot write the bundle: No space left on device") as ei:
        build_bundle(out, all_models=True, base_url=BASE)
    assert "nothing was changed" in ei.value.hint
    assert snapshot(out) == before
    assert not [p for p in out.iterdir() if p.name.startswith(".wiris-build-")]


def test_output_path_that_is_a_file_is_refused(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(CdfError, match="not a directory") as err:
        build_bundle(tmp_path / "f", ["wiris-pro"])
    assert err.value.where == str(tmp_path / "f") and "-o" in err.value.hint


@pytest.mark.parametrize("kind", ["directory", "symlink"])
def test_a_directory_or_symlink_under_a_published_name_is_refused(tmp_path, kind):
    out = tmp_path / "cdf"
    out.mkdir()
    target = out / "workswell_wiris-pro_v1.xml"
    if kind == "directory":
        target.mkdir()
    else:
        (tmp_path / "elsewhere.xml").write_bytes(cdf.generate.definition_xml(catalogue().get("wiris-pro")))
        target.symlink_to(tmp_path / "elsewhere.xml")
    with pytest.raises(CdfError, match="not a regular file") as err:
        build_bundle(out, ["wiris-pro"], base_url=BASE)
    assert err.value.where == str(target) and "move it away" in err.value.hint
    assert sorted(p.name for p in out.iterdir()) == [target.name]


def test_a_model_without_definition_version_is_refused_with_a_hint(tmp_path):
    tables = table_copy(tmp_path)
    edit_yaml(tables / "wiris-pro.yaml", lambda data: data["models"][0].pop("definition_version"))
    with pytest.raises(CdfError, match="wiris-pro has no definition_version") as err:
        build_bundle(tmp_path / "o", ["wiris-pro"], cat=load_catalogue(tables))
    assert err.value.where == "wiris-pro.yaml" and "`definition_version:`" in err.value.hint
    assert not (tmp_path / "o").exists()


def test_an_xz_twin_that_does_not_inflate_back_is_reported_as_a_bug(tmp_path, monkeypatch):
    import cdf.bundle

    monkeypatch.setattr(cdf.bundle, "xz_bytes", lambda data: lzma.compress(data + b" ", format=lzma.FORMAT_XZ))
    with pytest.raises(CdfError, match="xz twin does not inflate") as err:
        build_bundle(tmp_path / "o", ["wiris-pro"], xz=True)
    assert "report" in err.value.hint and "--xz" in err.value.hint
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("out", ["d" * 300, "/proc/wiris-bundle"])
def test_an_output_directory_the_system_refuses_is_an_error(tmp_path, out):
    before = sorted(tmp_path.iterdir())
    r = CliRunner().invoke(cli, ["cdf", "build", "--all", "-o", str(tmp_path / out)])
    assert r.exit_code == 1 and "internal error" not in r.output and "cannot" in r.output, r.output
    assert "\n  hint: " in r.output
    assert sorted(tmp_path.iterdir()) == before


# ----------------------------------------------------------------------------------------------- CLI

def test_cli_build_all_then_validate_the_result(tmp_path):
    out = tmp_path / "build" / "cdf"
    r = CliRunner().invoke(cli, ["cdf", "build", "--all", "-o", str(out), "--base-url", BASE])
    assert r.exit_code == 0, r.output
    assert "note: rededge-mx skipped" in r.output and "workswell_wiris-pro_v1.xml" in r.output
    files = sorted(str(p) for p in out.glob("*.xml"))
    assert len(files) == len(MODELS)
    v = CliRunner().invoke(cli, ["cdf", "validate", *files])
    if v.exit_code == 2 and "No such command" in v.output:
        pytest.skip("wiris cdf validate not built yet")
    assert v.exit_code == 0, v.output
    again = CliRunner().invoke(cli, ["cdf", "build", "--all", "-o", str(out), "--base-url", BASE, "--json"])
    assert again.exit_code == 0
    report = json.loads(again.output[again.output.index("{"):])
    assert report["written"] == [] and len(report["unchanged"]) == len(MODELS)


def test_cli_errors_exit_1_without_traceback(tmp_path):
    r = CliRunner().invoke(cli, ["cdf", "build", "rededge-m", "-o", str(tmp_path / "o")])
    assert r.exit_code == 1 and "Traceback" not in r.output and "has no camera definition" in r.output
    r = CliRunner().invoke(cli, ["cdf", "build", "-o", str(tmp_path / "o")])
    assert r.exit_code == 1 and "--all" in r.output
    r = CliRunner().invoke(cli, ["cdf", "build", "--all"])
    assert r.exit_code == 2   # usage: -o is required


# ------------------------------------------------------------------------------------------ concurrency

RACE_ROUNDS = 24


def _wait_for(path: Path, proc_a, proc_b) -> None:
    import time

    for _ in range(120_000):                     # up to about two minutes on a loaded machine
        if path.exists():
            return
        assert proc_a.poll() in (None, 0) and proc_b.poll() in (None, 0), "a build process died"
        time.sleep(0.001)
    raise AssertionError(f"no {path.name} from the build processes")


def test_two_concurrent_builds_of_one_version_with_different_content_cannot_both_publish(tmp_path):
    """Two real processes build wiris-pro v1 at the same moment, one from a table that labels a setting
    differently: exactly one publishes, the other is refused as a change of a published version, and the
    published file is the winner's. Half the rounds build into an existing empty folder, half create it."""
    import subprocess
    import sys

    ours = table_copy(tmp_path / "a")
    theirs = table_copy(tmp_path / "b")

    def relabel(data):
        for s in data["groups"]["radiometry"]:
            if s["key"] == "emissivity":
                s["label"] = "Object emissivity"
    edit_yaml(theirs / "workswell.yaml", relabel)
    content = {who: cdf.generate.definition_xml(load_catalogue(t).get("wiris-pro"))
               for who, t in (("a", ours), ("b", theirs))}
    assert content["a"] != content["b"]
    work = tmp_path / "work"
    work.mkdir()
    for k in range(0, RACE_ROUNDS, 2):
        (work / f"out-{k}").mkdir()
    worker = Path(__file__).with_name("bundle_race_worker.py")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).resolve().parents[2]),
                                                         os.environ.get("PYTHONPATH", "")])}
    procs = [subprocess.Popen([sys.executable, str(worker), who, str(t), str(work), str(RACE_ROUNDS)], env=env)
             for who, t in (("a", ours), ("b", theirs))]
    try:
        for k in range(RACE_ROUNDS):
            for who in "ab":
                _wait_for(work / f"ready-{k}-{who}", *procs)
            (work / f"go-{k}").touch()
            outcomes = {}
            for who in "ab":
                _wait_for(work / f"result-{k}-{who}", *procs)
                outcomes[who] = (work / f"result-{k}-{who}").read_text(encoding="utf-8")
            winners = [who for who, text in outcomes.items() if text == "ok"]
            assert len(winners) == 1, (k, outcomes)
            loser = outcomes["b" if winners == ["a"] else "a"]
            assert re.search(r"wiris-pro: (definition version 1 is already published|"
                             r"workswell_wiris-pro_v1.xml already exists) with different content", loser), (k, loser)
            out = work / f"out-{k}"
            assert (out / "workswell_wiris-pro_v1.xml").read_bytes() == content[winners[0]]
            rows = json.loads((out / MANIFEST).read_text())["models"]
            assert [r["sha256"] for r in rows] == [hashlib.sha256(content[winners[0]]).hexdigest()]
            assert sorted(p.name for p in out.iterdir()) == sorted([MANIFEST, "workswell_wiris-pro_v1.xml"])
        for p in procs:
            assert p.wait(60) == 0
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait(5)
