"""Every file a user names is read through one capped reader (cdf.userfile): a regular file of at most its
cap, or standard input where a command takes it on purpose ("-", /dev/stdin). A pipe, a device, a FIFO or a
directory is refused at once with the package's error, the path and a hint; more than the cap is refused
after reading cap + 1 bytes, whatever stat() said."""

from __future__ import annotations

import dataclasses
import os
import shutil
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from cdf.errors import CdfError, WirisError
from cdf.userfile import UserFile, read_user_file
from missions.errors import PlanError
from wiris_tools.errors import LinkError

REPO = Path(__file__).resolve().parents[1]


def _plan(p):
    from missions.plan import load_plan
    return load_plan(p)


def _geojson(p):
    from missions.geometry.area import read_geojson
    return read_geojson(Path(p))


def _kml(p):
    from missions.geometry.area import read_kml
    return read_kml(Path(p))


def _qgc_plan(p):
    from missions.formats.planfile import load_plan
    return load_plan(p)


def _wpl(p):
    from missions.formats.wpl import load_wpl
    return load_wpl(p)


def _setup(p):
    from wiris_tools.camera_client import load_setup
    return load_setup(p)


def _key(p):
    from wiris_tools.signing import load_signing_key
    return load_signing_key(p)


def _definition(p):
    from cdf.validation.engine import validate_source
    return validate_source(p)


# (loader, the error it raises, a file name its suffix dispatch accepts)
LOADERS = {"capture plan": (_plan, PlanError, "p.yaml"), "geojson area": (_geojson, PlanError, "a.geojson"),
           "kml area": (_kml, PlanError, "a.kml"),
           "qgc plan": (_qgc_plan, PlanError, "m.plan"), "waypoints": (_wpl, PlanError, "m.waypoints"),
           "setup file": (_setup, LinkError, "f.setup.json"), "signing key": (_key, LinkError, "k.key"),
           "camera definition": (_definition, CdfError, "c.xml")}


def _within(fn, timeout_s: float = 20.0):
    """fn() in a daemon thread: its exception (or result) within timeout_s, or an AssertionError when it
    blocks (a FIFO opened for reading waits for a writer)."""
    out: list = []

    def run():
        try:
            out.append(fn())
        except BaseException as err:   # noqa: BLE001 (handed to the test)
            out.append(err)
    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(timeout_s)
    assert out, f"still reading after {timeout_s} s"
    return out[0]


@pytest.mark.parametrize("loader,error,name", LOADERS.values(), ids=LOADERS)
def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path, loader, error, name):
    fifo = tmp_path / name
    os.mkfifo(fifo)
    err = _within(lambda: loader(fifo))
    assert isinstance(err, error), err
    assert err.message == "is a pipe (FIFO), not a file" and err.where == str(fifo) and err.hint


@pytest.mark.parametrize("loader,error,name", LOADERS.values(), ids=LOADERS)
def test_a_directory_is_a_directory(tmp_path, loader, error, name):
    d = tmp_path / name
    d.mkdir()
    with pytest.raises(error) as err:
        loader(d)
    assert err.value.message == "is a directory, not a file" and err.value.where == str(d) and err.value.hint


@pytest.mark.parametrize("loader,error", [(v[0], v[1]) for v in LOADERS.values()], ids=LOADERS)
def test_dev_zero_is_refused_before_a_byte_is_read(loader, error):
    # stat() says 0 bytes; a stat-then-read reader read until MemoryError
    with pytest.raises(error) as err:
        loader("/dev/zero")
    assert err.value.message == "is a character device, not a file" and err.value.where == "/dev/zero"


def test_a_socket_is_refused(tmp_path):
    path = tmp_path / "s.yaml"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
        with pytest.raises(PlanError, match="is a socket, not a file"):
            _plan(path)


def test_the_cap_is_read_not_stated(tmp_path):
    kind = UserFile("test file", 10, PlanError, hint="h", size_hint="smaller")
    f = tmp_path / "f"
    f.write_bytes(b"x" * 10)
    assert read_user_file(f, kind) == b"x" * 10                     # exactly the cap is fine
    f.write_bytes(b"x" * 11)
    with pytest.raises(PlanError) as err:
        read_user_file(f, kind)
    assert err.value.message == "the test file is larger than 10 bytes" and err.value.hint == "smaller"
    # a caller that reports the excess itself gets cap + 1 bytes, no more
    f.write_bytes(b"x" * 1000)
    assert read_user_file(f, dataclasses.replace(kind, size_hint=None)) == b"x" * 11


def test_standard_input_only_where_the_caller_takes_it(tmp_path, monkeypatch):
    import io

    kind = UserFile("test file", 10, PlanError, hint="h", stdin_ok=True)
    for name in ("-", "/dev/stdin"):
        monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b"abc")))
        assert read_user_file(name, kind) == b"abc"
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b"y\n" * 100)))
    with pytest.raises(PlanError, match="larger than 10 bytes") as err:
        read_user_file("-", kind)
    assert err.value.where == "<stdin>"
    monkeypatch.chdir(tmp_path)   # "-" is a file name where standard input is not taken
    with pytest.raises(PlanError, match="no such file"):
        read_user_file("-", dataclasses.replace(kind, stdin_ok=False))


def test_the_error_family_is_the_callers():
    for _loader, error, _name in LOADERS.values():
        assert issubclass(error, WirisError)


def _child(code: str, cwd: Path = REPO) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=cwd, env=env)


def test_an_endless_pipe_into_dev_stdin_stops_at_the_cap():
    """`yes 'a: 1' | wiris mission check /dev/stdin` read until 4 GB: now 1 MB + 1 byte, then a PlanError."""
    child = _child("from wiris_tools.cli import main; import sys; sys.argv = ['wiris', 'mission', 'check', "
                   "'/dev/stdin']; main()")
    written = 0

    def feed():
        nonlocal written
        try:
            while written < 200 * 2**20:      # bounded: a reader without a cap fails the test, not the machine
                child.stdin.write(b"a: 1\n" * 8192)
                written += 5 * 8192
        except (BrokenPipeError, ValueError):
            return
        child.stdin.close()
    t = threading.Thread(target=feed, daemon=True)
    t.start()
    err = child.stderr.read()
    child.stdout.read()
    child.wait(120)
    t.join(60)
    assert child.returncode == 1, err
    assert b"<stdin>: the plan is larger than 1000000 bytes" in err, err
    assert written < 20 * 2**20       # the child stopped reading at the cap (pipe buffers hold the rest)


def test_a_plan_on_standard_input_compiles_with_paths_relative_to_the_current_directory(tmp_path):
    plan = (REPO / "tests" / "missions" / "plans" / "good.yaml").read_text()
    shutil.copytree(REPO / "tests" / "missions" / "plans" / "areas", tmp_path / "areas")
    child = _child("from missions.plan import load_plan; p = load_plan('-'); print(p.name, p.path, p.base_dir)",
                   cwd=tmp_path)
    out, err = child.communicate(plan.encode(), timeout=120)
    assert child.returncode == 0, err
    assert out.decode().split() == ["good-survey", "<stdin>", str(tmp_path)]
