"""The link options (--connect, --signing-key) are one definition (wiris_tools.cli.options) in every command
that talks MAVLink: the same name, parameter, type and default everywhere, and the same help wherever the
meaning is the same (an emulator's --connect shows the other end's connection strings)."""

from __future__ import annotations

import click

from wiris_tools.cli import cli
from wiris_tools.cli.options import LINK_EXAMPLES, SIGNING_KEY_HELP


def _commands(group: click.Group, path: str):
    for name, command in group.commands.items():
        if isinstance(command, click.Group):
            yield from _commands(command, f"{path} {name}")
        else:
            yield f"{path} {name}", command


def _option(command: click.Command, flag: str) -> click.Option | None:
    return next((p for p in command.params if isinstance(p, click.Option) and flag in p.opts), None)


def test_every_link_command_has_the_shared_connect_and_signing_key():
    linked = {path: command for path, command in _commands(cli, "wiris") if _option(command, "--connect")}
    assert {"wiris emulate", "wiris mission upload", "wiris mission download", "wiris camera info", "wiris camera apply"} <= set(linked)
    for path, command in linked.items():
        connect, key = _option(command, "--connect"), _option(command, "--signing-key")
        assert key is not None, path
        assert (connect.name, connect.required, connect.metavar) == ("url", True, "URL"), path
        assert (key.name, key.default, type(key.type), key.type.dir_okay) == ("signing_key", None, click.Path,
                                                                                 False), path
        assert key.help == SIGNING_KEY_HELP, path
        if path == "wiris emulate":
            assert connect.help.startswith("pymavlink connection string: udpout:") and "towards a GCS" in connect.help
        elif path == "wiris sim vehicle":      # a vehicle's end too: its examples are the ground station's peer
            assert connect.help.startswith("pymavlink connection string: udpin:") and "towards a GCS" in connect.help
        else:
            assert connect.help == f"pymavlink connection string: {LINK_EXAMPLES}.", path
