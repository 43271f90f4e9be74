"""The ground footprint of one photo, in metres, and the spacing arithmetic that follows from overlap.

`across_m` is the footprint width perpendicular to the flight line, `along_m` the length along it (the
compiler's optics module picks sensor width/height from the landscape/portrait setting). Same arithmetic
as QGroundControl's CameraCalc: spacing = across·(1 − side), trigger distance = along·(1 − front).
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from missions.errors import PlanError

# QGC caps overlap at 85 %; photogrammetry for 3-D models asks for up to ~90 %. Above 95 % the trigger
# distance falls below the GPS position noise of a consumer receiver, so it is almost certainly a typo.
MAX_OVERLAP_PCT = 95.0


@dataclass(frozen=True)
class Footprint:
    """Ground footprint of one image at the flight altitude."""

    across_m: float
    along_m: float

    def __post_init__(self) -> None:
        for name in ("across_m", "along_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise PlanError(f"footprint {name} must be a positive number of metres, got {v!r}",
                                hint="check the altitude / GSD and the camera optics")

    @property
    def area_m2(self) -> float:
        return self.across_m * self.along_m


def check_overlap(pct: float, name: str) -> float:
    if not (isinstance(pct, (int, float)) and math.isfinite(pct) and 0.0 <= pct <= MAX_OVERLAP_PCT):
        raise PlanError(f"{name} overlap {pct!r} % is outside 0..{MAX_OVERLAP_PCT:g} %",
                        where=f"overlap.{name}", hint="give overlap in percent, e.g. front: 80, side: 70")
    return float(pct)


def transect_spacing_m(fp: Footprint, side_pct: float) -> float:
    """Distance between neighbouring flight lines."""
    return fp.across_m * (1.0 - check_overlap(side_pct, "side") / 100.0)


def trigger_distance_m(fp: Footprint, front_pct: float) -> float:
    """Distance between consecutive photos on a line."""
    return fp.along_m * (1.0 - check_overlap(front_pct, "front") / 100.0)
