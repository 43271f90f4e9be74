"""The `wiris` console script's entry point: from the moment it runs, a Ctrl-C during start-up ends with
"interrupted" and exit 130, never a traceback.

Python raises KeyboardInterrupt wherever a Ctrl-C lands, and importing click and the command modules takes
most of start-up: an interrupt there came out as a traceback through the imports. So `main` first makes a
Ctrl-C end the process at once (there is nothing to clean up while importing), then imports the CLI; the
CLI hands Ctrl-C back to KeyboardInterrupt (raise_keyboard_interrupts) once a command's own handling of it
is in place. This module imports only modules loaded before any script runs: `os` (by `site`) and
`_signal`, the C module behind `signal` (signal.py builds its enums in Python: a few ms in which a Ctrl-C
would still be a traceback).

What comes before `main` is Python's: until the interpreter installs its handler (the first ~10 ms) a
Ctrl-C ends the process as the signal's default action does, silently; while Python imports its `site`
module (the next few tens of ms with an editable install) it prints "Fatal Python error: init_import_site"
and a traceback, and the console script's own first lines can still be interrupted with a traceback.
"""

from __future__ import annotations

import _signal
import os


def _exit_interrupted(signum, frame) -> None:
    try:
        os.write(2, b"interrupted\n")
    except OSError:
        pass
    os._exit(130)   # nothing is open or half-written yet; 130 = 128 + SIGINT, as the shell reports a Ctrl-C


def main() -> None:
    # first: SIGINT left ignored (a background job) stays ignored, as Python itself leaves it
    if _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
        _signal.signal(_signal.SIGINT, _exit_interrupted)
    from wiris_tools.cli import main as cli_main

    cli_main()


def raise_keyboard_interrupts() -> None:
    """From now on a Ctrl-C raises KeyboardInterrupt again (it did before `main`): the caller handles it.
    Nothing changes where `main` did not install its start-up handler (CliRunner, tests, a background job)."""
    if _signal.getsignal(_signal.SIGINT) is _exit_interrupted:
        _signal.signal(_signal.SIGINT, _signal.default_int_handler)
