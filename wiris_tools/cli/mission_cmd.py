"""`wiris mission ...`: compile capture plans, check and preview them, move missions to and from a vehicle."""

from __future__ import annotations

import contextlib

import click


@click.group()
def mission() -> None:
    """Capture plans to missions: schema, compile, check, preview, upload, download."""


# --- schema, compile, check, preview (the compiler's commands; upload/download live below) -------------------

def _compile(plan: str, firmware: str | None):
    from missions.compile import compile_plan
    return compile_plan(plan, firmware=firmware)


@contextlib.contextmanager
def _located(plan: str):
    """A PlanError from measuring the compiled mission (the report, the preview) names no place of its
    own: it is about the plan as a whole, so it is located at the plan file."""
    from missions.errors import PlanError

    try:
        yield
    except PlanError as err:
        if err.where is None:
            err.where = plan
        raise


@mission.command("schema")
def schema_cmd() -> None:
    """Print the JSON Schema of the capture-plan format (for editors)."""
    import json

    from missions.plan.schema import plan_schema
    click.echo(json.dumps(plan_schema(), indent=2))


@mission.command("compile")
@click.argument("plan", type=click.Path(dir_okay=False))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="directory for NAME.plan, NAME.waypoints, NAME.geojson, NAME.kml, NAME.setup.json, ...")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), help="override the plan's vehicle.firmware")
def compile_cmd(plan: str, out_dir: str, firmware: str | None) -> None:
    """Compile PLAN.yaml into mission files in a directory (all or nothing)."""
    from missions.formats.outputs import write_outputs
    from missions.measure.flight import simulate
    from missions.measure.report import report, summary_lines

    compiled = _compile(plan, firmware)
    with _located(plan):
        sim = simulate(compiled)
        rep = report(compiled, sim, plan_path=plan)
    for line in summary_lines(rep):
        click.echo(line)
    if rep.errors:   # a mission that cannot be flown is not written (`check` shows the whole report)
        click.echo(f"not written: {len(rep.errors)} error(s)", err=True)
        raise click.exceptions.Exit(1)
    paths = write_outputs(compiled, out_dir, rep=rep, sim=sim)
    click.echo("wrote:")
    for p in paths:
        click.echo(f"  {p}")


@mission.command("check")
@click.argument("plan", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="print the report as JSON")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), help="override the plan's vehicle.firmware")
def check_cmd(plan: str, as_json: bool, firmware: str | None) -> None:
    """Compile PLAN.yaml in memory and print the measured report (exit 1 when it has errors)."""
    import json

    from missions.errors import PlanError
    from missions.measure.report import error_report, format_report, report

    try:
        with _located(plan):
            rep = report(_compile(plan, firmware), plan_path=plan)
    except PlanError as err:
        if not as_json:
            raise
        click.echo(json.dumps(error_report(plan, err).to_json(), indent=1))
        click.echo(f"error: {err}", err=True)
        raise click.exceptions.Exit(1)
    click.echo(json.dumps(rep.to_json(), indent=1, allow_nan=False) if as_json else format_report(rep))
    if rep.errors:
        raise click.exceptions.Exit(1)


@mission.command("preview")
@click.argument("plan", type=click.Path(dir_okay=False))
@click.option("-o", "--output", "out", required=True, type=click.Path(dir_okay=False),
              help="FILE.svg, FILE.png or FILE.html")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), help="override the plan's vehicle.firmware")
@click.option("--tiles", metavar="URL_TEMPLATE",
              help="HTML only: a basemap from this XYZ tile server, e.g. https://tile.openstreetmap.org/{z}/{x}/{y}.png "
                   "(without it the page makes no network request)")
@click.option("--attribution", metavar="TEXT", help="the basemap's attribution shown on the map "
              "(default: OpenStreetMap's for its servers, else the tile host)")
def preview_cmd(plan: str, out: str, firmware: str | None, tiles: str | None, attribution: str | None) -> None:
    """Draw the compiled mission: area, path, photo footprints, scale, legend; FILE.html is an interactive map
    (pan, zoom, layers to toggle, every item clickable) that works offline."""
    from missions.formats.preview import write_preview
    from missions.formats.webmap import TileSource

    source = TileSource.parse(tiles, attribution) if tiles is not None else None
    compiled = _compile(plan, firmware)
    with _located(plan):
        click.echo(f"wrote {write_preview(compiled, out, source)}")

