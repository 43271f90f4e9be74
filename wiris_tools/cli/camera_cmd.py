"""`wiris camera ...`: talk to a MAVLink camera (identify, settings, capture, apply a command sequence)."""

from __future__ import annotations

import contextlib
import functools
import math
import sys

import click

from wiris_tools.cli.jsonout import echo_json
from wiris_tools.cli.options import FiniteRange, connect_option, signing_key_option


def _link_options(fn):
    @connect_option()
    @click.option("--component", type=click.IntRange(0, 255), default=None,
                  help="The camera's component id (default: the first camera heard, 100–105 or MAV_TYPE_CAMERA).")
    @click.option("--system", type=click.IntRange(1, 255), default=None, help="The camera's system id.")
    @signing_key_option()
    @click.option("--mavlink1", is_flag=True, help="Send MAVLink 1 frames (a RedEdge's serial API).")
    @click.option("--timeout", type=FiniteRange(0.05, 60), default=1.0, show_default=True,
                  help="Seconds to wait for each answer (each request is retried 3 times; one the camera "
                       "reports in progress is waited for up to 10 times this).")
    @click.option("--wait", "find_s", type=FiniteRange(0.1, 600), default=5.0, show_default=True,
                  help="Seconds to wait for the camera's HEARTBEAT.")
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        return fn(*args, **kwargs)

    return wrapper


@contextlib.contextmanager
def _camera(url, component, system, signing_key, mavlink1, timeout, find_s):
    from wiris_tools.camera_client import CameraClient
    from wiris_tools.link import Link
    from wiris_tools.signing import load_signing_key

    key = load_signing_key(signing_key) if signing_key else None
    with Link(url, signing_key=key, mavlink1=mavlink1) as link:
        yield CameraClient(link, component=component, system=system, find_timeout_s=find_s, timeout_s=timeout)


def _echo_json(obj) -> None:
    echo_json(obj, indent=2)


def _num(v) -> str:
    if v is None:
        return "?"
    if isinstance(v, float):
        if math.isnan(v):
            return "NaN"
        return f"{v:.6g}"
    return str(v)


def _progress(as_json: bool):
    """A download progress line on a terminal; nothing when piped or with --json."""
    if as_json or not sys.stderr.isatty():
        return None

    def show(done: int, total: int) -> None:
        click.echo(f"\rdownloading the camera definition: {done}/{total} bytes", err=True, nl=done >= total)

    return show


def _findings(report, as_json: bool) -> None:
    if as_json or not report.findings:
        return
    for f in report.findings:
        click.echo("  " + f.format("definition"), err=True)


@click.group()
def camera() -> None:
    """Talk to a MAVLink camera: identify it, read and change settings, capture, run a setup sequence."""


@camera.command()
@_link_options
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def info(url, component, system, signing_key, mavlink1, timeout, find_s, as_json) -> None:
    """CAMERA_INFORMATION, storage and capture status (a part the camera refuses to report is "not
    reported", null with --json)."""
    with _camera(url, component, system, signing_key, mavlink1, timeout, find_s) as cam:
        information = cam.information()
        storage = cam.storage()            # None: the camera answered UNSUPPORTED or DENIED
        status = cam.capture_status()
    if as_json:
        _echo_json({"camera": information.to_json(), "storage": storage, "capture_status": status})
        return
    i = information
    click.echo(f"{i.vendor} {i.model} (system {i.system}, component {i.component})")
    click.echo(f"  resolution {i.resolution_px[0]}x{i.resolution_px[1]}, focal length {_num(i.focal_length_mm)} mm, "
               f"lens {i.lens_id}")
    click.echo(f"  capabilities: {', '.join(i.flag_names) or 'none'} (0x{i.flags:x})")
    click.echo(f"  definition v{i.definition_version}: {i.definition_uri or '(none)'}")
    if storage is None:
        click.echo("  storage: not reported (the camera refused the request)")
    for s in storage or ():
        click.echo(f"  storage {s['id']} {s['name'] or ''}: {_num(s['available_mib'])} of {_num(s['total_mib'])} MiB free")
    if status is None:
        click.echo("  capture: not reported (the camera refused the request)")
    else:
        click.echo(f"  capture: image status {status['image_status']}, video status {status['video_status']}, "
                   f"interval {_num(status['image_interval_s'])} s, {status['image_count']} images this session")


@camera.command()
@_link_options
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def settings(url, component, system, signing_key, mavlink1, timeout, find_s, as_json) -> None:
    """Every setting of the camera's definition with its current value."""
    with _camera(url, component, system, signing_key, mavlink1, timeout, find_s) as cam:
        information = cam.information()
        loaded = cam.definition(information, progress=_progress(as_json))
        values = cam.read_settings(loaded.definition)
        report = cam.check_against_camera(loaded, information)
    d = loaded.definition
    rows = [{"name": p.name, "description": p.description, "type": p.type, "value": values.get(p.name),
             "option": p.label_of(values.get(p.name)), "options": [{"value": o.value, "name": o.label} for o in p.options],
             "min": p.min, "max": p.max} for p in d.params]
    if as_json:
        _echo_json({"camera": information.to_json(), "definition": {"uri": loaded.uri, "valid": report.valid,
                    "findings": [f.to_json() for f in report.findings]}, "settings": rows})
        return
    state = "valid" if report.valid else "INVALID"
    click.echo(f"{information.vendor} {information.model}: definition v{d.version} ({state}, "
               f"{len(report.findings)} findings) from {loaded.uri}")
    _findings(report, as_json)
    width = max((len(r["name"]) for r in rows), default=4)
    for r in rows:
        shown = _num(r["value"]) + (f"  {r['option']}" if r["option"] else "")
        extra = ""
        if r["options"]:
            extra = " [" + ", ".join(f"{o['value']}={o['name']}" for o in r["options"][:8]) \
                    + (", ..." if len(r["options"]) > 8 else "") + "]"
        elif r["min"] is not None or r["max"] is not None:
            extra = f" [{_num(r['min'])}..{_num(r['max'])}]"
        click.echo(f"  {r['name']:<{width}}  {shown:<24} {r['description']}{extra}")
    missing = [r["name"] for r in rows if r["value"] is None]
    if missing:
        click.echo(f"the camera did not report: {', '.join(missing)}", err=True)


