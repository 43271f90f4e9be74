"""How long-running commands (`cdf serve`, `emulate`) stop: Ctrl-C, or SIGTERM like it."""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Iterator


@contextlib.contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """Within the block, SIGTERM (what `kill`, systemd and docker send) raises KeyboardInterrupt like Ctrl-C,
    so the command's own stop path runs: it closes what it holds, says "stopped" and exits 0. (SIGINT
    cannot be relied on alone: a shell starts background jobs with SIGINT ignored, and Python then never
    raises KeyboardInterrupt.) Only the main thread can set handlers; elsewhere the block runs as is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
