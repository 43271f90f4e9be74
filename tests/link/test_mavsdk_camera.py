"""MAVSDK 4.1.0's camera plugin (a real ground station) against the WIRIS emulator of every Workswell model,
and MAVProxy's camera-definition parser on every definition the emulator serves over HTTP.

MAVSDK runs in one subprocess for all models (it can crash the process; its CDF cache lives under a fresh
HOME): this file is also that subprocess's script (`python test_mavsdk_camera.py MODEL ...`), printing one
JSON line per model.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

MARK = "@@MODEL "
SETS_A = (("CAM_EXPMODE", "3"), ("LAYOUT", "3"), ("ALARM_MODE", "4"), ("RANGE_MODE", "1"), ("MAIN_CAMERA", "1"))
SETS_B = (("RANGE_MODE", "2"),)


# -- the subprocess ------------------------------------------------------------------------------
def _run_model(job: str) -> dict:
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.camera import Camera, CameraError, Option, Setting

    from wiris_tools.emulate.runner import start_emulator

    model, _, scheme = job.partition("@")
    emu = start_emulator(model, "udpin:127.0.0.1:0", definition_scheme=scheme or "http")
    gcs = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    result: dict = {"model": job, "uri": emu.definition_uri}
    captured: list = []
    try:
        gcs.add_any_connection(f"udpout://127.0.0.1:{emu.link.local_port}")
        deadline = time.time() + 15
        while not gcs.get_systems() and time.time() < deadline:
            time.sleep(0.05)
        systems = gcs.get_systems()
        if not systems:
            return result | {"outcome": "no-system"}
        cam = Camera(systems[0])
        cam.subscribe_capture_info(lambda info, _: captured.append((info.index, info.is_success)))
        options = None
        while time.time() < deadline:
            try:
                options = cam.get_possible_setting_options(100)
                if options:
                    break
            except CameraError:
                pass
            time.sleep(0.1)
        if not options:
            return result | {"outcome": "no-settings"}
        time.sleep(1.5)     # the PARAM_EXT_REQUEST_READ round trips, one per parameter
        result["settings"] = {so.setting_id: [o.option_id for o in so.options]
                              for so in cam.get_possible_setting_options(100)}
        result["current"] = {s.setting_id: s.option.option_id for s in cam.get_current_settings(100)}
        sets = {}

        def set_all(pairs) -> None:
            for name, option in pairs:
                if name not in {so.setting_id for so in cam.get_possible_setting_options(100)}:
                    continue
                try:
                    cam.set_setting(100, Setting(setting_id=name, option=Option(option_id=option)))
                    sets[name] = "ok"
                except CameraError as err:
                    sets[name] = f"error {err}"
            time.sleep(0.5)

        # options that reveal the settings their defaults hide (the definition's exclusions)
        set_all(SETS_A)
        with emu.lock:
            result["state_after_set"] = {n: emu.state.values.get(n) for n in sets}
            result["camera_settings_mode_id"] = emu.state.camera_settings(time.monotonic()).mode_id
        result["snapshots"] = [{"values": {k: result["current"][k] for k in result["current"]},
                                "settings": result["settings"]}]
        result["snapshots"].append({"values": {s.setting_id: s.option.option_id for s in cam.get_current_settings(100)},
                                    "settings": {so.setting_id: [o.option_id for o in so.options]
                                                 for so in cam.get_possible_setting_options(100)}})
        set_all(SETS_B)
        result["snapshots"].append({"values": {s.setting_id: s.option.option_id for s in cam.get_current_settings(100)},
                                    "settings": {so.setting_id: [o.option_id for o in so.options]
                                                 for so in cam.get_possible_setting_options(100)}})
        result["sets"] = sets
        before = emu.state.image_count
        try:
            cam.take_photo(100)
            result["take_photo"] = "ok"
        except CameraError as err:
            result["take_photo"] = f"error {err}"
        end = time.time() + 3
        while not captured and time.time() < end:
            time.sleep(0.05)
        result["captured"] = list(captured)
        result["emulator_images"] = emu.state.image_count - before
        result["emulator_errors"] = emu.errors
        return result | {"outcome": "ok"}
    finally:
        gcs.destroy()
        emu.close()


def _main(models: list[str]) -> None:
    import mavsdk

    mavsdk.log_subscribe(lambda *a: True)   # silence MAVSDK's own stdout log
    for model in models:
        try:
            res = _run_model(model)
        except Exception as err:  # report and go on with the next model
            res = {"model": model, "outcome": f"harness-error {type(err).__name__}: {err}"}
        sys.stdout.write(MARK + json.dumps(res) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    _main(sys.argv[1:])
    sys.exit(0)


# -- the tests -----------------------------------------------------------------------------------
from cdf.catalogue import catalogue  # noqa: E402

WORKSWELL = [c.id for c in catalogue().cameras if c.protocol == "workswell-mavlink"]


def _hidden(definition, values) -> set[str]:
    """Parameters a GCS hides for the current values (the definition's option exclusions)."""
    from lxml import etree

    root = etree.fromstring(definition)
    hidden = set()
    for p in root.iter("parameter"):
        value = values.get(p.get("name"))
        for o in p.iter("option"):
            if value is not None and float(o.get("value")) == float(value):
                hidden |= {e.text for e in o.iter("exclude")}
    return hidden


@pytest.fixture(scope="module")
def mavsdk_results(tmp_path_factory):
    pytest.importorskip("mavsdk")
    work = tmp_path_factory.mktemp("mavsdk")
    (work / "home").mkdir()
    (work / "tmp").mkdir()
    env = dict(os.environ, HOME=str(work / "home"), TMPDIR=str(work / "tmp"))
    jobs = [*WORKSWELL, f"{WORKSWELL[0]}@mftp"]      # one model with its definition over MAVLink FTP
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), *jobs], capture_output=True, text=True,
                          env=env, timeout=60 * len(jobs))
    results = {}
    for line in proc.stdout.splitlines():
        if line.startswith(MARK):
            r = json.loads(line[len(MARK):])
            results[r["model"]] = r
    assert results, f"MAVSDK subprocess gave nothing (rc {proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
    return results


