"""PX4 SITL with its built-in SIH simulator (a folder with `bin/px4`, `etc/` and `run-px4`, see
../shared/px4-sitl/README.md).

Instance N (1..9 here) is system N + 1 and holds, on 127.0.0.1: the GCS link (PX4 listens on 18570+N), which
this harness's monitor link holds; the API link (listens on 14580+N, sends to 14540+N), which is `gcs_url`
for ground-station tools; the payload link (listens on 14280+N, sends to 14030+N), where a camera listens at
`camera_port`. A PX4 UDP link answers the first local address it hears from and keeps it, so `gcs_url` binds
14540+N (`udpin:`): every tool that opens it is the same address to PX4, one after another. Instances 10 and
more share one API port (14549, PX4's px4-rc.mavlink), so they are not used.

A copy of PX4's folder may have lost its `bin/px4-*` symbolic links (the names its start-up scripts call);
the harness runs a copy of `bin/px4` from a cache folder of its own with those links made, and PX4's `etc/`
from the SITL folder. A MAVLink reboot makes SITL's PX4 exit; `reboot()` starts it again in the same
working directory, where parameters.bson keeps what was set.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import struct
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Mapping

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import CommandRefused, LinkError, NoAnswer
from wiris_tools.link import Link
from wiris_tools.sitl import SitlOptions
from wiris_tools.sitl.process import Instances, InstanceLock, SitlProcess, udp_port_free

FIRST_INSTANCE = 1             # 0 is the instance people start by hand
LAST_INSTANCE = 9
MODELS = {"copter": "sihsim_quadx", "plane": "sihsim_airplane", "vtol": "sihsim_standard_vtol"}
# PX4 custom mode: main mode AUTO (4), sub mode MISSION (4) (px4_custom_mode.h)
PX4_MAIN_AUTO = 4
PX4_SUB_MISSION = 4
PX4_SUB_LOITER = 3
PX4_SUB_RTL = 5
# PX4's SITL links stream at up to 100 Hz of simulated time (px4-rc.mavlink, the onboard mode's defaults): at
# 10x that is more than a Python reader on a shared machine keeps up with, and a mission transfer that falls
# behind PX4's time-out (in simulated time) is aborted. The harness turns off every stream it hears that is
# not in KEEP_STREAMS (SET_MESSAGE_INTERVAL -1) on both links it uses.
KEEP_STREAMS = {"HEARTBEAT": None, "SYS_STATUS": None, "STATUSTEXT": None, "HOME_POSITION": None,
                "EXTENDED_SYS_STATE": None, "GLOBAL_POSITION_INT": 5.0, "CAMERA_TRIGGER": None}
QUIET_LISTEN_S = 1.0


def ports(instance: int) -> dict[str, int]:
    return {"gcs": 18570 + instance, "api": 14580 + instance, "api_remote": 14540 + instance,
            "payload": 14280 + instance, "camera": 14030 + instance}


INSTANCES = Instances("wiris-sitl-px4", FIRST_INSTANCE, LAST_INSTANCE, lambda n: ports(n).values(), udp_port_free,
                      "PX4 SITL", "stop PX4 processes left running (ps -ef | grep bin/px4)")


def runnable_px4(px4_dir: Path) -> Path:
    """`bin/px4` copied to a cache folder beside the links PX4's scripts call (bin/MODULES), made once per
    binary; the SITL folder itself may be read-only."""
    binary = px4_dir / "bin" / "px4"
    st = binary.stat()
    key = hashlib.sha1(f"{binary.resolve()}:{st.st_size}:{st.st_mtime_ns}".encode()).hexdigest()[:12]
    target = Path(tempfile.gettempdir()) / f"wiris-px4-bin-{os.getuid()}-{key}"
    if (target / "px4").is_file():
        return target / "px4"
    build = Path(tempfile.mkdtemp(prefix=target.name + ".", dir=target.parent))
    shutil.copy2(binary, build / "px4")
    modules = px4_dir / "bin" / "MODULES"
    names = modules.read_text().split() if modules.is_file() else [
        p.name for p in (px4_dir / "bin").glob("px4-*") if p.name != "px4-alias.sh"]
    for name in names:
        os.symlink("px4", build / name)
    alias = px4_dir / "bin" / "px4-alias.sh"
    if alias.is_file():
        shutil.copy2(alias, build / alias.name)
    try:
        build.rename(target)
    except OSError:              # another process made it first
        shutil.rmtree(build, ignore_errors=True)
    return target / "px4"


def _float_of_int(value: float) -> float:
    """PX4 sends and takes an INT32 parameter's bits in PARAM_VALUE/PARAM_SET's float (bytewise encoding)."""
    return struct.unpack("<f", struct.pack("<i", int(value)))[0]


def _int_of_float(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


class Px4Sitl(SitlProcess):
    """One PX4 SITL process with SIH (see the package docstring for the interface)."""

    firmware = "px4"

    def __init__(self, px4_dir: Path, options: SitlOptions) -> None:
        if options.vehicle not in MODELS:
            raise LinkError(f"vehicle {options.vehicle!r}", hint="PX4 SIH here flies " + ", ".join(MODELS))
        self.options = options
        self.vehicle = options.vehicle
        self.px4_dir = Path(px4_dir)
        self._open_workdir(options.workdir, prefix="wiris-px4-")
        self._lock = InstanceLock(INSTANCES)
        self.instance = self._lock.instance
        self.target_system = self.instance + 1
        p = ports(self.instance)
        self.camera_port = p["camera"]            # where PX4's payload link sends: the camera binds it
        self.gcs_url = f"udpin:127.0.0.1:{p['api_remote']}"
        self._monitor_url = f"udpout:127.0.0.1:{p['gcs']}"
        try:
            self._binary = runnable_px4(self.px4_dir)
            self._start(clean=options.wipe, boot_params=options.params)
        except BaseException:
            self.close()
            raise

    # -- process ---------------------------------------------------------------------------------
    def _start(self, *, clean: bool, boot_params: Mapping[str, float] = {}) -> None:
        if clean:
            for name in ("parameters.bson", "parameters_backup.bson", "dataman", "eeprom"):
                path = self.workdir / name
                if path.is_dir():
                    shutil.rmtree(path)
                elif path.exists():
                    path.unlink()
        lat, lon, alt, _yaw = self.options.home
        env = {**os.environ, "PX4_SIM_MODEL": MODELS[self.vehicle], "PX4_SIMULATOR": "sihsim",
               "PX4_SIM_SPEED_FACTOR": f"{self.options.speedup:g}", "HEADLESS": "1",
               "PX4_HOME_LAT": f"{lat:.7f}", "PX4_HOME_LON": f"{lon:.7f}", "PX4_HOME_ALT": f"{alt:g}"}
        # rcS sets each PX4_PARAM_<name> after the airframe's defaults: parameters given at boot, as a pilot
        # loading a parameter file before the flight would have them
        env.update({f"PX4_PARAM_{k}": _fmt(v) for k, v in boot_params.items()})
        cmd = [str(self._binary), "-d", "-i", str(self.instance), "-w", str(self.workdir), str(self.px4_dir / "etc")]
        out = open(self.workdir / "px4.out", "ab")
        try:
            self._proc = subprocess.Popen(cmd, cwd=self.workdir, env=env, stdout=out, stderr=subprocess.STDOUT,
                                          stdin=subprocess.DEVNULL, start_new_session=True)
        finally:
            out.close()
        self._connect()

    def _connect(self, timeout: float = 30.0) -> None:
        link = Link(self._monitor_url)
        link.subscribe(self._record)
        self._link = link
        deadline = time.monotonic() + timeout
        while True:
            try:
                link.wait_heartbeat(timeout=1.0, system=self.target_system, component=1)
                break
            except LinkError:
                if not self._alive():
                    raise LinkError("PX4 SITL exited", where=str(self.workdir / "px4.out"),
                                    hint="read px4.out in the working directory") from None
                if time.monotonic() > deadline:
                    raise LinkError("no HEARTBEAT from PX4 SITL", where=self._monitor_url,
                                    hint="read px4.out in the working directory") from None
        self.quieten(link)
        with Link(self.gcs_url) as api:
            self.quieten(api)

    def quieten(self, link: Link) -> None:
        """Turn off (or slow, KEEP_STREAMS) every stream `link` hears from the autopilot within a second."""
        heard: set[int] = set()
        with link.inbox(src_system=self.target_system, src_component=1) as box:
            end = time.monotonic() + QUIET_LISTEN_S
            while (left := end - time.monotonic()) > 0:
                msg = box.get(timeout=left)
                if msg is not None:
                    heard.add(msg.get_msgId())
        for msg_id in sorted(heard):
            name = mavlink2.mavlink_map[msg_id].msgname if msg_id in mavlink2.mavlink_map else ""
            if name in KEEP_STREAMS and KEEP_STREAMS[name] is None:
                continue
            interval = 1e6 / KEEP_STREAMS[name] if name in KEEP_STREAMS else -1
            link.send(link.mav.command_long_encode(self.target_system, 1, mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL,
                                                   0, msg_id, interval, 0, 0, 0, 0, 0))

    # -- readiness ---------------------------------------------------------------------------------
    def wait_ready(self, timeout: float = 60.0) -> None:
        """Until PX4 has a home position and says its pre-arm checks pass (SYS_STATUS health bit)."""
        deadline = time.monotonic() + timeout
        home = prearm = False
        with self.link.inbox(types=("HOME_POSITION", "SYS_STATUS"), src_system=self.target_system,
                             src_component=1) as box:
            while not (home and prearm):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise LinkError("PX4 SITL not ready to arm", where=str(self.workdir),
                                    hint="last messages: " + " | ".join(self._statustext[-5:]))
                msg = box.get(timeout=min(1.0, left))
                if msg is None:
                    if not home:   # HOME_POSITION streams slowly: ask
                        self.link.send(self.link.mav.command_long_encode(
                            self.target_system, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0,
                            mavlink2.MAVLINK_MSG_ID_HOME_POSITION, 0, 0, 0, 0, 0, 0))
                    continue
                if msg.get_type() == "HOME_POSITION":
                    home = True
                else:
                    prearm = bool(msg.onboard_control_sensors_health & mavlink2.MAV_SYS_STATUS_PREARM_CHECK)

    # -- parameters --------------------------------------------------------------------------------
    def _read_param(self, name: str, timeout: float = 3.0):
        link = self.link
        for _ in range(3):
            with link.inbox(types="PARAM_VALUE", src_system=self.target_system,
                            predicate=lambda m: m.param_id == name) as box:
                link.send(link.mav.param_request_read_encode(self.target_system, 1, name.encode(), -1))
                msg = box.get(timeout=timeout / 3)
            if msg is not None:
                return msg
        return None

    @staticmethod
    def _value(msg) -> float:
        if msg.param_type == mavlink2.MAV_PARAM_TYPE_REAL32:
            return float(msg.param_value)
        return float(_int_of_float(msg.param_value))

    def get_param(self, name: str, timeout: float = 3.0) -> float | None:
        msg = self._read_param(name, timeout)
        return None if msg is None else self._value(msg)

    def set_params(self, params: Mapping[str, float], *, reboot: bool = False, skip_unknown: bool = False) -> list[str]:
        """PARAM_SET each in the type PX4 holds it in, confirmed by PARAM_VALUE; a name PX4 lacks never
        answers: an error, or with `skip_unknown` skipped and returned. `reboot`: restart PX4 afterwards."""
        link = self.link
        skipped: list[str] = []
        for name, value in params.items():
            current = self._read_param(name)
            if current is None:
                if skip_unknown:
                    skipped.append(name)
                    continue
                raise LinkError(f"parameter {name} is unknown to PX4", where=str(self.workdir),
                                hint="check the name for this PX4 version (param show in its shell)")
            kind = current.param_type
            wire = float(value) if kind == mavlink2.MAV_PARAM_TYPE_REAL32 else _float_of_int(value)
            for _ in range(5):
                with link.inbox(types="PARAM_VALUE", src_system=self.target_system,
                                predicate=lambda m, n=name: m.param_id == n) as box:
                    link.send(link.mav.param_set_encode(self.target_system, 1, name.encode(), wire, kind))
                    msg = box.get(timeout=1.0)
                if msg is not None and abs(self._value(msg) - float(value)) < 1e-4 * max(1.0, abs(float(value))):
                    break
            else:
                raise LinkError(f"parameter {name} was never set to {value:g}", where=str(self.workdir),
                                hint="read px4.out: PX4 may refuse the value")
        if reboot:
            self.reboot()
        return skipped

    def reboot(self, timeout: float = 60.0) -> None:
        """Stop PX4 and start it again in the same folder (stored parameters and mission kept)."""
        time.sleep(0.5)   # PX4 saves parameters.bson shortly after a change
        self._stop_process()
        self._start(clean=False)

    # -- flying ------------------------------------------------------------------------------------
    def set_mission_mode(self) -> None:
        self.link.command_long(self.target_system, 1, mavlink2.MAV_CMD_DO_SET_MODE,
                               [mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, PX4_MAIN_AUTO, PX4_SUB_MISSION,
                                0, 0, 0, 0])

    def arm(self, timeout: float = 60.0) -> None:
        """Arm, retrying while PX4's health checks refuse (the first request right after boot usually is)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.link.command_long(self.target_system, 1, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM,
                                       [1, 0, 0, 0, 0, 0, 0])
                return
            except (CommandRefused, NoAnswer):
                if time.monotonic() > deadline:
                    raise LinkError("PX4 SITL refused to arm", where=str(self.workdir),
                                    hint="last messages: " + " | ".join(self._statustext[-8:])) from None
                time.sleep(1.0)

    def arm_and_start_mission(self, timeout: float = 60.0) -> None:
        """AUTO.MISSION, then arm: PX4 takes off and flies the stored mission."""
        self.set_mission_mode()
        self.arm(timeout)

    def armed(self) -> bool:
        hb = self.link.heartbeats().get((self.target_system, 1))
        return bool(hb and hb.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)

    def wait_mission_end(self, timeout: float = 300.0) -> None:
        """Until the vehicle disarms (after landing)."""
        deadline = time.monotonic() + timeout
        with self.link.inbox(types="HEARTBEAT", src_system=self.target_system, src_component=1) as box:
            while time.monotonic() < deadline:
                hb = box.get(timeout=1.0)
                if hb is not None and not hb.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED:
                    return
                if not self._alive():
                    break
        raise LinkError("the mission did not end (vehicle still armed)", where=str(self.workdir),
                        hint="last messages: " + " | ".join(self._statustext[-5:]))

    def wait_mission_flown(self, timeout: float = 300.0) -> None:
        """Until the vehicle has left AUTO.MISSION for its end (AUTO.RTL, AUTO.LOITER) or disarmed: a
        fixed-wing's RTL loiters over home for ever (RTL_TYPE 0) and never lands by itself."""
        deadline = time.monotonic() + timeout
        with self.link.inbox(types="HEARTBEAT", src_system=self.target_system, src_component=1) as box:
            while time.monotonic() < deadline:
                hb = box.get(timeout=1.0)
                if hb is None:
                    if not self._alive():
                        break
                    continue
                main, sub = (hb.custom_mode >> 16) & 0xFF, (hb.custom_mode >> 24) & 0xFF
                if not hb.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED or (
                        main == PX4_MAIN_AUTO and sub in (PX4_SUB_RTL, PX4_SUB_LOITER)):
                    return
        raise LinkError("the mission was not flown to its end", where=str(self.workdir),
                        hint="last messages: " + " | ".join(self._statustext[-5:]))

    # -- results -----------------------------------------------------------------------------------
    def ulogs(self) -> list[Path]:
        """The ULogs PX4 wrote in this working directory (log/YYYY-MM-DD/HH_MM_SS.ulg), oldest first."""
        return sorted((self.workdir / "log").glob("**/*.ulg"), key=lambda p: (p.stat().st_mtime, str(p)))

    def dataflash_logs(self) -> list[Path]:
        """The flight logs, as the ArduPilot backend names its own: PX4 writes ULogs."""
        return self.ulogs()


def _fmt(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else repr(float(v))
