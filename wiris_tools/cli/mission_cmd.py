"""`wiris mission ...`: compile capture plans, check and preview them, move missions to and from a vehicle."""

from __future__ import annotations

import click


@click.group()
def mission() -> None:
    """Capture plans to missions: schema, compile, check, preview, upload, download."""
