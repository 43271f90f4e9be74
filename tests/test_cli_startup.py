"""`wiris --help` must stay fast: no heavy library is imported to print it."""

import json
import re
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from cli_child import CHILD_ENV, wait_stopped  # noqa: E402

HEAVY = ("pymavlink", "lxml", "shapely", "pyproj", "xmlschema", "mavsdk", "jsonschema", "PIL")


def test_help_imports_no_heavy_module():
    code = (
        "import sys, json\n"
        "from click.testing import CliRunner\n"
        "from wiris_tools.cli import cli\n"
        "r = CliRunner().invoke(cli, ['--help'])\n"
        "assert r.exit_code == 0, r.output\n"
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_help_lists_groups():
    from click.testing import CliRunner

    from wiris_tools.cli import cli

    result = CliRunner().invoke(cli, ["--help"])
    assert result.exit_code == 0
    assert "cdf" in result.output


def _console_script(tmp_path) -> Path:
    """The `wiris` script as pip writes it for pyproject.toml's entry point."""
    module, func = tomllib.loads(Path(__file__).parents[1].joinpath("pyproject.toml").read_text())[
        "project"]["scripts"]["wiris"].split(":")
    script = tmp_path / "wiris"
    script.write_text(f"import re\nimport sys\nfrom {module} import {func}\nif __name__ == '__main__':\n"
                      f"    sys.argv[0] = re.sub(r'(-script\\.pyw|\\.exe)?$', '', sys.argv[0])\n"
                      f"    sys.exit({func}())\n")
    return script


def _start(script: Path, *args: str, sigint=signal.SIG_DFL) -> subprocess.Popen:
    # SIGINT at its default in the child, as a terminal starts it (a test run started as a background job
    # hands its children SIGINT ignored, and Python then installs no handler)
    return subprocess.Popen([sys.executable, str(script), *(args or ["--help"])], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=CHILD_ENV, preexec_fn=lambda: signal.signal(signal.SIGINT, sigint))


_FRAME = re.compile(r'File "([^"]+)", line (\d+), in (\S+)')


def _frames_after_the_handler(stderr: str) -> list[str]:
    """The traceback frames of `stderr` that run once the entry point's Ctrl-C handler is installed: click's,
    the CLI's, and the entry point's own from the line that imports the CLI on."""
    entry = Path(__file__).parents[1] / "wiris_tools" / "entry.py"
    cli_import = next(n for n, line in enumerate(entry.read_text().splitlines(), 1)
                      if "from wiris_tools.cli import" in line)
    after = []
    for path, line, func in _FRAME.findall(stderr):
        path = path.replace("\\", "/")
        if "/click/" in path or "/wiris_tools/cli/" in path or (
                path.endswith("wiris_tools/entry.py") and func == "main" and int(line) >= cli_import):
            after.append(f"{path}:{line} in {func}")
    return after


def test_ctrl_c_at_any_moment_of_start_up_is_interrupted_and_130_not_a_traceback(tmp_path):
    """SIGINT sent to the console script at 32 moments spread over an uninterrupted `wiris --help`. Once the
    entry point runs, the answer is "interrupted" and 130; importing click and the CLI used to be a
    traceback. Before it, Python's own windows (README): killed by the signal before Python has a handler,
    "Fatal Python error" while it initialises (its site import, mostly), or a KeyboardInterrupt in the
    console script's first lines."""
    script = _console_script(tmp_path)
    durations = []
    for _ in range(2):
        started = time.monotonic()
        assert _start(script).wait(60) == 0
        durations.append(time.monotonic() - started)
    span = max(durations)
    outcomes = []
    for step in range(32):
        proc = _start(script)
        time.sleep(span * step / 32)
        proc.send_signal(signal.SIGINT)
        _, stderr = proc.communicate(timeout=60)
        assert not _frames_after_the_handler(stderr), stderr
        if proc.returncode == 130:
            assert stderr == "interrupted\n"
        elif proc.returncode not in (0, -signal.SIGINT):   # ended before the signal; killed before Python's handler
            assert "KeyboardInterrupt" in stderr, (proc.returncode, stderr)   # one of Python's own windows
        outcomes.append(proc.returncode)
    assert 130 in outcomes, outcomes   # the window the entry point closes was reached


def test_sigint_ignored_at_start_stays_ignored(tmp_path):
    """A shell starts a background job with SIGINT ignored, and Python leaves it so: the entry point's
    start-up handler must not make such a job stoppable by a Ctrl-C meant for the foreground."""
    import http.client

    (tmp_path / "bundle").mkdir()
    proc = _start(_console_script(tmp_path), "cdf", "serve", str(tmp_path / "bundle"), "--port", "0",
                  sigint=signal.SIG_IGN)
    try:
        first = proc.stderr.readline()
        assert first.startswith("serving "), first
        proc.send_signal(signal.SIGINT)
        conn = http.client.HTTPConnection("127.0.0.1", int(first.split("127.0.0.1:")[1].split("/")[0]), timeout=10)
        conn.request("GET", "/x.xml")
        assert conn.getresponse().status == 404   # still serving after the Ctrl-C
        conn.close()
        proc.send_signal(signal.SIGTERM)
        assert wait_stopped(proc) == 0 and "stopped" in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
