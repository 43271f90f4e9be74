"""Autopilot parameters a compiled mission relies on, each with the reason, and the `.params` text.

The serial port numbers are a wiring choice the plan does not know: cameras are placed on TELEM2 (SERIAL2 /
MAV_1 = TELEM 2) first, then the next ports, and the reason line says so — change the port number to where
the camera is plugged in. Sources: reference autopilots-and-cameras §2.1 (CAMx_TYPE), §2.4 (MAVLink ports
and forwarding), §2.5 (streaming position to a camera, FLIR Vue example), §3.2 (PX4 camera_trigger and port
set-up), §5.1 (RedEdge: MAVLink 1, 57600, GPS_RAW_INT or SYSTEM_TIME + GLOBAL_POSITION_INT); Workswell
manual §5.2 (UART 57600, MAVLink 2) and §6.1 (GPS messages it geotags with).
"""

from __future__ import annotations

import math

from typing import Any, Iterable, Mapping

from missions.errors import PlanError

Param = tuple[str, float, str]

# ArduPilot SERIALn ports tried for cameras whose plan names no `autopilot_serial`, in order: TELEM2, then
# SERIAL4/5 (GPS2/spare UARTs on most boards).
ARDUPILOT_PORTS = (2, 4, 5, 6)
# SERIALn ports that speak MAVLink in ArduPilot's stock layout (USB, TELEM1, TELEM2; SERIAL3 is the GPS).
ARDUPILOT_STOCK_MAVLINK = (0, 1, 2)
# The first release that names a MAVLink channel's stream rates MAVn_ (n = channel + 1, libraries/GCS_MAVLink/
# GCS.cpp: AP_SUBGROUPVARPTR(_chan[0], "1", ...) under "MAV"); 4.5 and 4.6 name them SRn_ (n = channel,
# ArduCopter/Parameters.cpp: GOBJECTN(_gcs.chan_parameters[n], gcsn, "SRn_", ...)).
ARDUPILOT_MAV_STREAM_NAMES = (4, 7)


def _ardupilot_channel(port: int, camera_ports: list[int]) -> int:
    """The MAVLink channel of SERIAL`port`, which its stream rates belong to: ArduPilot numbers channels
    by counting the serial ports set to MAVLink, in port order (GCS::setup_uarts; ArduPilot #28646: "SRx
    parameters are meant for the x mavlink channel, not for the x serial port"). Counted with the stock layout
    plus the camera ports this template sets to MAVLink."""
    return len({p for p in (*ARDUPILOT_STOCK_MAVLINK, *camera_ports) if p < port})


def _release(version: str | None) -> tuple[int, int] | None:
    if version is None:
        return None
    parts = str(version).split(".")
    return int(parts[0]), int(parts[1]) if len(parts) > 1 else 0


def _stream_rows(version: str | None, channel: int, port: str, stream: str, value: float, why: str) -> list[Param]:
    """One stream rate as the plan's ArduPilot release names it; both names (each saying which releases have
    it) when the plan names no release. A ground station loading the file skips the name its firmware lacks
    (Mission Planner, QGroundControl and MAVProxy warn and go on), so the file works as written on 4.5-4.7."""
    release = _release(version)
    old = (f"SR{channel}_{stream}", f"ArduPilot 4.5/4.6 name (SRn_ = MAVLink channel n)")
    new = (f"MAV{channel + 1}_{stream}", f"ArduPilot 4.7+ name (MAVn_ = MAVLink channel n - 1)")
    names = [old, new] if release is None else [new if release >= ARDUPILOT_MAV_STREAM_NAMES else old]
    where = (f"{port} is MAVLink channel {channel}, counted after the other MAVLink ports (stock: SERIAL0-2; "
             "recount if yours differ)")
    return [(name, value, f"{why}; {which}; {where}") for name, which in names]


# The WIRIS geotags each photo with the last GLOBAL_POSITION_INT it heard (manual §6.1): at a stream rate r the tag
# is up to speed / r behind where the photo was taken. 5 Hz keeps that within 2 m up to 10 m/s; faster vehicles
# (a plane at 20 m/s: 4 m, flown in arduplane SITL) get the rate that keeps it within GEOTAG_LAG_M.
GEOTAG_RATE_HZ = 5
GEOTAG_LAG_M = 2.0


