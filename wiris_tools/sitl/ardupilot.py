"""ArduPilot SITL (arducopter / arduplane from a folder with `run-sitl`, see ../shared/sitl/README.md).

Ports of instance N: serial0 TCP 5760+10N is the monitor link this harness holds (SITL's clock starts when
it connects); the camera's serial port (SERIAL2 = TELEM2 by default, as NAME.params assumes, or SERIAL1) is a
MAVLink 2 UDP client to the camera port when one is given; the other of serial1 (TCP 5762+10N) and serial2
(TCP 5763+10N) is `gcs_url`, for ground-station tools. A MAVLink reboot makes SITL restart itself in the same process with
its arguments minus `-w`, so stored parameters (eeprom.bin) survive it and the monitor reconnects.
"""

from __future__ import annotations

import contextlib
import io
import subprocess
import time
from pathlib import Path
from typing import Mapping

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import CommandRefused, LinkError, NoAnswer
from wiris_tools.link import Link
from wiris_tools.sitl import SitlOptions
from wiris_tools.sitl.process import Instances, InstanceLock, SitlProcess, tcp_port_free

FIRST_INSTANCE = 10            # leave 0..9 to people starting SITL by hand
LAST_INSTANCE = 59
MONITOR_STREAM_HZ = 10

# EKF_STATUS_REPORT flags that together mean "a position estimate good enough to arm and fly a mission"
EKF_READY = (mavlink2.EKF_ATTITUDE | mavlink2.EKF_VELOCITY_HORIZ | mavlink2.EKF_VELOCITY_VERT
             | mavlink2.EKF_POS_HORIZ_ABS | mavlink2.EKF_POS_VERT_ABS | mavlink2.EKF_PRED_POS_HORIZ_ABS)
EKF_NOT_READY = mavlink2.EKF_CONST_POS_MODE | mavlink2.EKF_UNINITIALIZED
PREARM = mavlink2.MAV_SYS_STATUS_PREARM_CHECK


def _ports(instance: int) -> tuple[int, int, int]:
    base = 5760 + 10 * instance
    return base, base + 2, base + 3


INSTANCES = Instances("wiris-sitl-ardupilot", FIRST_INSTANCE, LAST_INSTANCE, _ports, tcp_port_free, "SITL",
                      "stop SITL processes left running (ps -ef | grep arducopter)")


