"""`wiris cdf ...`: camera catalogue and camera definition files."""

from __future__ import annotations

import click


@click.group()
def cdf() -> None:
    """Camera catalogue and camera definition files: list, build, validate, serve."""


@cdf.command()
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def models(as_json: bool) -> None:
    """List the camera catalogue: id, vendor, model, imagers, lenses, component ids."""
    import json

    from cdf.catalogue import catalogue

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