def geotag_rate_hz(speed_mps: float | None) -> int:
    """The GLOBAL_POSITION_INT rate that keeps a WIRIS geotag within GEOTAG_LAG_M of where the photo was taken."""
    if not speed_mps or speed_mps <= 0:
        return GEOTAG_RATE_HZ
    return max(GEOTAG_RATE_HZ, math.ceil(speed_mps / GEOTAG_LAG_M - 1e-9))


def _ardupilot(payloads: list[Any], cameras: Mapping[str, Any], infos: Mapping[str, Any],
               instances: Mapping[str, int], needs_lua: bool, version: str | None = None,
               speed_mps: float | None = None) -> list[Param]:
    out: list[Param] = []
    rate = geotag_rate_hz(speed_mps)
    given = {getattr(p, "autopilot_serial", None) for p in payloads} - {None}
    ports = iter(n for n in ARDUPILOT_PORTS if n not in given)
    used: list[int] = []
    for p in payloads:
        cam = cameras[p.name]
        n = getattr(p, "autopilot_serial", None)
        if n is None:
            try:
                n = next(ports)
            except StopIteration:
                raise PlanError("more cameras than free serial ports in the parameter template",
                                hint="give each payload its autopilot_serial (the SERIALn it is wired to)") from None
        elif n in used:
            raise PlanError(f"two payloads on SERIAL{n}", hint="give each payload the autopilot_serial it is wired to")
        port = f"SERIAL{n}"
        ch = _ardupilot_channel(n, used)
        used.append(n)
        if cam.protocol == "rededge-serial":
            out += [
                (f"{port}_PROTOCOL", 1, f"{p.name} (RedEdge) port: MAVLink 1 — the RedEdge speaks only MAVLink v1 "
                                        f"(serial API); {port} = the port it is wired to (autopilot_serial)"),
                (f"{port}_BAUD", 57, f"{p.name}: 57600 baud (RedEdge serial API)"),
                # RedEdge geotags from GPS_RAW_INT (its time_usec sets UTC) or SYSTEM_TIME + GLOBAL_POSITION_INT,
                # not both: stream GPS_RAW_INT (EXT_STAT group) and ATTITUDE (EXTRA1), nothing position-group.
                *_stream_rows(version, ch, port, "EXT_STAT", 5,
                              f"{p.name}: GPS_RAW_INT at 5 Hz for the RedEdge's overlap mode and geotags"),
                *_stream_rows(version, ch, port, "EXTRA1", 5, f"{p.name}: ATTITUDE at 5 Hz (RedEdge records "
                                                                "aircraft attitude)"),
                *_stream_rows(version, ch, port, "POSITION", 0, f"{p.name}: no GLOBAL_POSITION_INT — the RedEdge "
                                                                  "wants GPS_RAW_INT or SYSTEM_TIME+GLOBAL_POSITION_INT, "
                                                                  "not both"),
                *_stream_rows(version, ch, port, "EXTRA3", 0, f"{p.name}: no SYSTEM_TIME (see POSITION)"),
            ]
            continue
        i = instances[p.name]
        out += [
            (f"{port}_PROTOCOL", 2, f"{p.name} ({cam.model}) port: MAVLink 2 (Workswell manual §5.2); {port} = the "
                                    "port it is wired to (autopilot_serial); not private, so PARAM_EXT settings from "
                                    "the GCS are routed"),
            (f"{port}_BAUD", 57, f"{p.name}: 57600 baud (Workswell manual §5.2)"),
            *_stream_rows(version, ch, port, "POSITION", rate, f"{p.name}: GLOBAL_POSITION_INT at {rate} Hz, which "
                                                                 "the camera geotags with (manual §6.1)"
                                                                 + ("" if rate == GEOTAG_RATE_HZ else
                                                                    f": at {speed_mps:g} m/s a photo's tag is then at "
                                                                    f"most {GEOTAG_LAG_M:g} m behind it")),
            (f"CAM{i}_TYPE", 6, f"{p.name} is camera instance {i} because its component id is {p.component_id}: "
                                "MAVLinkCamV2 looks for instance n only at component 100 + n - 1 "
                                "(AP_Camera_MAVLinkCamV2::find_camera), with the vehicle's system id and a "
                                "MAV_TYPE_CAMERA heartbeat, in the first 60 s after boot or while disarmed, and "
                                "sends IMAGE_START_CAPTURE per trigger. 5 (MAVLink) also works: DO_DIGICAM_CONTROL "
                                "broadcast to every camera with the autopilot's system id"),
        ]
        info = infos.get(p.name)
        if info is not None and info.min_interval_s:
            out.append((f"CAM{i}_INTRVAL_MIN", float(info.min_interval_s),
                        f"{p.name}: never trigger faster than the camera's minimum capture interval "
                        f"({info.min_interval_s:g} s, catalogue)"))
    taken = set(instances.values())
    if taken and 1 not in taken:
        only = next(name for name, i in instances.items() if i == min(taken))
        out.append(("CAM1_TYPE", 0, f"no camera at component 100 in this plan: CAM1 off, so that CAM{min(taken)} "
                                    f"({only}) is the primary camera, the one distance triggering fires "
                                    "(AP_Camera: the first configured instance is primary)"))
    if needs_lua:
        out.append(("SCR_ENABLE", 1, "Lua scripting on: the mission changes camera settings through the generated "
                                     "bridge script (copy NAME.lua to APM/scripts/, reboot)"))
    return out


