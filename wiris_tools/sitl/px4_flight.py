"""Fly a compiled plan in PX4 SITL with the WIRIS emulator on the payload link, as a pilot would: NAME.params
given to PX4 at boot (its `param set` lines; names this build lacks are reported), NAME.plan uploaded with
read-back, AUTO.MISSION, arm, fly to landing, and keep what the camera took and what reached it.

    with fly_compiled_px4(px4_dir, out_dir, "solar-park") as flight:
        flight.photos              # the emulator's Captured list, in order
        flight.commands            # (command, target_system, target_component) of each camera command it heard
        flight.sitl.ulogs()        # the flight's ULog (kept in the working directory)
"""

from __future__ import annotations

import math
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Mapping

from wiris_tools.sitl import SitlOptions, start_sitl
from wiris_tools.sitl.flight import read_params_file


@dataclass(frozen=True)
class HeardCommand:
    command: int
    target_system: int
    target_component: int
    confirmation: int
    src_component: int
    param4: float          # camera_trigger's IMAGE_START_CAPTURE numbers its shots here (CAMERA_TRIGGER.hpp)


@dataclass
class Px4Flight:
    sitl: object
    emulator: object
    unknown_params: list[str]
    upload: dict
    photos: list = field(default_factory=list)
    commands: list[HeardCommand] = field(default_factory=list)

    def trigger_shots(self, component: int = 100) -> int:
        """How many shots PX4's camera_trigger fired at `component`: the distinct sequence numbers of its
        IMAGE_START_CAPTURE commands (a resent command keeps its number)."""
        from pymavlink.dialects.v20 import ardupilotmega as mavlink2
        return len({c.param4 for c in self.commands
                    if c.command == mavlink2.MAV_CMD_IMAGE_START_CAPTURE and c.target_component == component})


class _CommandLog:
    """Every COMMAND_LONG the camera's link carries from the autopilot, in order (subscribed before PX4 starts)."""

    def __init__(self, emulator) -> None:
        self.lock = threading.Lock()
        self.heard: list[HeardCommand] = []
        emulator.link.subscribe(self._on, types="COMMAND_LONG")

    def _on(self, m) -> None:
        with self.lock:
            self.heard.append(HeardCommand(m.command, m.target_system, m.target_component, m.confirmation,
                                           m.get_srcComponent(), float(m.param4)))


UPLOAD_ATTEMPTS = 2
# Images within this of the one before are one shot: PX4 sends each camera_trigger shot as two commands and
# resends a command whose ACK is late; well under the trigger spacings of a survey (several metres)
SAME_SHOT_M = 2.0


def shot_positions(images: list[tuple[float, float, float]],
                   within_m: float = SAME_SHOT_M) -> list[tuple[float, float, float]]:
    """(lat, lon, alt) of each shot, from the camera's images in order: consecutive images within `within_m`
    of the one before are the same shot (the first of them is kept). A fast plane on a loaded machine gets the
    two commands of a shot farther apart than SAME_SHOT_M: give it a bound under its trigger spacing."""
    out: list[tuple[float, float, float]] = []
    for lat, lon, alt in images:
        if out:
            plat, plon, _ = out[-1]
            dy = (lat - plat) * 111_320.0
            dx = (lon - plon) * 111_320.0 * math.cos(math.radians(lat))
            if math.hypot(dx, dy) < within_m:
                continue
        out.append((lat, lon, alt))
    return out


def _upload(sitl, plan: Path) -> dict:
    """Upload with read-back, once more after a failure (as a pilot would): PX4 times a transfer out in
    simulated time, which a ground station on a loaded machine can miss at a high speed-up. The summary
    says how many attempts it took."""
    from wiris_tools.errors import LinkError
    from wiris_tools.link import Link
    from wiris_tools.transfer import upload_file

    for attempt in range(1, UPLOAD_ATTEMPTS + 1):
        try:
            with Link(sitl.gcs_url) as link:
                summary = upload_file(link, str(plan), verify=True, timeout=20)
            return {**summary, "attempts": attempt}
        except LinkError:
            if attempt == UPLOAD_ATTEMPTS:
                raise
    raise AssertionError("unreachable")


@contextmanager
def fly_compiled_px4(px4_dir: Path | None, out_dir: Path, name: str, *, model: str = "wiris-pro",
                     component: int = 100, speedup: float = 6.0, vehicle: str = "copter",
                     home: tuple[float, float, float] = (50.08, 14.42, 262.0), fly: bool = True,
                     extra_params: Mapping[str, float] | None = None, workdir: Path | None = None,
                     timeout: float = 600.0) -> Iterator[Px4Flight]:
    """Start PX4 SITL with `out_dir/name.params` (plus `extra_params`) at boot and the emulator on its payload
    link, upload `name.plan` with read-back and (with `fly`) fly it in AUTO.MISSION to landing."""
    from wiris_tools.emulate.runner import start_emulator

    out_dir = Path(out_dir)
    params = read_params_file(out_dir / f"{name}.params")
    params.update(extra_params or {})
    sitl = emu = None
    try:
        sitl = start_sitl("px4", px4_dir, SitlOptions(vehicle=vehicle, speedup=speedup, workdir=workdir,
                                                      home=(*home, 0.0), params=params))
        # PX4 sends the payload link to a fixed port per instance: the camera binds it, with PX4's system id
        emu = start_emulator(model, f"udpin:127.0.0.1:{sitl.camera_port}", component=component,
                             system=sitl.target_system)
        heard = _CommandLog(emu)
        sitl.wait_ready()
        unknown, lost = [], {}
        for n, wanted in params.items():
            held = sitl.get_param(n, timeout=1.5)
            if held is None:
                unknown.append(n)
            elif abs(held - wanted) > 1e-4 * max(1.0, abs(wanted)):
                lost[n] = wanted
        # a value given at boot equal to PX4's built-in default is not kept as set, so an airframe's
        # `param set-default` (rc.fw_defaults: MIS_TKO_LAND_REQ 2) overrides it: set those over MAVLink, as a
        # ground station loading the file after boot would
        if lost:
            sitl.set_params(lost)
        summary = _upload(sitl, out_dir / f"{name}.plan")
        flight = Px4Flight(sitl, emu, unknown, summary)
        if fly:
            sitl.arm_and_start_mission()
            if vehicle == "copter":
                sitl.wait_mission_end(timeout=timeout)
            else:   # a fixed-wing's RTL loiters over home: the mission is flown when it gets there
                sitl.wait_mission_flown(timeout=timeout)
            time.sleep(1.0)   # the last CAMERA_IMAGE_CAPTURED
            with emu.lock:
                flight.photos = list(emu.state.history)
            with heard.lock:
                flight.commands = list(heard.heard)
        yield flight
    finally:
        if sitl is not None:
            sitl.close()
        if emu is not None:
            emu.close()
