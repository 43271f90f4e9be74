"""What a mission-file reader repaired or skipped on the way (pure).

A reader takes what QGroundControl, pymavlink's MAVWPLoader or MAVSDK take, and says so for each thing it
did not read verbatim: a QGC 3.x save's version-1 geoFence it skipped, a WPL row it renumbered. The CLI
prints each note as `warning: WHERE: MESSAGE`.
"""

from __future__ import annotations

from typing import NamedTuple


class ReadNote(NamedTuple):
    where: str      # NAME:LINE (WPL) or NAME: json.path (.plan)
    message: str

    def __str__(self) -> str:
        return f"{self.where}: {self.message}"
