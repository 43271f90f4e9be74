"""The `wiris` command line: thin commands over library calls.

Start-up must stay fast: the command modules import only click at module level; pymavlink, lxml,
shapely and pyproj are imported inside the commands that need them (tests/test_cli_startup.py).
"""

from __future__ import annotations

import os
import sys
from typing import NoReturn

import click

from cdf.errors import WirisError
from wiris_tools.entry import raise_keyboard_interrupts


class WirisGroup(click.Group):
    """A group that turns WirisError (and anything unexpected) into a one-line message and exit 1, and a
    Ctrl-C into "interrupted" and exit 130."""

    def invoke(self, ctx: click.Context):
        try:
            raise_keyboard_interrupts()   # until here the console script's start-up handler ends the process
            return super().invoke(ctx)
        except (click.exceptions.Exit, click.ClickException, click.Abort):
            raise
        except KeyboardInterrupt:
            _interrupted(ctx)
        except BrokenPipeError:
            # the reader went away (`wiris ... | head`): not a bug of ours. Point stdout at /dev/null so that the
            # flush at exit does not raise again, and end quietly as a closed pipe ends `cat`, with a failure code.
            # (Files a command writes are complete before it prints its summary.)
            try:
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            except (OSError, ValueError):
                pass
            ctx.exit(1)
        except Exception as err:
            if _raised_by_an_interrupt(err):
                _interrupted(ctx)
            if isinstance(err, WirisError):
                click.echo(f"error: {err}", err=True)
                ctx.exit(1)
            if os.environ.get("WIRIS_DEBUG"):  # a bug of ours: still no traceback unless asked for
                raise
            click.echo(f"internal error: {type(err).__name__}: {err}\n"
                       "  hint: rerun with WIRIS_DEBUG=1 for a traceback and report it", err=True)
            ctx.exit(1)


def _interrupted(ctx: click.Context) -> NoReturn:
    click.echo("interrupted", err=True)
    ctx.exit(130)


def _raised_by_an_interrupt(err: BaseException) -> bool:
    """Whether `err` was raised while a Ctrl-C (KeyboardInterrupt) was being handled. One that lands in
    threading.Condition.wait (queue.Queue.get, Event.wait) after the lock is released and before the
    try that takes it back surfaces as RuntimeError('cannot release un-acquired lock') from the `with`
    around the wait: it is still the user's Ctrl-C, not a bug to report."""
    seen: set[int] = set()
    cause = err.__context__
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__context__
    return False


@click.group(cls=WirisGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="wiris-tools", prog_name="wiris")
def cli() -> None:
    """Tools for Workswell WIRIS and MicaSense RedEdge cameras on MAVLink drones."""


# Each group module imports only click at module level, so registering them costs little at start-up.
from wiris_tools.cli.camera_cmd import camera  # noqa: E402
from wiris_tools.cli.cdf_cmd import cdf  # noqa: E402
from wiris_tools.cli.emulate_cmd import emulate  # noqa: E402
from wiris_tools.cli.mission_cmd import mission  # noqa: E402
from wiris_tools.cli.sim_cmd import sim  # noqa: E402

for _command in (cdf, mission, camera, emulate, sim):
    cli.add_command(_command)


def main() -> None:
    cli(prog_name="wiris")


if __name__ == "__main__":
    sys.exit(main())
