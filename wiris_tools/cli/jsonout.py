"""JSON on standard output for data that came over the radio."""

from __future__ import annotations

import click


def echo_json(obj, indent: int | None = None) -> None:
    """Cameras and vehicles send NaN for "unknown" (and a broken one may send inf): written as null."""
    import json  # here, not at module level: `wiris --help` imports this module (tests/test_cli_startup.py)

    from missions.formats.jsonfinite import finite

    click.echo(json.dumps(finite(obj), indent=indent, allow_nan=False, default=str))