# PX4 MAV_n instances and the port each is put on (MAV_n_CONFIG values: 102 TELEM 2, 103 TELEM 3). PX4 has three
# MAVLink instances, MAV_0..MAV_2 (src/modules/mavlink/module.yaml: num_instances 3), and MAV_0 is the ground
# station's telemetry (default TELEM 1): two are free for cameras.
PX4_PORTS = ((1, 102, "SER_TEL2_BAUD", "TELEM 2"), (2, 103, "SER_TEL3_BAUD", "TELEM 3"))



def _px4(payloads: list[Any], cameras: Mapping[str, Any], triggers: set[str],
         fixed_wing_without_landing: bool = False) -> list[Param]:
    if {"distance", "interval"} <= triggers:
        raise PlanError("PX4 has one TRIG_MODE: this plan mixes distance and interval triggering",
                        hint="use the same trigger for every survey and corridor")
    if not {"distance", "interval"} & triggers:
        # measured in PX4 1.16 SITL: with camera_trigger running (TRIG_MODE > 0) a mission's single capture
        # (DIGICAM_CONTROL, IMAGE_START_CAPTURE of one image) is also a camera_trigger shot, which its
        # CAMERA_TRIGGER stream sends on as IMAGE_START_CAPTURE and DO_DIGICAM_CONTROL: 10 photos for 3 captures
        out: list[Param] = [
            ("TRIG_MODE", 0, "camera_trigger off: this plan triggers no survey, and each capture item then reaches "
                             "the camera as one command, so one photo (with camera_trigger on, each also becomes a "
                             "trigger shot sent as two more commands)"),
        ]
    else:
        mode = 1 if "interval" in triggers else 4
        out = [
            ("TRIG_INTERFACE", 3, "camera_trigger sends MAVLink: its CAMERA_TRIGGER stream sends every shot to "
                                  "components 100..105 as IMAGE_START_CAPTURE and as DO_DIGICAM_CONTROL "
                                  "(CAMERA_TRIGGER.hpp; reference §3.2). A WIRIS answers both: two images per "
                                  "trigger position, and PX4 1.16 has no parameter that sends only one"),
            ("TRIG_MODE", mode, "time based, on command (DO_SET_CAM_TRIGG_INTERVAL)" if mode == 1 else
                                "distance based, on command (DO_SET_CAM_TRIGG_DIST in the mission)"),
        ]
    ports = iter(PX4_PORTS)
    has_v1 = False
    for p in payloads:
        cam = cameras[p.name]
        try:
            n, cfg, baud, label = next(ports)
            telem = getattr(p, "autopilot_serial", None)
            if telem is not None and telem > 4:
                raise PlanError(f"{p.name}: PX4 has no TELEM {telem} to configure", hint="autopilot_serial is the "
                                "TELEM port on PX4: 1..4")
            if telem is not None:
                # the plan names the TELEM port it is wired to: SER_TELn_BAUD, MAV_x_CONFIG 100 + n (101 TELEM 1 ..
                # 104 TELEM/SERIAL 4 in PX4's serial port table)
                cfg, baud, label = 100 + telem, f"SER_TEL{telem}_BAUD", f"TELEM {telem}"
        except StopIteration:
            raise PlanError(f"{len(payloads)} MAVLink cameras, but PX4 has three MAVLink instances (MAV_0..MAV_2) and "
                            "MAV_0 is the ground station's telemetry", hint="connect the cameras through a companion "
                            "computer or a MAVLink router on one port, or fly at most two of them") from None
        out += [
            (f"MAV_{n}_CONFIG", cfg, f"{p.name} ({cam.model}) on {label}: change to the port it is wired to"),
            (f"MAV_{n}_MODE", 2, f"{p.name}: Onboard mode (PX4 camera docs) — streams GPS/position for geotags"),
            (f"MAV_{n}_RATE", 0, f"{p.name}: 0 = PX4 chooses the rate from the baud rate"),
            (f"MAV_{n}_FORWARD", 1, f"{p.name}: forward MAVLink between the camera and the ground station "
                                     "(camera protocol / PARAM_EXT from QGC)"),
            (baud, 57600, f"{p.name}: 57600 baud"),
        ]
        has_v1 = has_v1 or cam.mavlink_version == 1
    if fixed_wing_without_landing:
        # measured in PX4 1.16 SITL (sihsim_airplane): the mission ending in RTL was rejected ("Landing
        # waypoint/pattern required") and arming refused, until MIS_TKO_LAND_REQ was 0
        out.append(("MIS_TKO_LAND_REQ", 0, "the mission ends without a landing (RTL): PX4's fixed-wing default (2) "
                                           "requires one and rejects the mission, so arming is refused; RTL then "
                                           "loiters over home (RTL_TYPE 0) until you land"))
    if has_v1:
        out.append(("MAV_PROTO_VER", 0, "start every link in MAVLink 1 and upgrade only links that speak 2: the "
                                        "RedEdge speaks only MAVLink 1"))
    return out


