"""The `wiris` command line: thin commands over library calls.

Start-up must stay fast: the command modules import only click at module level; pymavlink, lxml,
shapely and pyproj are imported inside the commands that need them (tests/test_cli_startup.py).
"""

from __future__ import annotations

import os
import sys

import click

from cdf.errors import WirisError


class WirisGroup(click.Group):
    """A group that turns WirisError (and anything unexpected) into a one-line message and exit 1."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except WirisError as err:
            click.echo(f"error: {err}", err=True)
            ctx.exit(1)
        except (click.exceptions.Exit, click.ClickException, click.Abort):
            raise
        except KeyboardInterrupt:
            click.echo("interrupted", err=True)
            ctx.exit(130)
        except Exception as err:  # a bug of ours: still no traceback unless asked for
            if os.environ.get("WIRIS_DEBUG"):
                raise
            click.echo(f"internal error: {type(err).__name__}: {err}\n"
                       "  hint: rerun with WIRIS_DEBUG=1 for a traceback and report it", err=True)
            ctx.exit(1)


@click.group(cls=WirisGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="wiris-tools", prog_name="wiris")
def cli() -> None:
    """Tools for Workswell WIRIS and MicaSense RedEdge cameras on MAVLink drones."""


# Each group module imports only click at module level, so registering them costs little at start-up.
from wiris_tools.cli.camera_cmd import camera  # noqa: E402
from wiris_tools.cli.cdf_cmd import cdf  # noqa: E402
from wiris_tools.cli.emulate_cmd import emulate  # noqa: E402
from wiris_tools.cli.mission_cmd import mission  # noqa: E402

for _command in (cdf, mission, camera, emulate):
    cli.add_command(_command)


def main() -> None:
    cli(prog_name="wiris")


if __name__ == "__main__":
    sys.exit(main())
