"""`wiris sim ...`: something to fly against without hardware.

`wiris sim ardupilot` starts ArduPilot SITL (the real firmware) with the WIRIS emulator on its camera link.

`wiris sim vehicle` runs the project's vehicle simulator (wiris_tools.vehicle_sim) until Ctrl-C: the vehicle's half
of the mission protocol for the mission, fence and rally lists, as ArduPilot or PX4 keeps them, with HEARTBEAT and
AUTOPILOT_VERSION. It flies nothing: it is what `wiris mission upload`, `download` and `--verify` talk to.
"""

from __future__ import annotations

import math
import threading

import click

from wiris_tools.cli.options import FiniteRange, connect_option, signing_key_option

# ArduPilot SITL's default home (CMAC, Canberra): where a simulated ArduPilot is when nothing else is said
DEFAULT_HOME = (-35.363262, 149.165237, 584.0)


class HomeType(click.ParamType):
    """LAT,LON,ALT: the vehicle's home in degrees and metres above mean sea level."""

    name = "LAT,LON,ALT"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        parts = str(value).split(",")
        try:
            lat, lon, alt = (float(p) for p in parts)
        except ValueError:
            self.fail(f"{value!r} is not LAT,LON,ALT (three numbers, e.g. -35.363262,149.165237,584)", param, ctx)
        if not (all(map(math.isfinite, (lat, lon, alt))) and -90 <= lat <= 90 and -180 <= lon <= 180):
            self.fail(f"{value!r}: latitude must be -90..90 and longitude -180..180", param, ctx)
        return lat, lon, alt


def _home(value: str) -> tuple[float, float, float]:
    try:
        lat, lon, alt = (float(v) for v in value.split(","))
    except ValueError:
        raise click.BadParameter("write it as LAT,LON,ALT_AMSL_M, e.g. 50.08,14.42,262") from None
    return lat, lon, alt


@click.group()
def sim() -> None:
    """Simulated peers to try the tools against without hardware."""


@sim.command("vehicle")
@connect_option("udpin:127.0.0.1:14550 (a ground station then connects with udpout:127.0.0.1:14550) or "
                "udpout:127.0.0.1:14550 (towards a GCS that listens)")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), required=True,
              help="Whose mission protocol and storage to play.")
@click.option("--system", type=click.IntRange(1, 255), default=1, show_default=True, help="The vehicle's system id.")
@click.option("--home", type=HomeType(), default=None,
              help="ArduPilot's home, item 0 of a downloaded mission (default: SITL's -35.363262,149.165237,584).")
@click.option("--item-limit", type=click.IntRange(1, 65535), default=None,
              help="Mission items the vehicle holds (default: PX4 500, ArduPilot no limit).")
@signing_key_option()
@click.option("--duration", type=FiniteRange(0, None), default=0.0,
              help="Stop after this many seconds (0: run until Ctrl-C).")
def vehicle(url: str, firmware: str, system: int, home: tuple[float, float, float] | None, item_limit: int | None,
            signing_key: str | None, duration: float) -> None:
    """Run a simulated ArduPilot or PX4 vehicle's mission server at --connect until Ctrl-C.

    It keeps a mission, a fence and a rally list as that firmware does (ArduPilot: item 0 of the mission is home,
    altitudes in centimetres; PX4: its item limit and yaw in radians), answers the mission protocol as that
    firmware does, sends HEARTBEAT and answers AUTOPILOT_VERSION requests. It flies nothing.
    """
    from missions.emit.items import FRAME_GLOBAL, MISSION_TYPES, MissionItem, deg_to_e7, mavlink
    from wiris_tools.cli.stopping import sigterm_interrupts
    from wiris_tools.signing import load_signing_key
    from wiris_tools.vehicle_sim import VehicleSim

    key = load_signing_key(signing_key) if signing_key else None
    lat, lon, alt = home or DEFAULT_HOME
    home_item = MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, FRAME_GLOBAL, x=deg_to_e7(lat), y=deg_to_e7(lon), z=alt)
    sim_ = VehicleSim(url, flavour=firmware, system=system, item_limit=item_limit, signing_key=key,
                      home=home_item if firmware == "ardupilot" else None, stores_like_firmware=True)
    port = sim_.port
    shown = url if not url.startswith("udpin:") or port is None else f"{url.rsplit(':', 1)[0]}:{port}"
    stop = threading.Event()
    try:
        with sigterm_interrupts():  # before the first line: whoever reads it may send SIGTERM at once
            click.echo(f"simulated {firmware} vehicle (system {system}) on {shown}", err=True)
            click.echo("Ctrl-C stops it" if not duration else f"stopping after {duration:g} s", err=True)
            stop.wait(duration or None)
    except KeyboardInterrupt:
        pass
    finally:
        held = {kind: len(sim_.items(t)) for kind, t in MISSION_TYPES.items()}
        sim_.close()
    click.echo("vehicle stopped, holding " + ", ".join(f"{n} {kind}" for kind, n in held.items()) + " items",
               err=True)


