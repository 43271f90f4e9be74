"""`wiris ARGS` as a real child process, for the commands that run until stopped (`cdf serve`, `emulate`)."""

from __future__ import annotations

import contextlib
import subprocess
import sys
from typing import Iterator

# Python's Ctrl-C handler installed as a terminal would start the command (a test run started as a
# background job hands its children SIGINT ignored, and Python then never raises KeyboardInterrupt), then
# the console script's entry point, which ends start-up on a Ctrl-C and hands it back to the command
_CODE = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
         "from wiris_tools.entry import main; sys.argv = ['wiris'] + sys.argv[1:]; main()")


@contextlib.contextmanager
def wiris_child(*args: str) -> Iterator[subprocess.Popen]:
    """The child, its stderr a text pipe; killed on the way out if it is still running."""
    proc = subprocess.Popen([sys.executable, "-c", _CODE, *args], stderr=subprocess.PIPE, text=True)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)


def stop(proc: subprocess.Popen, signum: int) -> str:
    """Send `signum`; the child must exit 0 within 30 s. Returns the rest of its stderr."""
    proc.send_signal(signum)
    assert proc.wait(30) == 0
    return proc.stderr.read()
