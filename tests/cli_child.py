"""`wiris ARGS` as a real child process, for the commands that run until stopped (`cdf serve`, `emulate`)."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Iterator

# Python's Ctrl-C handler installed as a terminal would start the command (a test run started as a
# background job hands its children SIGINT ignored, and Python then never raises KeyboardInterrupt), then
# the console script's entry point, which ends start-up on a Ctrl-C and hands it back to the command
_CODE = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
         "from wiris_tools.entry import main; sys.argv = ['wiris'] + sys.argv[1:]; main()")

# faulthandler in every child: a child that does not stop is sent SIGABRT and prints where each thread was
CHILD_ENV = {**os.environ, "PYTHONFAULTHANDLER": "1"}


@contextlib.contextmanager
def wiris_child(*args: str) -> Iterator[subprocess.Popen]:
    """The child, its stderr a text pipe; killed on the way out if it is still running."""
    proc = subprocess.Popen([sys.executable, "-c", _CODE, *args], stderr=subprocess.PIPE, text=True, env=CHILD_ENV)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)


def signal_state(pid: int) -> str:
    """The kernel's view of a process's signals and state (/proc/PID/status): what was pending, blocked,
    ignored or caught when it did not stop."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError as err:
        return f"(no /proc/{pid}/status: {err})"
    return "; ".join(line for line in lines if line.startswith(("State", "Threads", "Sig", "Shd")))


def wait_stopped(proc: subprocess.Popen, timeout_s: float = 30) -> int:
    """proc's exit code; if it is still running after `timeout_s`, the test fails with its signal state and
    every thread's stack (faulthandler on SIGABRT), so a child that does not stop says where it hangs."""
    try:
        return proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        state = signal_state(proc.pid)
        proc.send_signal(signal.SIGABRT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
        stderr = proc.stderr.read() if proc.stderr else ""
        raise AssertionError(f"still running {timeout_s:.0f} s after the signal; {state}\n{stderr}") from None


def stop(proc: subprocess.Popen, signum: int) -> str:
    """Send `signum`; the child must exit 0 within 30 s. Returns the rest of its stderr."""
    proc.send_signal(signum)
    assert wait_stopped(proc) == 0
    return proc.stderr.read()
