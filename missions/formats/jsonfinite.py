"""JSON has no NaN or infinity (RFC 8259): json.dumps would write them anyway, and strict readers (jq,
JavaScript's JSON.parse, QGroundControl) refuse the whole document. Shared by the compiler's JSON files and
the CLI's JSON output of radio data."""

from __future__ import annotations

import math
from typing import Any


def finite(obj: Any) -> Any:
    """`obj` with every NaN or infinite float, at any depth of dicts, lists and tuples, replaced by None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj
