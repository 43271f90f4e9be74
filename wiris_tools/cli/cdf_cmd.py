"""`wiris cdf ...`: camera catalogue and camera definition files."""

from __future__ import annotations

import click


@click.group()
def cdf() -> None:
    """Camera catalogue and camera definition files: list, build, validate, serve."""