@sim.command("ardupilot")
@click.option("--sitl-dir", type=click.Path(file_okay=False), default=None,
              help="folder with run-sitl and bin/arducopter, bin/arduplane (default: $WIRIS_SITL_DIR)")
@click.option("--vehicle", type=click.Choice(["copter", "plane"]), default="copter", show_default=True)
@click.option("--camera", "model", default="wiris-pro", show_default=True, help="catalogue camera to emulate")
@click.option("--component", type=click.IntRange(100, 101), default=100, show_default=True,
              help="the camera's component id (ArduPilot finds CAMn at 100 + n - 1: 100 or 101)")
@click.option("--cam-type", type=click.Choice(["5", "6"]), default="6", show_default=True,
              help="CAMn_TYPE: 6 MAVLinkCamV2 (IMAGE_START_CAPTURE), 5 MAVLink (DO_DIGICAM_CONTROL)")
@click.option("--params", "params_file", type=click.Path(exists=True, dir_okay=False), default=None,
              help="load this NAME.params (from `wiris mission compile`) instead of the camera's defaults")
@click.option("--home", default="50.08,14.42,262", show_default=True, help="LAT,LON,ALT_AMSL_M of home")
@click.option("--speedup", type=FiniteRange(0.1, 100), default=1.0, show_default=True,
              help="simulated seconds per second")
@click.option("--workdir", type=click.Path(file_okay=False), default=None,
              help="SITL's working folder: eeprom.bin, logs/ (DataFlash), gcs.tlog, scripts/ for Lua "
                   "(default: a new temporary folder)")
@click.option("--duration", type=FiniteRange(0, None), default=0.0, help="stop after this many seconds (0: Ctrl-C)")
def ardupilot(sitl_dir: str | None, vehicle: str, model: str, component: int, cam_type: str, params_file: str | None,
              home: str, speedup: float, workdir: str | None, duration: float) -> None:
    """Start ArduPilot SITL with the MODEL emulator on its camera link (SERIAL2), set up as NAME.params says,
    and wait until it is ready to arm; then connect QGroundControl or `wiris mission upload` to the printed URL."""
    import sys
    import time
    from pathlib import Path

    from wiris_tools.cli.stopping import sigterm_interrupts
    from wiris_tools.sitl import find_sitl_dir
    from wiris_tools.sitl.flight import desk_sim

    found = find_sitl_dir(sitl_dir)
    if found is None:
        raise click.BadParameter(f"no run-sitl and bin/ in {sitl_dir or '$WIRIS_SITL_DIR'}", param_hint="--sitl-dir")
    try:
        with sigterm_interrupts():
            click.echo("starting ArduPilot SITL …", err=True)
            with desk_sim(found, model=model, component=component, cam_type=int(cam_type), vehicle=vehicle,
                          speedup=speedup, home=_home(home), params_file=Path(params_file) if params_file else None,
                          workdir=Path(workdir) if workdir else None) as sim_:
                click.echo(f"ground station: {sim_.sitl.gcs_url}")
                sys.stdout.flush()   # a script reading the URL through a pipe must get it now
                click.echo(f"camera: {model} as component {component} on SERIAL2 (CAM{component - 99}_TYPE "
                           f"{cam_type}); working folder {sim_.sitl.workdir}", err=True)
                for name in sim_.skipped_params:
                    click.echo(f"note: this firmware has no parameter {name} (skipped)", err=True)
                click.echo("Ctrl-C stops it" if not duration else f"stopping after {duration:g} s", err=True)
                end = time.monotonic() + duration if duration else None
                while end is None or time.monotonic() < end:
                    time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    click.echo("simulation stopped", err=True)