@mission.command("audit")
@click.argument("plan", type=click.Path(dir_okay=False))
@click.argument("logs", metavar="LOG...", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("-o", "--output", "out_dir", type=click.Path(file_okay=False),
              help="directory for NAME.audit.json, NAME.gaps.geojson, NAME.audit.png and the refly plan "
                   "NAME-refly.yaml with its mission in NAME-refly/")
@click.option("--json", "as_json", is_flag=True, help="print the audit as JSON")
@click.option("--images", "images_dir", type=click.Path(file_okay=False),
              help="the folder of the flight's JPEGs: matched to the captures by the number in their names or by "
                   "EXIF time; their XMP gimbal angles (DJI's or Pix4D's tags) place their footprints")
@click.option("--mount", type=click.Choice(["gimbal", "fixed"]), default="gimbal", show_default=True,
              help="gimbal: the camera looks straight down; fixed: the airframe's logged pitch and roll tilt it")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), help="override the plan's vehicle.firmware")
def audit_cmd(plan: str, logs: tuple[str, ...], out_dir: str | None, as_json: bool, images_dir: str | None,
              mount: str, firmware: str | None) -> None:
    """Audit a flight: what LOG (.tlog, DataFlash .BIN or PX4 .ulg) says was captured against PLAN.yaml --
    coverage from the captured footprints, overlaps, missing photos, gaps, where the flight left the plan.
    Several LOGs of one plan (its sorties, or a mission resumed after a battery swap) are audited each
    against the sortie it flew and all together: the union decides what is left to refly."""
    from wiris_tools.audit.logs import read_log
    from wiris_tools.audit.measure import audit_flight, format_audit
    from wiris_tools.cli.jsonout import echo_json

    compiled = _compile(plan, firmware)
    with _located(plan):
        flight_logs = [read_log(log) for log in logs]
        images = None
        if images_dir:
            from wiris_tools.audit.images import read_folder
            images = read_folder(images_dir)
        if len(flight_logs) == 1:
            result = audit_flight(compiled, flight_logs[0], plan, mount=mount, images=images)
            union, doc, text = result, result.to_json(), format_audit(result)
        else:
            from wiris_tools.audit.flights import audit_flights, format_multi
            multi = audit_flights(compiled, flight_logs, plan, mount=mount, images=images)
            union, doc, text = multi.union, multi.to_json(), format_multi(multi)
        paths = []
        if out_dir:
            from wiris_tools.audit.outputs import write_audit
            paths = write_audit(out_dir, compiled, union, plan, doc)
    if as_json:
        echo_json({**doc, "written": [str(p) for p in paths]}, indent=1)
        return
    click.echo(text)
    if paths:
        click.echo("wrote:")
        for p in paths:
            click.echo(f"  {p}")


# --- end of the compiler's commands ----------------------------------------------------------------------------


# --- upload / download (wiris_tools/cli/transfer_cmd.py) --------------------------------------------------------
from wiris_tools.cli.transfer_cmd import download as _download_cmd, upload as _upload_cmd  # noqa: E402

mission.add_command(_upload_cmd)
mission.add_command(_download_cmd)


# --- convert (missions/formats/convert.py) -----------------------------------------------------------------------

@mission.command("convert")
@click.argument("src", metavar="IN", type=click.Path(dir_okay=False))
@click.option("-o", "--output", "out", required=True, type=click.Path(dir_okay=False),
              help="OUT.plan, OUT.waypoints (.wpl, .txt), OUT.geojson or OUT.kml, written atomically")
@click.option("--type", "only", type=click.Choice(["mission", "fence", "rally"]), default=None,
              help="convert this list only (a .waypoints holds one list: needed when IN holds several)")
@click.option("--firmware", type=click.Choice(["ardupilot", "px4"]), default=None,
              help="for a .plan output: the firmwareType to write (default: IN's, or generic)")
@click.option("--json", "as_json", is_flag=True, help="print the result as JSON")
def convert_cmd(src: str, out: str, only: str | None, firmware: str | None, as_json: bool) -> None:
    """Convert IN (.plan, or a WPL 110 .waypoints/.txt) to OUT by its suffix: .plan holds mission, fence and
    rally; .waypoints one list; .geojson/.kml draw them all. What IN's reader repaired is printed as a warning."""
    from missions.formats.convert import convert_file
    from wiris_tools.cli.jsonout import echo_json

    result = convert_file(src, out, only=only, firmware=firmware)
    if as_json:
        echo_json({"file": str(result.out), "items": result.counts, "warnings": [str(n) for n in result.notes]},
                  indent=1)
        return
    for note in result.notes:
        click.echo(f"warning: {note}", err=True)
    counts = ", ".join(f"{n} {kind}" for kind, n in result.counts.items())
    click.echo(f"wrote {result.out}: {counts} items")