class ArduPilotSitl(SitlProcess):
    """One ArduPilot SITL process (see the package docstring for the interface)."""

    firmware = "ardupilot"

    def __init__(self, sitl_dir: Path, options: SitlOptions) -> None:
        if options.vehicle not in ("copter", "plane"):
            raise LinkError(f"vehicle {options.vehicle!r}", hint="ArduPilot SITL here has copter and plane")
        self.options = options
        self.vehicle = options.vehicle
        self._own_workdir = options.workdir is None
        self._open_workdir(options.workdir, prefix="wiris-sitl-")
        self._lock = InstanceLock(INSTANCES)
        self.instance = self._lock.instance
        if options.camera_serial not in (1, 2):
            raise LinkError(f"camera on SERIAL{options.camera_serial}", hint="SITL's camera link is SERIAL1 or SERIAL2")
        monitor, serial1, serial2 = _ports(self.instance)
        tools = serial1 if options.camera_serial == 2 and options.camera_port is not None else serial2
        self.gcs_url = f"tcp:127.0.0.1:{tools}"
        self._monitor_url = f"tcp:127.0.0.1:{monitor}"
        try:
            self._proc = self._spawn(sitl_dir)
            self._connect()
            if options.params:
                self.set_params(options.params)
        except BaseException:
            self.close()
            raise

    # -- process ---------------------------------------------------------------------------------
    def _spawn(self, sitl_dir: Path) -> subprocess.Popen:
        o = self.options
        cmd = [str(sitl_dir / "run-sitl"), "-v", o.vehicle, "-I", str(self.instance), "-s", f"{o.speedup:g}",
               "-w", str(self.workdir), "-H", ",".join(f"{v:g}" for v in o.home)]
        if o.wipe:
            cmd.append("-l")
        if o.camera_port is not None and o.camera_serial == 1:
            cmd += ["-c", str(o.camera_port)]
        elif o.camera_port is not None:
            cmd += ["--", f"--serial{o.camera_serial}", f"udpclient:127.0.0.1:{o.camera_port}"]
        out = open(self.workdir / "sitl.out", "ab")
        try:
            # its own process group: close() ends run-sitl and the firmware together, nothing is left behind
            return subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    start_new_session=True)
        finally:
            out.close()

    def _connect(self, timeout: float = 30.0) -> None:
        """Open the monitor link on serial0 (SITL accepts one client there) and ask for its streams."""
        deadline = time.monotonic() + timeout
        while True:
            if not self._alive():
                raise LinkError("ArduPilot SITL exited", where=str(self.workdir / "sitl.out"),
                                hint="read sitl.out in the working directory")
            try:
                # pymavlink prints each refused TCP attempt on stdout, where `wiris sim` prints its URL
                with contextlib.redirect_stdout(io.StringIO()):
                    link = Link(self._monitor_url)
                break
            except LinkError:
                if time.monotonic() > deadline:
                    raise LinkError("SITL's serial0 never accepted a connection", where=self._monitor_url,
                                    hint="read sitl.out in the working directory") from None
                time.sleep(0.1)
        link.subscribe(self._record)
        self._link = link
        hb = link.wait_heartbeat(timeout=max(1.0, deadline - time.monotonic()), component=1)
        self.target_system = hb.get_srcSystem()
        self._request_streams()

    def _request_streams(self) -> None:
        # a copter streams nothing on a channel until asked (its default SRn_/MAVn_ rates are 0)
        link = self.link
        link.send(link.mav.request_data_stream_encode(self.target_system, 1, mavlink2.MAV_DATA_STREAM_ALL,
                                                      MONITOR_STREAM_HZ, 1))

    # -- readiness ---------------------------------------------------------------------------------
    def wait_ready(self, timeout: float = 60.0) -> None:
        """Until the EKF uses GPS for an absolute position and the pre-arm checks pass (SYS_STATUS)."""
        deadline = time.monotonic() + timeout
        ekf_ok = prearm_ok = False
        ask_again = time.monotonic() + 2.0
        with self.link.inbox(types=("EKF_STATUS_REPORT", "SYS_STATUS"), src_system=self.target_system,
                             src_component=1) as box:
            while not (ekf_ok and prearm_ok):
                left = deadline - time.monotonic()
                msg = box.get(timeout=min(1.0, max(left, 0.01)))
                if left <= 0:
                    raise LinkError(f"SITL not ready to arm (EKF {'ok' if ekf_ok else 'not ready'}, pre-arm "
                                    f"{'ok' if prearm_ok else 'failing'})", where=str(self.workdir),
                                    hint="last messages: " + " | ".join(self._statustext[-5:]))
                if time.monotonic() > ask_again:   # a request lost at start-up would leave us waiting for ever
                    self._request_streams()
                    ask_again = time.monotonic() + 2.0
                if msg is None:
                    continue
                if msg.get_type() == "EKF_STATUS_REPORT":
                    ekf_ok = (msg.flags & EKF_READY) == EKF_READY and not msg.flags & EKF_NOT_READY
                else:
                    prearm_ok = bool(msg.onboard_control_sensors_health & PREARM)

    # -- parameters --------------------------------------------------------------------------------
    def get_param(self, name: str, timeout: float = 3.0) -> float | None:
        link = self.link
        for _ in range(3):
            with link.inbox(types="PARAM_VALUE", src_system=self.target_system,
                            predicate=lambda m: m.param_id == name) as box:
                link.send(link.mav.param_request_read_encode(self.target_system, 1, name.encode(), -1))
                msg = box.get(timeout=timeout / 3)
            if msg is not None:
                return float(msg.param_value)
        return None

    def set_params(self, params: Mapping[str, float], *, reboot: bool = False, skip_unknown: bool = False) -> list[str]:
        """PARAM_SET each and wait for its PARAM_VALUE; then reboot when asked (CAMn_TYPE, SCR_ENABLE need it).
        A name the firmware does not have never answers: an error, or with `skip_unknown` (as a ground station
        loading a parameter file does) skipped and returned."""
        link = self.link
        skipped: list[str] = []
        for name, value in params.items():
            for _ in range(3 if skip_unknown else 5):
                with link.inbox(types="PARAM_VALUE", src_system=self.target_system,
                                predicate=lambda m, n=name: m.param_id == n) as box:
                    link.send(link.mav.param_set_encode(self.target_system, 1, name.encode(), float(value),
                                                        mavlink2.MAV_PARAM_TYPE_REAL32))
                    msg = box.get(timeout=1.0)
                if msg is not None:
                    break
            else:
                if skip_unknown:
                    skipped.append(name)
                    continue
                raise LinkError(f"parameter {name} was never confirmed", where=str(self.workdir),
                                hint="ArduPilot ignores PARAM_SET of a name it does not have: check the name "
                                     "for this firmware version")
        if reboot:
            self.reboot()
        return skipped

    def reboot(self, timeout: float = 60.0) -> None:
        link = self.link
        try:
            link.command_long(self.target_system, 1, mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, [1, 0, 0, 0, 0, 0, 0])
        except NoAnswer:
            pass   # the ACK may die with the connection
        link.close()
        self._link = None
        time.sleep(0.5)   # let the old connection drop before reconnecting
        self._connect(timeout)

    # -- flying ------------------------------------------------------------------------------------
    def _mode(self, name: str) -> int:
        table = mavutil.mode_mapping_acm if self.vehicle == "copter" else mavutil.mode_mapping_apm
        return {mode: number for number, mode in table.items()}[name]

    def set_mode(self, name: str) -> None:
        self.link.command_long(self.target_system, 1, mavlink2.MAV_CMD_DO_SET_MODE,
                               [mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, self._mode(name), 0, 0, 0, 0, 0])

    def arm(self, timeout: float = 60.0) -> None:
        """Arm, retrying while pre-arm checks refuse (the refusals' reasons end up in the error)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.link.command_long(self.target_system, 1, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM,
                                       [1, 0, 0, 0, 0, 0, 0])
                return
            except (CommandRefused, NoAnswer):
                if time.monotonic() > deadline:
                    raise LinkError("SITL refused to arm", where=str(self.workdir),
                                    hint="pre-arm messages: " + " | ".join(
                                        t for t in self._statustext[-20:] if "Arm" in t)) from None
                time.sleep(0.5)

    def arm_and_start_mission(self, timeout: float = 60.0) -> None:
        """Copter: GUIDED, arm, MISSION_START (AUTO without RC throttle). Plane: AUTO, then arm."""
        if self.vehicle == "copter":
            self.set_mode("GUIDED")
            self.arm(timeout)
            self.link.command_long(self.target_system, 1, mavlink2.MAV_CMD_MISSION_START, [0, 0, 0, 0, 0, 0, 0])
        else:
            self.set_mode("AUTO")
            self.arm(timeout)

    def armed(self) -> bool:
        hb = self.link.heartbeats.get((self.target_system, 1))
        return bool(hb and hb.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)

    def wait_mission_end(self, timeout: float = 300.0) -> None:
        """Until the vehicle disarms (after landing), or a plane's mission hands it to RTL mode (an RTL item: it
        then circles home for ever)."""
        deadline = time.monotonic() + timeout
        rtl = self._mode("RTL")
        with self.link.inbox(types="HEARTBEAT", src_system=self.target_system, src_component=1) as box:
            while time.monotonic() < deadline:
                hb = box.get(timeout=1.0)
                if hb is not None and not hb.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED:
                    return
                if hb is not None and self.vehicle == "plane" and hb.custom_mode == rtl:
                    return
                if not self._alive():
                    break
        raise LinkError("the mission did not end (vehicle still armed)", where=str(self.workdir),
                        hint="last messages: " + " | ".join(self._statustext[-5:]))

    # -- results -----------------------------------------------------------------------------------
    def dataflash_logs(self) -> list[Path]:
        return sorted((self.workdir / "logs").glob("*.BIN"))