def autopilot_params(prof: Any, payloads: Iterable[Any], cameras: Mapping[str, Any], infos: Mapping[str, Any],
                     instances: Mapping[str, int], needs_lua: bool = False,
                     triggers: Iterable[str] = (), version: str | None = None,
                     fixed_wing_without_landing: bool = False, speed_mps: float | None = None) -> tuple[Param, ...]:
    """(name, value, why) for the firmware `prof` (missions.emit.firmware.FirmwareProfile); `version` is the
    plan's vehicle.firmware_version (None: names every supported release understands)."""
    payloads = list(payloads)
    if prof.name == "ardupilot":
        rows = _ardupilot(payloads, cameras, infos, instances, needs_lua, version, speed_mps)
    else:
        rows = _px4(payloads, cameras, set(triggers), fixed_wing_without_landing)
    return tuple((n, float(v), why) for n, v, why in rows)


def _fmt(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else repr(float(v))


def format_params(compiled: Any) -> str:
    """The `.params` text: ArduPilot/Mission Planner `NAME,VALUE` lines, or PX4 `param set NAME VALUE` lines
    (an nsh script for the SD card's etc/extras.txt or the MAVLink shell), each after a `#` reason."""
    px4 = compiled.firmware == "px4"
    head = [f"# {compiled.name}: autopilot parameters this mission relies on ({compiled.firmware})",
            "# Review each line: serial port numbers assume the camera is wired to the port named."]
    lines = list(head)
    for name, value, why in compiled.params:
        lines.append(f"# {why}")
        lines.append(f"param set {name} {_fmt(value)}" if px4 else f"{name},{_fmt(value)}")
    return "\n".join(lines) + "\n"
