"""`wiris cdf ...`: camera catalogue and camera definition files."""

from __future__ import annotations

import click

from wiris_tools.cli.options import FiniteRange


@click.group()
def cdf() -> None:
    """Camera catalogue and camera definition files: list, build, validate, serve."""


def _setting_values(s) -> str:
    """What a setting takes, as a plan writes it: its options (one or more flags), or its range."""
    if s.flags and s.enum is not None:
        return "one or more of " + ", ".join(o.key for o in s.enum.options)
    if s.options:
        return ", ".join(o.key for o in s.options)
    return s.range_text().removeprefix("allowed: ")


def _setting_row(s) -> dict:
    return {"plan_name": s.key, "param": s.param, "label": s.label, "type": s.type, "unit": s.unit,
            "default": s.default, "values": _setting_values(s),
            "options": [{"name": o.key, "label": o.name, "value": o.value}
                        for o in (s.enum.options if s.flags and s.enum else s.options)],
            "min": s.min, "max": s.max, "step": s.step, "in_definition": s.in_cdf}


def _print_settings(model: str, as_json: bool) -> None:
    """Every setting of one catalogue camera: the name a plan gives it, its PARAM_EXT name, values, unit."""
    import json

    from cdf.catalogue import catalogue

    cam = catalogue().get(model)
    rows = [_setting_row(s) for s in cam.settings]
    if as_json:
        click.echo(json.dumps({"id": cam.id, "settings": rows}, indent=2))
        return
    takers = "a plan and `wiris camera set` take" if cam.has_cdf else "a plan takes"
    click.echo(f"{cam.id} ({cam.vendor} {cam.model}): {len(rows)} settings; {takers} either name, in any case, "
               "and an option's name or label")
    width = max(len(r["plan_name"]) for r in rows)
    pwidth = max(len(r["param"]) for r in rows)
    for r in rows:
        unit = f" [{r['unit']}]" if r["unit"] else ""
        click.echo(f"  {r['plan_name']:<{width}}  {r['param']:<{pwidth}}  {r['label']}{unit}: {r['values']}")


