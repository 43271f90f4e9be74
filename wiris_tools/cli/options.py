"""Option types shared by the command groups."""

from __future__ import annotations

import math

import click


class FiniteRange(click.FloatRange):
    """click.FloatRange that also refuses nan and inf: float() accepts both, and nan passes every range
    test (its comparisons are all false), so `--timeout nan` waited for ever and `--timeout inf` reached
    the socket layer as an internal error."""

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number.", param, ctx)
        return number


# -- the link options of every command that talks MAVLink (camera, mission upload/download, emulate) ---------

LINK_EXAMPLES = "udpin:127.0.0.1:14550, udpout:HOST:PORT, tcp:HOST:PORT, /dev/ttyUSB0,57600"
SIGNING_KEY_HELP = ("MAVLink 2 signing key file: 64 hex characters (the 32-byte key) or a passphrase (SHA-256, as "
                    "MAVProxy's `signing setup`).")


def connect_option(examples: str = LINK_EXAMPLES):
    """--connect URL (required, passed as `url`). `examples`: the connection strings the help shows - an
    emulator's are the other end's (udpout towards a ground station, udpin to be found)."""
    return click.option("--connect", "url", required=True, metavar="URL",
                        help=f"pymavlink connection string: {examples}.")


def signing_key_option():
    """--signing-key FILE (default None: unsigned), read with wiris_tools.signing.load_signing_key."""
    return click.option("--signing-key", type=click.Path(dir_okay=False), default=None, help=SIGNING_KEY_HELP)
