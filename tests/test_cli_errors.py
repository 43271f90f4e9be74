"""How the `wiris` group answers what a command raises: a WirisError is its message and hint, anything
else a one-line internal error, both exit 1; a Ctrl-C is "interrupted" and exit 130, wherever it lands."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from interrupts import InterruptAt, finishes
from wiris_tools.cli import WirisGroup
from wiris_tools.errors import LinkError


def run(body) -> tuple[int, str]:
    """Run `body` as a command of a WirisGroup, as `wiris` would; (exit code, stderr)."""
    group = WirisGroup("wiris")
    group.command("go")(body)
    result = CliRunner().invoke(group, ["go"])
    return result.exit_code, result.stderr


def test_wiris_error_is_one_line_and_exit_1():
    def body():
        raise LinkError("no HEARTBEAT", where="udpin:127.0.0.1:1", hint="check the link")

    code, err = run(body)
    assert (code, err) == (1, "error: udpin:127.0.0.1:1: no HEARTBEAT\n  hint: check the link\n")


def test_a_bug_is_an_internal_error_without_traceback(monkeypatch):
    monkeypatch.delenv("WIRIS_DEBUG", raising=False)

    def body():
        raise RuntimeError("cannot release un-acquired lock")

    code, err = run(body)
    assert code == 1
    assert err.startswith("internal error: RuntimeError") and "Traceback" not in err


@pytest.mark.parametrize("raised", [RuntimeError("cannot release un-acquired lock"), LinkError("link closed")])
def test_an_error_raised_while_a_ctrl_c_unwinds_is_the_ctrl_c(raised):
    def body():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise raised

    assert run(body) == (130, "interrupted\n")


def test_ctrl_c_anywhere_in_an_inbox_wait_exits_130_and_leaves_the_inbox_working():
    """Inboxes were queue.Queue, whose get() waits in Python through threading.Condition. A Ctrl-C landing
    there after the lock was released made the `with` around the wait raise RuntimeError('cannot release
    un-acquired lock'), reported as an internal error (exit 1); one landing just after the lock was taken
    left it held, and the next get() blocked for ever. The interrupt is raised at each place of a wait
    where Python checks for signals, in turn: every one must exit 130, and the inbox must still answer
    afterwards."""
    from wiris_tools.link import Link

    with Link("udpin:127.0.0.1:0") as link:
        n = 0
        while True:
            with link.inbox(types=["CAMERA_INFORMATION"]) as box:  # nothing arrives: every get() waits
                at = InterruptAt(n)

                def body():
                    with at:
                        box.get(timeout=0.01)

                code, err = run(body)
                if at.fired:
                    assert (code, err) == (130, "interrupted\n"), f"interrupt at signal check {n} of the wait"
                else:
                    assert code == 0
                assert finishes(box.get, 0.01), f"the inbox hangs after an interrupt at signal check {n}"
            if not at.fired:
                break
            n += 1
    assert n >= 1  # the wait was interrupted before it returned uninterrupted


@pytest.mark.parametrize("args", [
    ["camera", "info", "--connect", "udpout:127.0.0.1:9", "--wait", "nan"],        # waited for ever
    ["camera", "capture", "--connect", "udpout:127.0.0.1:9", "--interval", "inf"],
    ["cdf", "validate", "http://127.0.0.1:9/x.xml", "--timeout", "nan"],          # internal error
    ["cdf", "validate", "http://127.0.0.1:9/x.xml", "--timeout", "inf"],          # internal error
    ["mission", "download", "-o", "x.plan", "--connect", "udpout:127.0.0.1:9", "--timeout", "NaN"],  # for ever
    ["emulate", "wiris-pro", "--connect", "udpin:127.0.0.1:0", "--storage-mib", "nan"],
    ["emulate", "wiris-pro", "--connect", "udpin:127.0.0.1:0", "--duration", "inf"],  # ran for ever
])
def test_a_number_option_refuses_nan_and_inf_as_a_usage_error(args, tmp_path, monkeypatch):
    from wiris_tools.cli import cli

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 2
    assert f"'{args[-1]}' is not a finite number" in result.stderr and "Traceback" not in result.output
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [["cdf", "models"], ["mission", "schema"]])
def test_a_reader_that_goes_away_is_not_an_internal_error(args):
    """`wiris cdf models | head -0`: the pipe's reader is gone before the command writes. A closed pipe ends the
    command quietly (exit 1, as the pipe's end), not with "internal error" or Python's "Exception ignored"."""
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "from wiris_tools.cli import main; main()", *args],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    child.stdout.close()                       # no reader from the start: every write is EPIPE
    _out, err = child.communicate(timeout=60)
    assert child.returncode == 1, err
    assert err == b"", err
