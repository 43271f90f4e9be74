"""`wiris mission upload` and `wiris mission download`: thin commands over wiris_tools.transfer.

Registered on the `mission` group at the bottom of mission_cmd.py. Only click and the standard
library are imported here at module level; pymavlink comes in with wiris_tools.transfer inside the
commands.
"""

from __future__ import annotations

import sys
from contextlib import contextmanager

import click

from wiris_tools.cli.jsonout import echo_json
from wiris_tools.cli.options import FiniteRange, connect_option, signing_key_option

TYPES = ("mission", "fence", "rally")


def _connect_options(f):
    options = [
        connect_option(),
        signing_key_option(),
        click.option("--target-system", type=click.IntRange(1, 255), default=None,
                     help="the vehicle's system id (default: the first autopilot heard)"),
        click.option("--target-component", type=click.IntRange(0, 255), default=1, show_default=True,
                     help="the autopilot's component id"),
        click.option("--timeout", type=FiniteRange(0.1, 600), default=10.0, show_default=True,
                     help="seconds to wait for the vehicle's HEARTBEAT"),
        click.option("--json", "as_json", is_flag=True, help="print the result as JSON (no progress bar)"),
    ]
    for option in reversed(options):   # decorators apply bottom-up; keep --help in this order
        f = option(f)
    return f


@contextmanager
def _link(url: str, signing_key: str | None):
    from wiris_tools.link import Link
    from wiris_tools.signing import load_signing_key

    key = load_signing_key(signing_key) if signing_key else None
    link = Link(url, signing_key=key)
    try:
        yield link
    finally:
        link.close()


@contextmanager
def _progress(label: str, quiet: bool):
    """A progress bar on a terminal; nothing when output is piped or --json is given."""
    if quiet or not sys.stderr.isatty():
        yield None
        return
    with click.progressbar(length=1, label=label, file=sys.stderr, show_pos=True) as bar:
        state = {"done": 0}

        def update(done: int, total: int) -> None:
            bar.length = max(total, 1)
            if done > state["done"]:
                bar.update(done - state["done"])
                state["done"] = done

        yield update


@click.command("upload")
@click.argument("file", type=click.Path(exists=True, dir_okay=False))
@click.option("--type", "kind", type=click.Choice(TYPES), default="mission", show_default=True,
              help="which list to upload (fence from a .plan or a capture plan, rally from a .plan, or a fence/rally "
                   "WPL file as Mission Planner saves one)")
@click.option("--verify", is_flag=True,
              help="download again after the upload and compare each item as the vehicle's firmware keeps it")
@click.option("--sortie", "--part", "part", type=click.IntRange(1), default=None,
              help="for a capture plan flown in sorties (longer than a battery or the item limit): the sortie "
                   "to upload (a compiled NAME.sortieN.plan uploads as it is)")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), default=None,
              help="for a capture plan: compile for this firmware instead of the vehicle's")
@click.option("--force", is_flag=True,
              help="upload even when the file was made for another firmware than the vehicle reports")
@_connect_options
def upload(file: str, kind: str, verify: bool, part: int | None, firmware: str | None, force: bool, url: str,
           signing_key: str | None, target_system: int | None, target_component: int, timeout: float,
           as_json: bool) -> None:
    """Upload FILE (.plan, .waypoints, a sortie's NAME.sortieN.plan or a capture plan .yaml) to the vehicle at
    --connect.

    A .plan made for ArduPilot or PX4 (its firmwareType) is refused by a vehicle whose HEARTBEAT reports the
    other (--force uploads it anyway); a capture plan is compiled for the vehicle's firmware."""
    from missions.emit.items import MISSION_TYPES
    from wiris_tools.transfer import load_for_upload, upload_file

    loaded = load_for_upload(file, MISSION_TYPES[kind], part=part, firmware=firmware)  # fails before connecting
    if not as_json:
        for note in loaded.notes:
            click.echo(f"warning: {note}", err=True)
    with _link(url, signing_key) as link, _progress(f"upload {kind}", as_json) as progress:
        summary = upload_file(link, file, mission_type=MISSION_TYPES[kind], verify=verify,
                              target_system=target_system, target_component=target_component, timeout=timeout,
                              progress=progress, loaded=loaded, force=force, firmware=firmware)
    if as_json:
        echo_json(summary, indent=1)
        return
    extra = []
    if summary["home_row"]:
        extra.append("item 0 is home (ArduPilot)")
    if summary["resent"]:
        extra.append(f"{summary['resent']} resent")
    if summary["nacks_tolerated"]:
        extra.append(f"{summary['nacks_tolerated']} transient NACKs tolerated")
    click.echo(f"uploaded {summary['items']} {kind} items to system {summary['target_system']} "
               f"({summary['autopilot']}) in {summary['seconds']:.2f} s"
               + (", verified by read-back" if summary["verified"] else "")
               + (f" ({'; '.join(extra)})" if extra else ""))
    for note in summary["notes"]:
        click.echo(f"note: {note}")


@click.command("download")
@click.option("-o", "--output", "out", required=True, type=click.Path(dir_okay=False),
              help="FILE.plan (mission, fence and rally) or FILE.waypoints (mission)")
@click.option("--deadline", "deadline_s", type=FiniteRange(0.1, 7 * 24 * 3600), default=None, metavar="SECONDS",
              help="give up when one list (mission, fence or rally) takes longer than this to download "
                   "(default: 30 s plus 8 round trips, as measured on the link, for each item the vehicle reports)")
@_connect_options
def download(out: str, deadline_s: float | None, url: str, signing_key: str | None, target_system: int | None,
             target_component: int, timeout: float, as_json: bool) -> None:
    """Save what the vehicle at --connect holds (.plan or .waypoints by suffix, written atomically)."""
    from wiris_tools.transfer import download_file

    if not out.lower().endswith((".plan", ".waypoints", ".wpl", ".txt")):
        raise click.BadParameter("the output must end in .plan or .waypoints", param_hint="-o/--output")
    with _link(url, signing_key) as link, _progress("download mission", as_json) as progress:
        summary = download_file(link, out, target_system=target_system, target_component=target_component,
                                timeout=timeout, progress=progress, deadline_s=deadline_s)
    if as_json:
        echo_json(summary, indent=1)
        return
    counts = ", ".join(f"{n} {k}" for k, n in summary["items"].items())
    click.echo(f"downloaded {counts} items from system {summary['target_system']} in {summary['seconds']:.2f} s "
               f"to {summary['file']}")
    for note in summary["notes"]:
        click.echo(f"note: {note}")
