"""Fly a compiled plan in SITL with the WIRIS emulator on the camera link, as a pilot would: load NAME.params
as written (names the firmware lacks are skipped, as ground stations do), reboot, upload NAME.plan with
read-back, arm, fly to the end, and keep what the camera took.

    with fly_compiled(sitl_dir, out_dir, "solar-park", cam_type=6) as flight:
        flight.photos            # the emulator's Captured list, in order
        flight.sitl.tlog, flight.sitl.dataflash_logs()
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import LinkError
from wiris_tools.sitl import SitlOptions, start_sitl


def read_params_file(path: Path) -> dict[str, float]:
    """`NAME,VALUE` lines of an ArduPilot parameter file (Mission Planner's format), or the `param set NAME VALUE`
    lines NAME.params holds for PX4 (its shell's syntax); `#` comments skipped."""
    out: dict[str, float] = {}
    for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("param set "):
            line = ",".join(line[len("param set "):].split(None, 1))
        name, sep, value = line.replace("\t", ",").partition(",")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise LinkError(f"not NAME,VALUE: {line[:60]!r}", where=f"{path}:{number}",
                            hint="an ArduPilot parameter file has one NAME,VALUE per line") from None
    return out


@dataclass
class Flight:
    sitl: object
    emulator: object
    skipped_params: list[str]
    upload: dict
    photos: list = field(default_factory=list)


class _InformationAsked:
    """Set once the autopilot asks the camera for CAMERA_INFORMATION (MAVLinkCamV2 asks until answered, then
    never again: subscribed before SITL starts)."""

    def __init__(self, emulator) -> None:
        import threading
        self.event = threading.Event()
        emulator.link.subscribe(self._on, types="COMMAND_LONG", src_system=1, src_component=1)

    def _on(self, m) -> None:
        if (m.command == mavlink2.MAV_CMD_REQUEST_CAMERA_INFORMATION
                or (m.command == mavlink2.MAV_CMD_REQUEST_MESSAGE
                    and int(m.param1) == mavlink2.MAVLINK_MSG_ID_CAMERA_INFORMATION)):
            self.event.set()


def _wait_camera_known(sitl, asked: _InformationAsked, component: int, cam_type: int, timeout: float) -> None:
    """Until the autopilot routes the camera's HEARTBEAT to the ground station and, for MAVLinkCamV2 (6), has
    asked it for CAMERA_INFORMATION (it searches from 10 s after boot): before that camera items go nowhere."""
    sitl.link.wait_heartbeat(timeout=timeout, system=1, component=component)
    if cam_type == 6 and not asked.event.wait(timeout):
        raise LinkError("ArduPilot never asked the camera for CAMERA_INFORMATION", where=str(sitl.workdir),
                        hint=f"MAVLinkCamV2 looks for instance n at component 100 + n - 1; the camera is at "
                             f"{component}")


@contextmanager
def fly_compiled(sitl_dir: Path | None, out_dir: Path, name: str, *, model: str = "wiris-pro", component: int = 100,
                 cam_type: int | None = None, speedup: float = 20.0, vehicle: str = "copter",
                 home: tuple[float, float, float] = (50.08, 14.42, 262.0), fly: bool = True,
                 extra_params: dict | None = None, workdir: Path | None = None,
                 camera_serial: int = 2, before_flight: Callable[[Flight], None] | None = None,
                 mission_timeout_s: float = 600.0) -> Iterator[Flight]:
    """Start SITL and the emulator, load `out_dir/name.params`, upload `name.plan` and (with `fly`) fly it, for
    at most `mission_timeout_s` of wall time; a `name.lua` bridge goes into the working folder's scripts/
    (SCR_ENABLE comes from NAME.params)."""
    import shutil
    import tempfile
    from wiris_tools.emulate.runner import start_emulator
    from wiris_tools.link import Link
    from wiris_tools.transfer import upload_file

    out_dir = Path(out_dir)
    workdir = Path(workdir or tempfile.mkdtemp(prefix="wiris-sitl-"))
    (workdir / "scripts").mkdir(parents=True, exist_ok=True)
    if (out_dir / f"{name}.lua").exists():
        shutil.copy(out_dir / f"{name}.lua", workdir / "scripts" / f"{name}.lua")
    emu = start_emulator(model, "udpin:127.0.0.1:0", component=component, system=1)
    asked = _InformationAsked(emu)
    sitl = None
    try:
        sitl = start_sitl("ardupilot", sitl_dir, SitlOptions(vehicle=vehicle, speedup=speedup, workdir=workdir,
                                                             camera_port=emu.link.local_port, home=(*home, 0.0),
                                                             camera_serial=camera_serial))
        sitl.wait_ready()
        params = read_params_file(out_dir / f"{name}.params")
        asked.event.clear()   # asked before the reboot counts for nothing
        instance = component - mavlink2.MAV_COMP_ID_CAMERA + 1
        if cam_type is not None:
            params[f"CAM{instance}_TYPE"] = cam_type
        params.update(extra_params or {})
        skipped = sitl.set_params(params, reboot=True, skip_unknown=True)
        sitl.wait_ready()
        with Link(sitl.gcs_url) as link:
            summary = upload_file(link, str(out_dir / f"{name}.plan"), verify=True, timeout=20)
        flight = Flight(sitl, emu, skipped, summary)
        if before_flight is not None:
            before_flight(flight)     # e.g. `wiris camera apply NAME.setup.json` through the autopilot
        if fly:
            _wait_camera_known(sitl, asked, component, int(params.get(f"CAM{instance}_TYPE", 0)), timeout=90)
            sitl.arm_and_start_mission()
            sitl.wait_mission_end(timeout=mission_timeout_s)
            time.sleep(0.5)   # the last CAMERA_IMAGE_CAPTURED
            with emu.lock:
                flight.photos = list(emu.state.history)
        yield flight
    finally:
        if sitl is not None:
            sitl.close()
        emu.close()


def camera_params(component: int, cam_type: int, camera_serial: int) -> dict[str, float]:
    """What a WIRIS at `component` on SERIAL`camera_serial` needs when no NAME.params is given: MAVLink 2 on its
    port, its CAMn (n = component - 99: MAVLinkCamV2 looks nowhere else) and its position stream under both the
    4.5/4.6 and the 4.7 name (SITL's stock MAVLink ports SERIAL0-2 make the channel the port number)."""
    instance = component - mavlink2.MAV_COMP_ID_CAMERA + 1
    return {f"SERIAL{camera_serial}_PROTOCOL": 2, f"CAM{instance}_TYPE": cam_type,
            f"SR{camera_serial}_POSITION": 5, f"MAV{camera_serial + 1}_POSITION": 5}


@contextmanager
def desk_sim(sitl_dir: Path | None, *, model: str = "wiris-pro", component: int = 100, cam_type: int = 6,
             vehicle: str = "copter", speedup: float = 1.0, home: tuple[float, float, float] = (50.08, 14.42, 262.0),
             params_file: Path | None = None, workdir: Path | None = None, camera_serial: int = 2,
             http_port: int = 0) -> Iterator[Flight]:
    """SITL with the emulator on its camera link, set up and ready to arm, for a user to fly against
    (`wiris sim ardupilot`): connect a ground station to `flight.sitl.gcs_url`."""
    from wiris_tools.emulate.runner import start_emulator

    emu = start_emulator(model, "udpin:127.0.0.1:0", component=component, system=1, http_port=http_port)
    sitl = None
    try:
        sitl = start_sitl("ardupilot", sitl_dir, SitlOptions(vehicle=vehicle, speedup=speedup, workdir=workdir,
                                                             camera_port=emu.link.local_port, home=(*home, 0.0),
                                                             camera_serial=camera_serial))
        sitl.wait_ready(timeout=120)
        params = read_params_file(params_file) if params_file else camera_params(component, cam_type, camera_serial)
        skipped = sitl.set_params(params, reboot=True, skip_unknown=True)
        sitl.wait_ready(timeout=120)
        yield Flight(sitl, emu, skipped, {})
    finally:
        if sitl is not None:
            sitl.close()
        emu.close()
