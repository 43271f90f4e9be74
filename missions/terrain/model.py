"""What a plan's `terrain:` block means once its DEM is read: `Terrain`, carried by the compile and the report.

Defaults where the plan says nothing:
- tolerance: 10 % of each survey's or corridor's altitude (the issue's rule of thumb: a 10 % coarser GSD);
- climb and descent rates: a copter's auto-mission defaults (ArduCopter WPNAV_SPEED_UP 2.5 m/s, WPNAV_SPEED_DN
  1.5 m/s; PX4 MPC_Z_V_AUTO_UP 3, MPC_Z_V_AUTO_DN 1.5), a plane's TECS limits (ArduPlane TECS_CLMB_MAX and
  TECS_SINK_MAX 5 m/s; PX4 FW_T_CLMB_MAX 5); a VTOL flies its lines fixed-wing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from missions.terrain.dem import Dem

RATE_DEFAULTS_MPS = {"copter": (2.5, 1.5), "plane": (5.0, 5.0), "vtol": (5.0, 5.0)}   # (climb, descent)
TOLERANCE_FRACTION = 0.10
FRAMES = ("amsl", "terrain")


@dataclass(frozen=True)
class Terrain:
    dem: Dem
    frame: str                   # "amsl" | "terrain"
    tolerance_m: float | None    # None: TOLERANCE_FRACTION of each step's altitude
    clearance_m: float
    climb_mps: float
    descent_mps: float

    def tolerance_for(self, altitude_m: float) -> float:
        return self.tolerance_m if self.tolerance_m is not None else TOLERANCE_FRACTION * altitude_m

    def to_json(self) -> dict[str, Any]:
        return {"dem": [f.to_json() for f in self.dem.files], "frame": self.frame,
                "tolerance_m": self.tolerance_m, "clearance_m": self.clearance_m,
                "climb_mps": self.climb_mps, "descent_mps": self.descent_mps}


def rates_for(frame: str, climb_mps: float | None, descent_mps: float | None) -> tuple[float, float]:
    climb, descent = RATE_DEFAULTS_MPS.get(frame, RATE_DEFAULTS_MPS["copter"])
    return (climb_mps or climb, descent_mps or descent)
