"""`wiris emulate MODEL --connect URL`: a camera emulator that runs until Ctrl-C."""

from __future__ import annotations

import click

from wiris_tools.cli.options import FiniteRange, connect_option, signing_key_option


@click.command()
@click.argument("model")
@connect_option("udpout:127.0.0.1:14550 (towards a GCS) or udpin:0.0.0.0:14560")
@click.option("--component", type=int, default=None, help="Component id (WIRIS: 100–105, default 100).")
@click.option("--system", type=click.IntRange(1, 255), default=1, show_default=True,
              help="System id (a RedEdge adopts its peer's instead).")
@click.option("--http-port", type=click.IntRange(0, 65535), default=0, show_default=True,
              help="Port of the definition's HTTP server (0: a free one).")
@click.option("--http-host", default="127.0.0.1", show_default=True,
              help="Address the definition's HTTP server binds to and names in cam_definition_uri.")
@click.option("--storage-mib", type=FiniteRange(0, None), default=None,
              help="Capacity of each storage in MiB (WIRIS; small values let you test a full storage).")
@click.option("--image-mib", type=FiniteRange(0.001, None), default=None,
              help="Room one image of one format takes in MiB (WIRIS).")
@click.option("--definition-over", "definition_scheme", type=click.Choice(["http", "mftp"]), default="http",
              show_default=True, help="Transport named in cam_definition_uri (WIRIS; MAVLink FTP is always served too).")
@click.option("--ethernet-sdk", is_flag=True, help="Emulate the Ethernet Stream SDK (RTSP streams).")
@click.option("--no-licence", is_flag=True, help="Emulate a camera without the MAVLink licence (ignores commands).")
@signing_key_option()
@click.option("--duration", type=FiniteRange(0, None), default=0.0,
              help="Stop after this many seconds (0: run until Ctrl-C).")
def emulate(model: str, url: str, component: int | None, system: int, http_port: int, http_host: str,
            storage_mib: float | None, image_mib: float | None, definition_scheme: str, ethernet_sdk: bool,
            no_licence: bool,
            signing_key: str | None, duration: float) -> None:
    """Run the emulator of catalogue camera MODEL (see `wiris cdf models`) until Ctrl-C.

    A WIRIS answers the Workswell manual's commands and PARAM_EXT, and serves its camera definition over
    HTTP; a RedEdge speaks its serial API (MAVLink 1, DIGICAM_CONTROL message, classic parameters).
    """
    from wiris_tools.cli.stopping import sigterm_interrupts
    from wiris_tools.emulate.runner import start_emulator
    from wiris_tools.signing import load_signing_key

    key = load_signing_key(signing_key) if signing_key else None
    storage = (storage_mib,) * 3 if storage_mib is not None else None
    emu = start_emulator(model, url, component=component, system=system, http_port=http_port, http_host=http_host,
                         signing_key=key, storage_capacity_mib=storage, image_size_mib=image_mib,
                         ethernet_sdk=ethernet_sdk, licensed=not no_licence, definition_scheme=definition_scheme)
    cam = emu.camera
    comp = getattr(emu.state, "config", None)
    comp_id = comp.component if comp is not None else emu.state.component
    port = emu.link.local_port
    shown = url if not url.startswith("udpin:") or port is None else f"{url.rsplit(':', 1)[0]}:{port}"
    try:
        with sigterm_interrupts():  # before the first line: whoever reads it may send SIGTERM at once
            click.echo(f"emulating {cam.vendor} {cam.model} as component {comp_id} on {shown}"
                       + (" (MAVLink 1)" if cam.mavlink_version == 1 else ""), err=True)
            if emu.definition_uri:
                click.echo(f"camera definition: {emu.definition_uri}", err=True)
            click.echo("Ctrl-C stops it" if not duration else f"stopping after {duration:g} s", err=True)
            emu.wait(duration or None)
    except KeyboardInterrupt:
        pass
    finally:
        emu.close()
    click.echo("emulator stopped", err=True)
