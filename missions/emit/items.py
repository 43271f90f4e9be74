"""The mission item as it travels in MISSION_ITEM_INT: the one value type shared by the compiler,
the file formats (.plan, WPL 110) and the transfer protocol.

Coordinates are kept as the wire integers (degE7) so that a file round trip or an upload read-back
compares exactly; `lat`/`lon` give degrees for people and geometry.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
import struct

# The ArduPilot dialect is a superset of common.xml: one source for every MAVLink number we emit.
from pymavlink.dialects.v20 import ardupilotmega as mavlink

MISSION_TYPE_MISSION = mavlink.MAV_MISSION_TYPE_MISSION
MISSION_TYPE_FENCE = mavlink.MAV_MISSION_TYPE_FENCE
MISSION_TYPE_RALLY = mavlink.MAV_MISSION_TYPE_RALLY
MISSION_TYPES = {"mission": MISSION_TYPE_MISSION, "fence": MISSION_TYPE_FENCE, "rally": MISSION_TYPE_RALLY}

FRAME_GLOBAL = mavlink.MAV_FRAME_GLOBAL                              # altitude AMSL
FRAME_MISSION = mavlink.MAV_FRAME_MISSION                            # params are not a position
FRAME_GLOBAL_RELATIVE_ALT = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT    # altitude above home
FRAME_GLOBAL_TERRAIN_ALT = mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT


@dataclass(frozen=True)
class MissionItem:
    """One MISSION_ITEM_INT, without seq/target (those belong to the transfer)."""

    command: int
    frame: int = FRAME_GLOBAL_RELATIVE_ALT
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0            # latitude degE7, or an integer param5 when frame is MAV_FRAME_MISSION
    y: int = 0            # longitude degE7, or an integer param6
    z: float = 0.0        # altitude in metres (frame-relative), or param7
    autocontinue: int = 1
    current: int = 0
    mission_type: int = MISSION_TYPE_MISSION
    comment: str = field(default="", compare=False)  # why the compiler emitted it; never sent

    @property
    def lat(self) -> float:
        return self.x / 1e7

    @property
    def lon(self) -> float:
        return self.y / 1e7

    @property
    def params(self) -> tuple[float, float, float, float, float, float, float]:
        """The seven COMMAND_LONG-style params (x/y as plain numbers)."""
        return (self.param1, self.param2, self.param3, self.param4, float(self.x), float(self.y), self.z)

    def with_(self, **changes) -> "MissionItem":
        return replace(self, **changes)

    def infinite_field(self) -> str | None:
        """The first float field holding +-inf, as "param1 = inf"; None when all are finite or NaN.
        MAVLink's floats carry infinities (a vehicle may hold one), JSON and QGC's WPL readers do not."""
        for name in ("param1", "param2", "param3", "param4", "z"):
            v = getattr(self, name)
            if math.isinf(v):
                return f"{name} = {v}"
        return None

    def same_on_wire(self, other: "MissionItem") -> bool:
        """Field-by-field equality as a vehicle stores it: floats compared as float32, NaN equal to NaN."""
        def f32(v: float) -> float:
            return struct.unpack("<f", struct.pack("<f", v))[0]

        def eq(a: float, b: float) -> bool:
            fa, fb = f32(a), f32(b)
            return (math.isnan(fa) and math.isnan(fb)) or fa == fb

        return (
            self.command == other.command and self.frame == other.frame and self.x == other.x
            and self.y == other.y and self.autocontinue == other.autocontinue
            and self.mission_type == other.mission_type
            and all(eq(a, b) for a, b in ((self.param1, other.param1), (self.param2, other.param2),
                                           (self.param3, other.param3), (self.param4, other.param4),
                                           (self.z, other.z)))
        )


def deg_to_e7(deg: float) -> int:
    """Degrees to the wire's degE7 integer, rounded half away from zero like QGC and MAVSDK."""
    return int(math.floor(deg * 1e7 + 0.5)) if deg >= 0 else -int(math.floor(-deg * 1e7 + 0.5))
