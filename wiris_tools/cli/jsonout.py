"""JSON on standard output for data that came over the radio."""

from __future__ import annotations

import json
import math

import click


def finite(obj):
    """`obj` with every NaN or infinite float replaced by None. Cameras and vehicles send NaN for
    "unknown" (and a broken one may send inf); json.dumps would write them as NaN or Infinity, which
    is not JSON: jq, JavaScript's JSON.parse and most other readers refuse the whole document."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj


def echo_json(obj, indent: int | None = None) -> None:
    click.echo(json.dumps(finite(obj), indent=indent, allow_nan=False, default=str))