# ignore_unknown_options: a negative VALUE ("-20", a temperature) is taken as the value, not as an option
@camera.command(name="set", context_settings={"ignore_unknown_options": True})
@click.argument("name")
@click.argument("value")
@_link_options
@click.option("--json", "as_json", is_flag=True, help="Print the acknowledged value as JSON.")
def set_(name, value, url, component, system, signing_key, mavlink1, timeout, find_s, as_json) -> None:
    """Set NAME to VALUE: PARAM_EXT_SET, waits for the ACK. NAME is the definition's parameter (RANGE_MODE) or
    the setting's name in a capture plan (range_mode), any case; VALUE an option as the definition labels it
    or as a plan writes it (Manual, manual), or a number, also a negative one such as -20. `wiris cdf models
    --settings MODEL` lists both names."""
    from cdf.catalogue import catalogue
    from wiris_tools.camera_client import resolve_param

    with _camera(url, component, system, signing_key, mavlink1, timeout, find_s) as cam:
        information = cam.information()
        loaded = cam.definition(information, progress=_progress(as_json))
        if not loaded.report.valid:
            _findings(loaded.report, as_json)
        known = catalogue().find_model(information.vendor, information.model)
        p = resolve_param(loaded.definition, name, known)
        held = cam.set_setting(loaded.definition, p.name, value, known)
    name = p.name
    label = p.label_of(held)
    if as_json:
        _echo_json({"name": name, "value": held, "option": label, "acknowledged": True})
        return
    click.echo(f"{name} = {_num(held)}" + (f" ({label})" if label else "") + " (acknowledged)")


@camera.command()
@_link_options
@click.option("--interval", "interval_s", type=FiniteRange(0, None), default=0.0, show_default=True,
              help="Seconds between images (periodic capture).")
@click.option("--count", type=click.IntRange(0, None), default=1, show_default=True,
              help="Number of images (0: until Ctrl-C or --duration).")
@click.option("--duration", "duration_s", type=FiniteRange(0, None), default=None,
              help="Stop after this many seconds.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object per image.")
def capture(url, component, system, signing_key, mavlink1, timeout, find_s, interval_s, count, duration_s,
            as_json) -> None:
    """IMAGE_START_CAPTURE, then print each CAMERA_IMAGE_CAPTURED."""
    with _camera(url, component, system, signing_key, mavlink1, timeout, find_s) as cam:
        n = 0
        try:
            for shot in cam.capture(interval_s=interval_s, count=count, duration_s=duration_s):
                n += 1
                if as_json:
                    echo_json(shot.to_json())
                else:
                    click.echo(f"image {shot.index}: {shot.file or '(failed)'} at {shot.lat / 1e7:.7f}, "
                               f"{shot.lon / 1e7:.7f}, {shot.alt_mm / 1000:.1f} m")
        except KeyboardInterrupt:
            click.echo("stopped", err=True)
    if not as_json:
        click.echo(f"{n} image(s)", err=True)


@camera.command()
@click.argument("setup_file", type=click.Path(dir_okay=False))
@_link_options
@click.option("--payload", default=None, metavar="NAME",
              help="Run only the steps of this payload of the plan (e.g. thermal), in their order.")
@click.option("--json", "as_json", is_flag=True, help="Print the step results as JSON.")
def apply(setup_file, url, component, system, signing_key, mavlink1, timeout, find_s, payload, as_json) -> None:
    """Run the pre-flight command sequence of SETUP_FILE (NAME.setup.json), each step acknowledged (a RedEdge's
    DIGICAM_CONFIGURE, which it never answers, is sent repeatedly instead)."""
    from wiris_tools.camera_client import load_setup, steps_of_payload

    steps = load_setup(setup_file)       # checked completely before anything is sent
    if payload is not None:
        steps = steps_of_payload(steps, payload, setup_file)
        if component is None:               # the camera of that payload, not the first one heard
            component = steps[0].target_component or None
    done = []

    def report(result) -> None:
        done.append(result)
        if not as_json:
            click.echo(f"{result.step.label}: {result.outcome}" + (f" {result.detail}" if result.detail else ""))

    with _camera(url, component, system, signing_key, mavlink1, timeout, find_s) as cam:
        try:
            cam.apply(steps, on_step=report)
        except Exception:
            if as_json:
                _echo_json({"file": setup_file, "completed": [r.to_json() for r in done], "ok": False})
            else:
                click.echo(f"{len(done)} of {len(steps)} steps done before the failure", err=True)
            raise
    if as_json:
        _echo_json({"file": setup_file, "completed": [r.to_json() for r in done], "ok": True})
    else:
        unanswered = sum(1 for r in done if r.outcome == "SENT")
        if unanswered:
            click.echo(f"all {len(steps)} steps done: {len(steps) - unanswered} acknowledged, {unanswered} sent to "
                       "a camera that does not answer them")
        else:
            click.echo(f"all {len(steps)} steps acknowledged")