@cdf.command()
@click.option("--settings", "settings_of", metavar="MODEL", default=None,
              help="List every setting of MODEL (a catalogue id): plan name, PARAM_EXT name, values, unit.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def models(settings_of: str | None, as_json: bool) -> None:
    """List the camera catalogue: id, vendor, model, imagers, lenses, component ids."""
    import json

    from cdf.catalogue import catalogue

    if settings_of is not None:
        _print_settings(settings_of, as_json)
        return
    rows = []
    for cam in catalogue().cameras:
        rows.append({
            "id": cam.id, "vendor": cam.vendor, "model": cam.model, "protocol": cam.protocol,
            "definition": cam.has_cdf, "definition_version": cam.definition_version,
            "camera_protocol_in_manual": cam.camera_protocol,
            "imagers": [{"id": i.id, "known": i.known,
                         "resolution_px": list(i.resolution_px) if i.resolution_px else None,
                         "lenses_mm": list(i.lenses_mm), "assumed": list(i.assumed)} for i in cam.imagers],
            "component_ids": list(cam.component_ids), "mavlink": cam.mavlink_version, "baud": cam.baud,
            "settings": len(cam.settings),
        })
    if as_json:
        click.echo(json.dumps({"models": rows}, indent=2))
        return
    click.echo(f"{'id':<18} {'vendor':<10} {'model':<17} {'imagers (resolution, lenses mm)':<44} components")
    for r in rows:
        imagers = "; ".join(
            f"{i['id']} " + (f"{i['resolution_px'][0]}x{i['resolution_px'][1]}" if i["resolution_px"] else "unknown")
            + (f" {'/'.join(f'{x:g}' for x in i['lenses_mm'])}" if i["lenses_mm"] else "")
            + ("*" if i["assumed"] else "")
            for i in r["imagers"])
        comps = ",".join(str(c) for c in r["component_ids"])
        click.echo(f"{r['id']:<18} {r['vendor']:<10} {r['model']:<17} {imagers:<44} {comps}")
    click.echo("* includes assumed optics (see the catalogue table's notes)")


# --- validate (cdf.validation; rules documented in cdf/schema/RULES.md) ----------------------------------
@cdf.command()
@click.argument("sources", nargs=-1, required=True, metavar="FILE_OR_URL...")
@click.option("--profile", type=click.Choice(["qgc", "mavsdk", "strict"]), default="strict", show_default=True,
              help="qgc: what QGroundControl needs; mavsdk: what MAVSDK needs without dropping anything; "
                   "strict: both plus interoperability warnings.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object per file (one per line).")
@click.option("--timeout", "timeout_s", type=FiniteRange(min=0.1), default=15.0, show_default=True,
              help="Seconds to wait for an http(s) server.")
def validate(sources: tuple[str, ...], profile: str, as_json: bool, timeout_s: float) -> None:
    """Validate camera definition files (plain XML or .xml.xz, paths or http(s) URLs).

    Exit status 1 when any file is invalid in the profile or cannot be read, else 0.
    """
    import json

    from cdf.errors import CdfError
    from cdf.validate import validate_source

    failed = False
    for source in sources:
        try:
            report = validate_source(source, profile, timeout_s=timeout_s)
        except CdfError as err:
            failed = True
            message = err.message + (f" (hint: {err.hint})" if err.hint else "")
            if as_json:
                click.echo(json.dumps({"file": source, "valid": False, "profile": profile, "parameters": 0,
                                       "findings": [{"rule": "CDF001", "severity": "error", "line": None,
                                                     "parameter": None, "message": message}]}))
            else:
                click.echo(f"{source}: ERROR CDF001 {message}")
                click.echo(f"{source}: INVALID ({profile}): cannot be read")
            continue
        failed |= not report.valid
        if as_json:
            click.echo(json.dumps(report.to_json()))
            continue
        for finding in report.findings:
            click.echo(finding.format(report.file))
        counts = {s: sum(f.severity == s for f in report.findings) for s in ("error", "warning", "info")}
        verdict = "valid" if report.valid else "INVALID"
        click.echo(f"{report.file}: {verdict} ({profile}): {report.parameters} parameters, "
                   f"{counts['error']} errors, {counts['warning']} warnings, {counts['info']} info")
    if failed:
        raise SystemExit(1)


# --- build and serve (cdf.bundle, wiris_tools.serve) -------------------------------------------------------
@cdf.command()
@click.argument("model_ids", nargs=-1, metavar="[MODEL]...")
@click.option("--all", "all_models", is_flag=True, help="Every model with a definition (others are skipped with a note).")
@click.option("-o", "--output", "output", required=True, type=click.Path(file_okay=False, path_type=str),
              help="Bundle directory (created if missing).")
@click.option("--base-url", default=None, metavar="URL",
              help="Where DIR will be hosted, e.g. http://192.168.1.10:8000/cdf; each model's URI is URL/FILE "
                   "(at most 139 characters: CAMERA_INFORMATION.cam_definition_uri).")
@click.option("--xz", is_flag=True, help="Also write .xml.xz twins (for MAVLink FTP; serve plain .xml over HTTP).")
@click.option("--json", "as_json", is_flag=True, help="Print the written manifest entries as JSON.")
def build(model_ids: tuple[str, ...], all_models: bool, output: str, base_url: str | None, xz: bool,
          as_json: bool) -> None:
    """Write the hosting bundle: one definition per model, optional .xml.xz twins, manifest.json.

    Every file is validated (strict profile) before anything is written. Published versions are
    immutable: changed content under an existing version is refused (raise definition_version).
    """
    import json
    from dataclasses import asdict

    from cdf.bundle import build_bundle

    result = build_bundle(output, model_ids, all_models=all_models, base_url=base_url, xz=xz)
    if as_json:
        click.echo(json.dumps({"directory": str(result.directory), "models": [asdict(e) for e in result.entries],
                               "written": list(result.written), "unchanged": list(result.unchanged),
                               "skipped": [{"id": i, "reason": r} for i, r in result.skipped]}, indent=2))
        return
    for model_id, reason in result.skipped:
        click.echo(f"note: {model_id} skipped: {reason}", err=True)
    for e in result.entries:
        state = "wrote" if e.file in result.written else "unchanged"
        click.echo(f"{state:<9} {e.file}  {e.bytes} bytes  sha256 {e.sha256[:16]}  {e.uri}")
        if xz:
            twin = e.file + ".xz"
            click.echo(f"{'wrote' if twin in result.written else 'unchanged':<9} {twin}")
    click.echo(f"manifest  {result.directory / 'manifest.json'} ({len(result.manifest)} entries)")


@cdf.command()
@click.argument("directory", type=click.Path(file_okay=False, path_type=str), metavar="DIR")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option("--port", type=click.IntRange(0, 65535), default=8000, show_default=True, help="0 picks a free port.")
@click.option("--prefix", default=None, metavar="PATH",
              help="URL path DIR appears under [default: the path of manifest.json's URIs, else /].")
def serve(directory: str, host: str, port: int, prefix: str | None) -> None:
    """Serve a bundle over HTTP until Ctrl-C or SIGTERM (read-only: GET and HEAD, no escape out of DIR)."""
    from wiris_tools.cli.stopping import sigterm_interrupts
    from wiris_tools.serve import make_server, server_url

    server = make_server(directory, host, port, prefix=prefix)
    try:
        with sigterm_interrupts():  # before the ready line: whoever reads it may send SIGTERM at once
            click.echo(f"serving {directory} at {server_url(server)} (Ctrl-C stops)", err=True)
            server.serve_forever()
    except KeyboardInterrupt:
        click.echo("stopped", err=True)
    finally:
        server.server_close()