@pytest.mark.peer
@pytest.mark.slow
@pytest.mark.parametrize("job", [*WORKSWELL, f"{WORKSWELL[0]}@mftp"])
def test_mavsdk_camera_plugin_uses_the_emulator(mavsdk_results, job):
    from cdf.generate import definition_xml
    from wiris_tools.camera_definition import parse_definition

    r = mavsdk_results.get(job)
    assert r is not None, "the MAVSDK subprocess died before this model"
    assert r["outcome"] == "ok", r
    model, _, scheme = job.partition("@")
    assert r["uri"].startswith(f"{scheme or 'http'}://")
    data = definition_xml(catalogue().get(model))
    d = parse_definition(data)
    defaults = {p.name: p.default for p in d.params}
    for name, value in r["current"].items():
        assert float(value) == pytest.approx(float(defaults[name]), rel=1e-6), name
    seen = set()
    values = dict(defaults)
    for snap in r["snapshots"]:
        # MAVSDK lists exactly the settings the definition's exclusions leave visible for the current values
        values.update({k: float(v) for k, v in snap["values"].items()})
        expected_visible = {p.name for p in d.params if p.control} - _hidden(data, values)
        assert set(snap["settings"]) == expected_visible
        seen |= expected_visible
        for p in d.params:
            if p.name in snap["settings"] and p.options:
                assert [float(x) for x in snap["settings"][p.name]] == [float(o.value) for o in p.options], p.name
            elif p.name in snap["settings"]:
                assert [float(x) for x in snap["settings"][p.name]][:2] == [p.min, p.max], p.name
    assert seen == {p.name for p in d.params if p.control}       # every setting was listed at some point
    # set_setting reached the camera's one state, and the command side reports it
    assert set(r["sets"].values()) == {"ok"}, r["sets"]
    expected = dict((k, int(v)) for k, v in SETS_A)
    assert r["state_after_set"] == {k: expected[k] for k in r["state_after_set"]}
    assert "LAYOUT" in r["sets"] and "MAIN_CAMERA" in r["sets"]
    assert r["camera_settings_mode_id"] == 1          # CAMERA_SETTINGS reports the main camera (§6.4.2)
    assert r["take_photo"] == "ok" and r["emulator_images"] == 1 and r["captured"] == [[0, True]]
    assert r["emulator_errors"] == 0


@pytest.mark.peer
@pytest.mark.parametrize("model", WORKSWELL)
def test_mavproxy_parses_what_the_emulator_serves(model):
    import peers

    from wiris_tools.emulate.runner import start_emulator

    with start_emulator(model, "udpin:127.0.0.1:0") as emu:
        with urllib.request.urlopen(emu.definition_uri, timeout=5) as resp:
            body = resp.read()
        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(emu.definition_uri.rsplit("/", 1)[0] + "/../etc/passwd", timeout=5)
    assert body == emu.definition
    r = peers.mavproxy_load_definition(body)
    assert r.accepted, r.error
    from wiris_tools.camera_definition import parse_definition

    assert set(r.parameters) == {p.name for p in parse_definition(body).params}
