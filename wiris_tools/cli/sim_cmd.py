"""`wiris sim ardupilot`: ArduPilot SITL with the WIRIS emulator on its camera link, until Ctrl-C."""

from __future__ import annotations

import click

from wiris_tools.cli.options import FiniteRange


def _home(value: str) -> tuple[float, float, float]:
    try:
        lat, lon, alt = (float(v) for v in value.split(","))
    except ValueError:
        raise click.BadParameter("write it as LAT,LON,ALT_AMSL_M, e.g. 50.08,14.42,262") from None
    return lat, lon, alt


@click.group()
def sim() -> None:
    """Simulated vehicles to fly compiled plans against on your desk."""


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
