"""Software-in-the-loop autopilots for tests, benchmarks and `wiris sim`: one interface, one backend per firmware.

    from wiris_tools.sitl import SitlOptions, find_sitl_dir, start_sitl

    with start_sitl("ardupilot", find_sitl_dir(), SitlOptions(speedup=20, camera_port=port)) as sitl:
        sitl.wait_ready()                       # EKF using GPS and pre-arm checks passing, not a fixed sleep
        sitl.set_params({"CAM1_TYPE": 6}, reboot=True)
        # upload with our tools through sitl.gcs_url (a second ground-station port)
        sitl.arm_and_start_mission()
        sitl.wait_mission_end(timeout=120)
    sitl.dataflash_logs(), sitl.tlog              # kept in sitl.workdir after close()

A backend starts the firmware's process in its own process group and working directory, on an instance
nobody else on this machine holds (a lock file per instance plus a bind test of its ports), keeps one
monitoring link of its own (which writes the tlog), and stops every process it started on close(), also when
the test using it fails. PX4 slots in as a second entry of BACKENDS with the same methods.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Protocol

from wiris_tools.errors import LinkError

# The variable that names a SITL folder (ArduPilot's: bin/arducopter, bin/arduplane, run-sitl).
SITL_DIR_VARIABLE = "WIRIS_SITL_DIR"


@dataclass(frozen=True)
class SitlOptions:
    """How to start one simulated vehicle."""

    vehicle: str = "copter"                 # copter | plane
    speedup: float = 20.0                   # simulated seconds per wall-clock second
    camera_port: int | None = None          # a UDP port on 127.0.0.1 where a camera listens (the camera link)
    camera_serial: int = 2                  # the autopilot serial port the camera is on (1 or 2; TELEM2 stock)
    home: tuple[float, float, float, float] = (50.08, 14.42, 262.0, 0.0)   # lat, lon, alt AMSL m, yaw deg
    workdir: Path | None = None             # None: a fresh temporary folder
    params: Mapping[str, float] = field(default_factory=dict)   # set (PARAM_SET) before the first use
    wipe: bool = True                       # start from the firmware's defaults


class Sitl(Protocol):
    """What every firmware backend offers (see the module docstring)."""

    firmware: str
    workdir: Path
    gcs_url: str          # a pymavlink URL for ground-station tools (upload, camera apply), not the monitor's
    tlog: Path            # what the monitor link received, in tlog format (8-byte time stamp + frame)

    def wait_ready(self, timeout: float = 60.0) -> None: ...
    def set_params(self, params: Mapping[str, float], *, reboot: bool = False,
                   skip_unknown: bool = False) -> list[str]: ...
    def get_param(self, name: str) -> float | None: ...
    def arm_and_start_mission(self, timeout: float = 60.0) -> None: ...
    def wait_mission_end(self, timeout: float = 300.0) -> None: ...
    def dataflash_logs(self) -> list[Path]: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Sitl": ...
    def __exit__(self, *exc: object) -> None: ...


def find_sitl_dir(explicit: str | os.PathLike | None = None, *, near: Path | None = None) -> Path | None:
    """The SITL folder: `explicit`, else $WIRIS_SITL_DIR, else ../shared/sitl beside the checkout `near`
    (a folder inside it); None when none of them holds a SITL build."""
    candidates: list[Path] = []
    if explicit:
        candidates.append(Path(explicit))
    elif os.environ.get(SITL_DIR_VARIABLE):
        candidates.append(Path(os.environ[SITL_DIR_VARIABLE]))
    elif near is not None:
        candidates += [p / "shared" / "sitl" for p in (near, *near.parents)][:4]
    for c in candidates:
        if (c / "run-sitl").is_file() and (c / "bin").is_dir():
            return c.resolve()
    return None


def missing_sitl_reason() -> str:
    return (f"ArduPilot SITL not found: set {SITL_DIR_VARIABLE} to a folder holding run-sitl and "
            "bin/arducopter (see ../shared/sitl/README.md for how to build one)")


def start_sitl(firmware: str, sitl_dir: Path | None, options: SitlOptions = SitlOptions()) -> Sitl:
    """Start the `firmware` SITL found in `sitl_dir`; LinkError with a hint when it cannot."""
    if sitl_dir is None:
        raise LinkError(missing_sitl_reason(), hint=f"pass --sitl-dir DIR or set {SITL_DIR_VARIABLE}")
    if firmware == "ardupilot":
        from wiris_tools.sitl.ardupilot import ArduPilotSitl
        return ArduPilotSitl(sitl_dir, options)
    raise LinkError(f"no SITL backend for firmware {firmware!r}", hint="use ardupilot")
