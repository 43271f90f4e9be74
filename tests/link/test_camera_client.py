"""The camera client (library and `wiris camera ...`) against the emulators over real UDP sockets on 127.0.0.1:
identify, definition + validation, settings, set, capture, apply a compiled sequence, refusal, timeout,
a camera that disappears mid-sequence."""

from __future__ import annotations

import json
import math
import re
import socket
import time

import pytest
from click.testing import CliRunner

from cdf.catalogue import catalogue
from missions.compiled import SetupStep
from missions.emit.setup import dumps_setup
from raw_peers import timed_call
from wiris_tools.camera_client import CameraClient, load_setup, parse_setup
from wiris_tools.cli import cli
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.errors import LinkError
from wiris_tools.link import Link

NAN = math.nan


@pytest.fixture
def pro():
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", storage_capacity_mib=(30.0, 30.0, 30.0),
                        image_size_mib=10.0) as emu:
        yield emu


@pytest.fixture
def client(pro):
    with Link(f"udpout:127.0.0.1:{pro.link.local_port}", heartbeat_s=0.2) as link:
        yield CameraClient(link, timeout_s=0.5, retries=2)


def _url(emu) -> str:
    return f"udpout:127.0.0.1:{emu.link.local_port}"


def test_identify_and_information(client):
    info = client.information()
    cam = catalogue().get("wiris-pro")
    assert (info.vendor, info.model, info.definition_version) == (cam.vendor, cam.model, cam.definition_version)
    assert (info.system, info.component) == (1, 100)
    assert set(info.flag_names) == {c.removeprefix("CAMERA_CAP_FLAGS_") for c in cam.capabilities}
    assert [s["id"] for s in client.storage()] == [0, 1, 2]
    assert client.capture_status()["image_count"] == 0


def test_definition_is_downloaded_and_valid(client, pro):
    info = client.information()
    loaded = client.definition(info)
    assert loaded.data == pro.definition and loaded.report.valid, loaded.report.findings
    values = client.read_settings(loaded.definition)
    assert set(values) == {p.name for p in loaded.definition.params}
    with pro.lock:
        state = dict(pro.state.values)
    for name, value in values.items():
        assert value == pytest.approx(state[name], rel=1e-6), name


def test_set_by_option_name_and_number(client, pro):
    d = client.definition(client.information()).definition
    assert client.set_setting(d, "RANGE_MODE", "Span") == 2
    assert client.set_setting(d, "LAYOUT", "3") == 3
    assert client.set_setting(d, "EMISSIVITY", "0.9") == pytest.approx(0.9)
    with pro.lock:
        assert (pro.state.value("range_mode"), pro.state.value("layout")) == (2, 3)
        assert pro.state.value("emissivity") == pytest.approx(0.9)


@pytest.mark.parametrize("name,value,message", [
    ("LAYOUT", "Diagonal", "neither an option nor a number"),
    ("LAYOUT", "7", "not one of the options"),
    ("EMISSIVITY", "1.5", "above the maximum"),
    ("CAM_EV", "1.5", "not a whole number"),
    ("LAYUOT", "1", "did you mean LAYOUT"),
])
def test_set_refused_by_the_definition_sends_nothing(client, pro, name, value, message):
    d = client.definition(client.information()).definition
    with pro.lock:
        before = dict(pro.state.values)
    with pytest.raises(LinkError, match=message) as err:
        client.set_setting(d, name, value)
    assert err.value.hint
    with pro.lock:
        assert pro.state.values == before


def test_camera_refusal_names_the_result(client):
    with pytest.raises(LinkError, match="PARAM_ACK_VALUE_UNSUPPORTED") as unsupported:
        client.set_param_ext("EMISSIVITY", 3.0, "float")
    with pytest.raises(LinkError, match="PARAM_ACK_FAILED") as failed:
        client.set_param_ext("NOT_A_PARAM", 1, "uint32")
    assert unsupported.value.hint and failed.value.hint


def test_a_definition_type_that_cannot_carry_the_value_says_what_to_check(client, pro):
    """A camera's definition may declare a type its own range does not fit (a uint8 up to 1000) or one
    without a PARAM_EXT number encoding: the value is refused before anything is sent."""
    from wiris_tools.camera_definition import DefParam, Definition

    d = Definition("V", "M", 1, (DefParam("BIG", "uint8", None, max=1000.0), DefParam("TXT", "custom", None)))
    for name, value, text in (("BIG", "300", "does not fit uint8"), ("TXT", "1", "no PARAM_EXT number encoding")):
        with pytest.raises(LinkError, match=text) as err:
            client.set_setting(d, name, value)
        assert err.value.where == name and "wiris cdf validate" in err.value.hint


def test_a_param_ext_ack_result_mavlink_does_not_define_gets_a_hint():
    from pymavlink.dialects.v20 import ardupilotmega as m

    cam = Link("udpin:127.0.0.1:0", system=2, component=100, mav_type=m.MAV_TYPE_CAMERA, heartbeat_s=0.2)

    def on_set(msg):
        cam.send(cam.mav.param_ext_ack_encode(msg.param_id.encode(), msg.param_value.encode(), msg.param_type, 9))

    cam.subscribe(on_set, "PARAM_EXT_SET", to_me=True)
    try:
        with Link(f"udpout:127.0.0.1:{cam.local_port}", heartbeat_s=0.2) as link:
            client = CameraClient(link, timeout_s=0.5, retries=0)
            with pytest.raises(LinkError, match="the camera answered 9") as err:
                client.set_param_ext("EMISSIVITY", 0.5, "float")
    finally:
        cam.close()
    assert "firmware" in err.value.hint


def test_capture_periodic_then_storage_full(client):
    shots = list(client.capture(interval_s=1, count=2))
    assert [s.index for s in shots] == [0, 1] and all(s.result == 1 for s in shots)
    with pytest.raises(LinkError, match="failed to capture") as err:
        list(client.capture(interval_s=1, count=0, duration_s=20))       # 30 MiB, 10 MiB per image
    assert err.value.hint
    assert client.capture_status()["image_count"] == 3


def _setup_file(tmp_path, steps) -> str:
    path = tmp_path / "flight.setup.json"
    path.write_text(dumps_setup("flight", steps))
    return str(path)


def _compiled_like_steps(last_bad: bool = False):
    cam = catalogue().get("wiris-pro")
    layout = cam.setting("layout").command
    steps = [
        SetupStep("identify", 100, "command_long", "MAV_CMD_REQUEST_MESSAGE", (259.0, 0, 0, 0, 0, 0, 0)),
        SetupStep("layout blended", 100, "command_long", "MAV_CMD_SET_CAMERA_MODE",
                  (0.0, 0.0, None, None, layout.encode(3), None, None)),
        SetupStep("manual range 10..80 °C", 100, "command_long", "MAV_CMD_USER_1", (1, None, 80, 10, None, None, None)),
        SetupStep("emissivity", 100, "param_ext_set", param_id="EMISSIVITY", value=0.97, type="float",
                  expect="PARAM_ACK_ACCEPTED"),
    ]
    if last_bad:
        steps.insert(3, SetupStep("impossible range mode", 100, "command_long", "MAV_CMD_USER_1",
                                  (9, None, None, None, None, None, None)))
    return steps


def test_apply_a_compiled_sequence(tmp_path, pro):
    path = _setup_file(tmp_path, _compiled_like_steps())
    result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(pro), "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.output)
    assert out["ok"] and [s["outcome"] for s in out["completed"]] == [
        "MAV_RESULT_ACCEPTED", "MAV_RESULT_ACCEPTED", "MAV_RESULT_ACCEPTED", "PARAM_ACK_ACCEPTED"]
    with pro.lock:
        s = pro.state
        assert (s.value("layout"), s.value("range_mode"), s.value("range_max_c"), s.value("range_min_c")) == (3, 1, 80, 10)
        assert s.value("emissivity") == pytest.approx(0.97)


def test_apply_stops_at_the_first_refusal_naming_it(tmp_path, pro):
    path = _setup_file(tmp_path, _compiled_like_steps(last_bad=True))
    result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(pro)])
    assert result.exit_code == 1
    assert "step 4 (impossible range mode)" in result.output and "MAV_RESULT_DENIED" in result.output
    assert "3 of 5 steps done" in result.output
    assert "  hint: " in result.output
    with pro.lock:
        assert pro.state.value("emissivity") != pytest.approx(0.97)     # step 5 never ran


def test_apply_when_the_camera_disappears(tmp_path):
    steps = load_setup(_setup_file(tmp_path, _compiled_like_steps()))
    emu = start_emulator("wiris-pro", "udpin:127.0.0.1:0")
    try:
        with Link(f"udpout:127.0.0.1:{emu.link.local_port}", heartbeat_s=0.2) as link:
            cam = CameraClient(link, timeout_s=0.3, retries=1)
            done = []
            cam.apply(steps[:1], on_step=done.append)
            emu.close()
            with pytest.raises(LinkError, match=r"step 2 \(layout blended\).*no answer") as err:
                cam.apply(steps[1:2], on_step=done.append)
            assert len(done) == 1
            assert err.value.hint                      # the command's hint travels with the step
    finally:
        emu.close()


@pytest.mark.parametrize("kind,message", [("param_ext_set", "PARAM_EXT_SET"), ("param_set", "PARAM_SET")])
def test_a_step_for_another_component_leaves_the_client_aimed_at_its_camera(client, pro, kind, message):
    """A step naming another component is sent there with that component as the target: the client itself
    keeps talking to its camera meanwhile (another thread asking the camera something is not redirected).
    It used to swap its own system/component ids for the step and put them back afterwards."""
    steps = parse_setup({"steps": [{"kind": kind, "target_component": 77, "param_id": "EMISSIVITY",
                                    "value": 0.9, "type": "float"}]})
    aimed_at = []
    pro.link.subscribe(lambda m: aimed_at.append((client.system, client.component)), message,
                       predicate=lambda m: m.target_component == 77)
    with pytest.raises(LinkError, match="stopped the sequence"):
        client.apply(steps)                     # nobody is component 77: no answer
    assert aimed_at and set(aimed_at) == {(1, 100)}


def test_no_camera_times_out():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        result = CliRunner().invoke(cli, ["camera", "info", "--connect", f"udpout:127.0.0.1:{port}", "--wait", "0.5"])
    assert result.exit_code == 1 and "no HEARTBEAT" in result.output and "Traceback" not in result.output
    assert "  hint: " in result.output


@pytest.mark.parametrize("content,message", [
    ("{not json", "not valid JSON"),
    ('{"steps": [{"kind": "reboot", "target_component": 100}]}', "unknown step kind"),
    ('{"steps": [{"kind": "command_long", "command": "MAV_CMD_NOPE", "target_component": 100}]}', "unknown command"),
    ('{"steps": [{"kind": "param_ext_set", "param_id": "X", "value": 300, "type": "uint8", "target_component": 100}]}',
     "does not fit uint8"),
    ('{"steps": [{"kind": "command_long", "command": 203, "params": [1,2,3,4,5,6,7,8]}]}', "at most 7"),
    ('[]', '"steps" list'),
])
def test_bad_setup_files_are_refused_before_sending(tmp_path, pro, content, message):
    path = tmp_path / "bad.setup.json"
    path.write_text(content)
    with pro.lock:
        before = dict(pro.state.values)
    result = CliRunner().invoke(cli, ["camera", "apply", str(path), "--connect", _url(pro)])
    assert result.exit_code == 1 and message in result.output, result.output
    assert "\n  hint: " in result.output, result.output
    with pro.lock:
        assert pro.state.values == before


def _steps(*steps) -> str:
    return json.dumps({"format": "wiris-setup", "version": 1, "steps": list(steps)})


def _param(**kw) -> dict:
    return {"kind": "param_ext_set", "target_component": 100, "param_id": "EMISSIVITY", "value": 0.97,
            "type": "float"} | kw


def _command(**kw) -> dict:
    return {"kind": "command_long", "target_component": 100, "command": "MAV_CMD_SET_CAMERA_MODE",
            "params": [0, 1]} | kw


def _message(**kw) -> dict:
    return {"kind": "message", "target_component": 100, "message": "DIGICAM_CONFIGURE", "fields": {"mode": 2}} | kw


# (content, where after the file's path, message, a piece of the hint)
BAD_SETUP_FILES = {
    "not-json": ('{"steps": [\n  {not json', ":2", "not valid JSON", "wiris mission compile"),
    "not-utf8": (b'{"steps": ["\xff"]}', "", "not valid JSON", "UTF-8"),
    "not-an-object": ("[1, 2]", "", '"steps" list', "NAME.setup.json"),
    "no-steps-list": ('{"steps": {"kind": "param_set"}}', "", '"steps" list', "wiris mission compile"),
    "too-many-steps": (_steps(*[_param()] * 1001), "", "1001 steps; at most 1000", "split"),
    "step-not-an-object": (_steps(_param(), ["param_set"]), ": step 2", "must be a JSON object", '{"kind": '),
    "unknown-kind": (_steps(_param(kind="reboot")), ": step 1", "unknown step kind 'reboot'", "command_long"),
    "unknown-command-name": (_steps(_command(command="MAV_CMD_NOPE")), ": step 1", "unknown command", "MAV_CMD_"),
    "command-not-a-number": (_steps(_command(command=70000)), ": step 1", "not a MAV_CMD name or number",
                             "MAV_CMD_SET_CAMERA_MODE"),
    "command-true": (_steps(_command(command=True)), ": step 1", "not a MAV_CMD name or number", "530"),
    "eight-params": (_steps(_command(params=[0] * 8)), ": step 1", "at most 7 numbers", "null keeps"),
    "params-not-a-list": (_steps(_command(params="0,1")), ": step 1", "at most 7 numbers", '"params": ['),
    "param-text": (_steps(_command(params=[0, "1"])), ": step 1", "at most 7 numbers", '"params": ['),
    "unknown-expected-result": (_steps(_command(expect={"result": "OK"})), ": step 1", "unknown expected result",
                                "MAV_RESULT_ACCEPTED"),
    "component-256": (_steps(_param(target_component=256)), ": step 1", "not a component id",
                      '"target_component": 100'),
    "component-text": (_steps(_param(target_component="100")), ": step 1", "not a component id", "component id"),
    "component-described": (_steps(_param(description="emissivity", target_component=-1)), ": step 1 (emissivity)",
                            "not a component id", "component id"),
    "param-id-empty": (_steps(_param(param_id="")), ": step 1", "1–16 ASCII", '"param_id": "EMISSIVITY"'),
    "param-id-long": (_steps(_param(param_id="A" * 17)), ": step 1", "1–16 ASCII", "wiris camera settings"),
    "param-id-not-ascii": (_steps(_param(kind="param_set", param_id="Emissivität")), ": step 1", "1–16 ASCII",
                           "EMISSIVITY"),
    "value-nan": (_steps(_param(), _param()).replace("0.97", "NaN", 1), ": step 1", "not a finite number", '"value": '),
    "value-infinity": (_steps(_param(kind="param_set", value=1)).replace('"value": 1', '"value": -Infinity'),
                       ": step 1", "not a finite number", "NaN"),
    "value-text": (_steps(_param(value="0.97")), ": step 1", "not a finite number", "not text"),
    "value-does-not-fit": (_steps(_param(value=300, type="uint8")), ": step 1", "does not fit uint8", "uint8"),
    "fields-not-an-object": (_steps(_message(fields=[["mode", 2]])), ": step 1", "must be a JSON object",
                             '"fields": {'),
    "field-not-finite": (_steps(_message(fields={"iso": None})), ": step 1", "not a finite number", '"iso": 2'),
    "field-out-of-range": (_steps(_message(fields={"iso": 256})), ": step 1", "not an integer 0–255",
                           "whole number from 0 to 255"),
    "field-not-whole": (_steps(_message(fields={"shutter_speed": 1.5})), ": step 1", "not an integer 0–65535",
                        "from 0 to 65535"),
    "unknown-field": (_steps(_message(fields={"shutter": 60})), ": step 1", "no field 'shutter'", "shutter_speed"),
    "unknown-message": (_steps(_message(message="DIGICAM_CONTROL")), ": step 1", "cannot send message",
                        "DIGICAM_CONFIGURE"),
    "too-large": (b" " * (1024 * 1024) + b"{}", "", "larger than 1 MiB (1048576 bytes)", "wiris mission compile"),
    "missing": (None, "", "cannot read the setup file: no such file", "check the path"),
    "a-directory": ("directory", "", "is a directory, not a file", "check the path"),
}


@pytest.mark.parametrize("content,where,message,hint", BAD_SETUP_FILES.values(), ids=BAD_SETUP_FILES)
def test_a_bad_setup_file_says_where_what_and_what_to_do(tmp_path, content, where, message, hint):
    """Every refusal of `wiris camera apply FILE`'s loader names the file (and line or step) and carries a
    hint; nothing reaches a camera before the whole file is read."""
    path = tmp_path / "flight.setup.json"
    if content == "directory":
        path.mkdir()
    elif content is not None:
        (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    with pytest.raises(LinkError) as err:
        load_setup(path)
    assert message in err.value.message
    assert err.value.where == f"{path}{where}"
    assert err.value.hint and hint in err.value.hint, err.value.hint
    assert "\n" not in err.value.hint and len(err.value.hint) < 120      # one line


def test_a_step_the_camera_accepts_against_its_expected_result_says_how_to_fix_it(tmp_path, client):
    steps = [SetupStep("identify", 100, "command_long", "MAV_CMD_REQUEST_MESSAGE", (259.0, 0, 0, 0, 0, 0, 0),
                       expect="MAV_RESULT_DENIED")]
    with pytest.raises(LinkError, match="answered MAV_RESULT_ACCEPTED, expected MAV_RESULT_DENIED") as err:
        client.apply(load_setup(_setup_file(tmp_path, steps)))
    assert err.value.where == "step 1 (identify)"
    assert '"expect": {"result": "MAV_RESULT_ACCEPTED"}' in err.value.hint


def test_unknown_fields_are_tolerated(tmp_path, pro):
    doc = {"format": "wiris-setup", "version": 9, "future": True,
           "steps": [{"description": "zoom", "target_component": 100, "kind": "command_long",
                      "command": "MAV_CMD_DO_DIGICAM_CONTROL", "params": [None, 4, None, None, 0, None, None],
                      "expect": {"result": "MAV_RESULT_ACCEPTED", "extra": 1}, "payload": "thermal", "x": [1]}]}
    path = tmp_path / "f.setup.json"
    path.write_text(json.dumps(doc))
    result = CliRunner().invoke(cli, ["camera", "apply", str(path), "--connect", _url(pro)])
    assert result.exit_code == 0, result.output
    with pro.lock:
        assert pro.state.value("zoom") == 4


def test_cli_info_settings_set_capture(pro):
    r = CliRunner()
    info = r.invoke(cli, ["camera", "info", "--connect", _url(pro), "--json"])
    assert info.exit_code == 0, info.output
    assert json.loads(info.output)["camera"]["model"] == "WIRIS Pro"
    settings = r.invoke(cli, ["camera", "settings", "--connect", _url(pro), "--json"])
    assert settings.exit_code == 0, settings.output
    doc = json.loads(settings.output)
    assert doc["definition"]["valid"]
    layout = next(s for s in doc["settings"] if s["name"] == "LAYOUT")
    assert layout["option"] == "Fullscreen" and len(layout["options"]) == 4
    ok = r.invoke(cli, ["camera", "set", "LAYOUT", "blended", "--connect", _url(pro)])
    assert ok.exit_code == 0 and "LAYOUT = 3 (Blended)" in ok.output
    bad = r.invoke(cli, ["camera", "set", "LAYOUT", "9", "--connect", _url(pro)])
    assert bad.exit_code == 1 and "not one of the options" in bad.output
    # a negative value is the value, not an option (a thermal range starts below zero)
    cold = r.invoke(cli, ["camera", "set", "RANGE_MIN_C", "-20", "--connect", _url(pro)])
    assert cold.exit_code == 0 and "RANGE_MIN_C = -20 (acknowledged)" in cold.output, cold.output
    assert r.invoke(cli, ["camera", "set", "LAYOUT", "1", "--tiemout", "2", "--connect", _url(pro)]).exit_code == 2
    cap = r.invoke(cli, ["camera", "capture", "--connect", _url(pro), "--json"])
    assert cap.exit_code == 0, cap.output
    assert json.loads(cap.output.splitlines()[0])["ok"] is True


def test_rededge_parameters_through_the_client(tmp_path):
    steps = [SetupStep("overlap mode", 100, "param_set", param_id="autoCapMode", value=2,
                       type="MAV_PARAM_TYPE_UINT32", expect="PARAM_VALUE"),
             SetupStep("target altitude", 100, "param_set", param_id="operatingAlt", value=90,
                       type="MAV_PARAM_TYPE_INT32", expect="PARAM_VALUE"),
             SetupStep("timer", 100, "param_set", param_id="timerPeriod", value=1.5,
                       type="MAV_PARAM_TYPE_REAL32", expect="PARAM_VALUE"),
             SetupStep("impossible mode", 100, "param_set", param_id="autoCapMode", value=9,
                       type="MAV_PARAM_TYPE_UINT32", expect="PARAM_VALUE")]
    path = _setup_file(tmp_path, steps)
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu:
        result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(emu), "--mavlink1"])
        assert result.exit_code == 1, result.output
        assert "step 4 (impossible mode)" in result.output and "kept 2" in result.output
        assert "  hint: " in result.output
        with emu.lock:
            assert emu.state.values["autoCapMode"] == 2 and emu.state.values["operatingAlt"] == 90
            assert emu.state.values["timerPeriod"] == 1.5


def test_rededge_integer_parameter_sent_as_a_float_is_refused(tmp_path):
    """The camera reads PARAM_SET's 4 bytes as its parameter's own type ("implemented as a union"): autoCapMode
    2 sent as the float 2.0 (what this tool sent before) is the integer 1073741824 to it, not a mode."""
    steps = [SetupStep("overlap mode", 100, "param_set", param_id="autoCapMode", value=2.0,
                       type="MAV_PARAM_TYPE_REAL32", expect="PARAM_VALUE")]
    path = _setup_file(tmp_path, steps)
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu:
        result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(emu), "--mavlink1"])
        assert result.exit_code == 1, result.output
        assert "autoCapMode = 2.0: the camera kept 0" in result.output
        with emu.lock:
            assert emu.state.values["autoCapMode"] == 0


@pytest.mark.parametrize("step,error", [
    ({"value": 2.5, "type": "MAV_PARAM_TYPE_UINT32"}, "not a whole number for uint32"),
    ({"value": 2, "type": "MAV_PARAM_TYPE_UINT64"}, "does not fit a classic parameter's 4 bytes"),
    ({"value": 2, "type": "MAV_PARAM_TYPE_NOPE"}, "does not fit a classic parameter's 4 bytes"),
    ({"value": -5000000, "type": "MAV_PARAM_TYPE_INT32"}, "cannot be carried in a float's bytes"),
    ({"value": 5000000000, "type": "MAV_PARAM_TYPE_UINT32"}, "does not fit uint32"),
])
def test_setup_param_set_types_are_checked(step, error):
    with pytest.raises(LinkError) as err:
        parse_setup({"format": "wiris-setup", "version": 1, "steps": [
            {"kind": "param_set", "target_component": 100, "param_id": "autoCapMode", **step}]}, "s.json")
    assert error in str(err.value) and err.value.hint


def test_rededge_exposure_reaches_every_imager(tmp_path):
    """A compiled plan's RedEdge exposure settings: one DIGICAM_CONFIGURE, which the camera never answers, sent
    retries + 1 times over the wire (counted where the emulator receives it) and applied to all five bands."""
    from missions.plan import Payload
    from missions.emit.setup import setup_steps

    cam = catalogue().get("rededge-mx")
    settings = {"exposure_mode": "manual", "shutter_divisor": 2000, "iso": "iso800"}
    p = Payload(name="ms", camera="rededge-mx", component_id=100, settings=tuple(settings.items()),
                values=tuple((k, cam.setting(k).check(v)) for k, v in settings.items()))
    path = _setup_file(tmp_path, setup_steps([p], {"ms": cam}))
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu:
        received = []
        real = emu.state._on_digicam_configure
        emu.state._on_digicam_configure = lambda msg, now: received.append(msg) or real(msg, now)
        result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(emu), "--mavlink1"])
        assert result.exit_code == 0, result.output
        assert "step 1 (exposure of every imager" in result.output and ": SENT" in result.output
        assert "0 acknowledged, 1 sent to a camera that does not answer them" in result.output
        deadline = time.monotonic() + 2.0
        while len(received) < 4 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert len(received) == 4                     # CameraClient's default retries=3: four sends
        assert all(m.get_msgId() == 154 and m.target_component == 100 for m in received)
        with emu.lock:
            assert emu.state.exposure_mode == 4          # the API page: <li value="4">Manual</li>
            # serial API: "to specify 1/60sec, send 60"; ISO gain <li value="8">ISO800</li>
            assert [(e.shutter_divisor, e.iso) for e in emu.state.exposures] == [(2000, 8)] * 5
        # without --mavlink1 the frames would be MAVLink 2, which the RedEdge API does not promise to read:
        # with no answer to miss, that would pass unnoticed, so the step is refused before sending
        received.clear()
        result = CliRunner().invoke(cli, ["camera", "apply", path, "--connect", _url(emu)])
        assert result.exit_code == 1 and "speaks MAVLink 1" in result.output and "--mavlink1" in result.output
        assert "0 of 1 steps done" in result.output
        time.sleep(0.3)
        assert received == []


@pytest.mark.parametrize("step,message", [
    ({"message": "DIGICAM_CONTROL", "fields": {}}, "cannot send message 'DIGICAM_CONTROL'"),
    ({"message": "DIGICAM_CONFIGURE", "fields": {"shutter": 60}}, "has no field 'shutter'"),
    ({"message": "DIGICAM_CONFIGURE", "fields": {"target_system": 1}}, "has no field 'target_system'"),
    ({"message": "DIGICAM_CONFIGURE", "fields": {"iso": 256}}, "not an integer 0–255 (uint8_t)"),
    ({"message": "DIGICAM_CONFIGURE", "fields": {"shutter_speed": 1.5}}, "not an integer 0–65535"),
    ({"message": "DIGICAM_CONFIGURE", "fields": {"mode": True}}, "not a finite number"),
    ({"message": "DIGICAM_CONFIGURE", "fields": [2]}, "fields must be a JSON object"),
])
def test_a_bad_message_step_is_refused_before_anything_is_sent(step, message):
    doc = {"steps": [{"kind": "param_set", "param_id": "autoCapMode", "value": 2},
                     {"kind": "message", "target_component": 100, **step}]}
    with pytest.raises(LinkError, match=re.escape(message)) as ei:
        parse_setup(doc, "f.setup.json")
    assert ei.value.where.startswith("f.setup.json: step 2")
    assert ei.value.hint


def test_emulate_command_runs_and_stops():
    result = CliRunner().invoke(cli, ["emulate", "wiris-security", "--connect", "udpin:127.0.0.1:0",
                                      "--duration", "0.3"])
    assert result.exit_code == 0, result.output
    assert "WIRIS Security" in result.output and "http://127.0.0.1:" in result.output
    bad = CliRunner().invoke(cli, ["emulate", "wiris-pro", "--connect", "udpin:127.0.0.1:0", "--component", "99"])
    assert bad.exit_code == 1 and "100" in bad.output
    unknown = CliRunner().invoke(cli, ["emulate", "wiris-pr", "--connect", "udpin:127.0.0.1:0"])
    assert unknown.exit_code == 1 and "did you mean" in unknown.output


def test_emulate_command_stops_on_sigterm():
    """Run until stopped: SIGTERM (kill, systemd, docker) stops the real command like Ctrl-C, exit 0."""
    import signal

    from cli_child import stop, wiris_child

    with wiris_child("emulate", "wiris-security", "--connect", "udpin:127.0.0.1:0") as proc:
        first = proc.stderr.readline()
        assert first.startswith("emulating WORKSWELL WIRIS Security"), first
        # at once, as a supervisor that waits for the first line may: the handler is in place before it, so
        # the signal may land before or after the remaining start lines, and either way takes the stop path
        rest = stop(proc, signal.SIGTERM)
        assert rest.rstrip().endswith("emulator stopped"), rest


def test_emulator_wait_survives_an_interrupt_at_any_point():
    """Ctrl-C and SIGTERM raise KeyboardInterrupt wherever the main thread is. Raised inside Event.wait it
    could leave the Event's lock held, and close() then hung for ever (seen once in 40 SIGTERMs to
    `wiris emulate`). Here the interrupt is raised at each place of wait() where Python checks for signals
    (tests/interrupts.py), in turn, and close() must still finish."""
    from interrupts import InterruptAt, finishes

    n = 0
    while True:
        emu = start_emulator("wiris-security", "udpin:127.0.0.1:0")
        with InterruptAt(n) as at:
            try:
                emu.wait(0.05)
            except KeyboardInterrupt:
                assert at.fired
        assert finishes(emu.close), f"close() hangs after an interrupt at signal check {n} of wait()"
        if not at.fired:
            break
        n += 1
    assert n > 5  # wait() passed several signal checks before it returned uninterrupted


def test_settings_report_a_camera_that_disagrees_with_its_definition(pro):
    """A camera answering another type than its file says, or not answering a parameter, is reported
    (the validator's CDF303/CDF304) by `wiris camera settings`."""
    import dataclasses

    with pro.lock:
        d = pro.state.definition
        params = tuple(dataclasses.replace(p, type="int32") if p.name == "LAYOUT" else p
                       for p in d.params if p.name != "PALETTE")
        pro.state.definition = dataclasses.replace(d, params=params)
    result = CliRunner().invoke(cli, ["camera", "settings", "--connect", _url(pro), "--json", "--timeout", "0.3"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    found = {(f["rule"], f["parameter"]) for f in doc["definition"]["findings"]}
    assert ("CDF303", "LAYOUT") in found and ("CDF304", "PALETTE") in found
    assert next(s for s in doc["settings"] if s["name"] == "PALETTE")["value"] is None


def test_info_on_a_rededge_says_what_it_is():
    with start_emulator("rededge-mx", "udpin:127.0.0.1:0") as emu:
        r = CliRunner().invoke(cli, ["camera", "info", "--connect", _url(emu), "--mavlink1", "--timeout", "0.2"])
    assert r.exit_code == 1 and "not MAV_TYPE_CAMERA" in r.output and "serial API" in r.output


def test_falls_back_to_request_camera_information_for_an_older_camera():
    """A camera that answers REQUEST_MESSAGE with UNSUPPORTED gets MAV_CMD_REQUEST_CAMERA_INFORMATION (521)."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    cam = Link("udpin:127.0.0.1:0", system=2, component=101, mav_type=m.MAV_TYPE_CAMERA, heartbeat_s=0.2)
    seen = []

    def on_cmd(msg):
        seen.append(msg.command)
        ok = msg.command == m.MAV_CMD_REQUEST_CAMERA_INFORMATION
        cam.send(cam.mav.command_ack_encode(msg.command, m.MAV_RESULT_ACCEPTED if ok else m.MAV_RESULT_UNSUPPORTED,
                                            0, 0, msg.get_srcSystem(), msg.get_srcComponent()))
        if ok:
            cam.send(cam.mav.camera_information_encode(0, b"Old".ljust(32, b"\0"), b"Cam".ljust(32, b"\0"), 0, 4.0,
                                                       0, 0, 320, 240, 0, m.CAMERA_CAP_FLAGS_CAPTURE_IMAGE, 0, b""))

    cam.subscribe(on_cmd, "COMMAND_LONG", to_me=True)
    try:
        with Link(f"udpout:127.0.0.1:{cam.local_port}", heartbeat_s=0.2) as link:
            info = CameraClient(link, timeout_s=0.5).information()
            assert (info.vendor, info.model, info.system, info.component) == ("Old", "Cam", 2, 101)
            assert seen[:2] == [m.MAV_CMD_REQUEST_MESSAGE, m.MAV_CMD_REQUEST_CAMERA_INFORMATION]
            with pytest.raises(LinkError, match="names no camera definition") as err:
                CameraClient(link, timeout_s=0.5).definition(info)
            assert err.value.hint
    finally:
        cam.close()


@pytest.mark.parametrize("value", [NAN, math.inf])
def test_info_json_of_a_camera_that_reports_nan_or_inf_is_json(value):
    """NaN is MAVLink's "unknown" in CAMERA_INFORMATION, STORAGE_INFORMATION and CAMERA_CAPTURE_STATUS;
    `--json` used to stop with an internal error (json.dumps(allow_nan=False)) instead of writing null."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    cam = Link("udpin:127.0.0.1:0", system=2, component=100, mav_type=m.MAV_TYPE_CAMERA, heartbeat_s=0.2)

    def on_cmd(msg):
        cam.send(cam.mav.command_ack_encode(msg.command, m.MAV_RESULT_ACCEPTED, 0, 0, msg.get_srcSystem(),
                                            msg.get_srcComponent()))
        wanted = int(msg.param1) if msg.command == m.MAV_CMD_REQUEST_MESSAGE else None
        if wanted == m.MAVLINK_MSG_ID_CAMERA_INFORMATION:
            cam.send(cam.mav.camera_information_encode(0, b"V".ljust(32, b"\0"), b"M".ljust(32, b"\0"), 0, value,
                                                       value, value, 640, 512, 0, m.CAMERA_CAP_FLAGS_CAPTURE_IMAGE,
                                                       0, b""))
        elif wanted == m.MAVLINK_MSG_ID_STORAGE_INFORMATION:
            cam.send(cam.mav.storage_information_encode(0, 1, 1, 2, value, value, value, value, value))
        elif wanted == m.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS:
            cam.send(cam.mav.camera_capture_status_encode(0, 0, 0, value, 0, value, 0))

    cam.subscribe(on_cmd, "COMMAND_LONG", to_me=True)
    try:
        r = CliRunner().invoke(cli, ["camera", "info", "--connect", f"udpout:127.0.0.1:{cam.local_port}",
                                     "--timeout", "0.5", "--json"])
    finally:
        cam.close()
    assert r.exit_code == 0, r.output
    got = json.loads(r.output, parse_constant=lambda c: pytest.fail(f"{c} in JSON output"))
    assert got["camera"]["sensor_size_mm"] == [None, None] and got["camera"]["focal_length_mm"] is None
    assert got["storage"][0]["total_mib"] is None and got["capture_status"]["image_interval_s"] is None


def test_the_emulator_definition_server_on_ipv6_closes_idle_connections_and_names_a_bad_host(monkeypatch):
    import urllib.request

    from wiris_tools.emulate import runner

    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
    except OSError:
        pytest.skip("no IPv6 loopback on this machine")
    monkeypatch.setattr(runner, "IDLE_TIMEOUT_S", 0.3)
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", http_host="::1") as emu:
        assert emu.definition_uri.startswith("http://[::1]:")  # was http://::1:PORT, and no IPv6 listener
        with urllib.request.urlopen(emu.definition_uri, timeout=5) as resp:
            assert resp.read() == emu.definition
        port = int(emu.definition_uri.split("]:")[1].split("/")[0])
        with socket.create_connection(("::1", port), timeout=5) as stalled:
            stalled.sendall(b"GET /")
            assert stalled.recv(1) == b""  # closed after the idle timeout, not held for ever
    with pytest.raises(LinkError, match="cannot serve the camera definition on 192.0.2.1:0") as err:
        start_emulator("wiris-pro", "udpin:127.0.0.1:0", http_host="192.0.2.1")
    assert err.value.hint.startswith("give --http-host an address of this machine")


@pytest.mark.parametrize("uri,text", [
    ("mftp://comp=999:/x.xml", "names component 999, not 0-255"),
    ("mftp://[;comp=300]/x.xml", "names component 300, not 0-255"),
    ("http://[::1/x.xml", "malformed URL"),
    ("ftp://camera/x.xml", "unsupported definition URI scheme 'ftp'"),
])
def test_a_broken_definition_uri_from_the_camera_is_a_link_error(client, uri, text):
    # what a camera (or a corrupted CAMERA_INFORMATION) may report; the component id used to reach the
    # MAVLink encoder and fail there with struct.error
    import dataclasses

    info = dataclasses.replace(client.information(), definition_uri=uri)
    with pytest.raises(LinkError, match=re.escape(text)) as err:
        client.definition(info, timeout_s=1)
    assert err.value.hint


def test_cli_set_json_and_mftp_definition():
    with start_emulator("wiris-security", "udpin:127.0.0.1:0", definition_scheme="mftp") as emu:
        r = CliRunner().invoke(cli, ["camera", "set", "AGC_HOT_REJ", "12.5", "--connect", _url(emu), "--json"])
        assert r.exit_code == 0, r.output
        assert json.loads(r.output) == {"name": "AGC_HOT_REJ", "value": 12.5, "option": None, "acknowledged": True}
        with emu.lock:
            assert emu.state.value("hot_rejection_pct") == 12.5


@pytest.mark.parametrize("module", ["numpy", "curses"])
def test_ctrl_c_while_pymavlink_loads_stops_the_command(module):
    """pymavlink imports numpy (through its quaternion module) and curses inside bare `except:` clauses: a
    Ctrl-C landing there was swallowed and `wiris camera info` ran on to its own timeout (3 of 40 runs
    interrupted in the first 0.8 s). Here the interrupt is raised as `module` starts to load: the command
    must stop with 130, not report a missing camera after --wait."""
    import subprocess
    import sys

    code = ("import sys\n"
            "class Interrupt:\n"
            "    def find_spec(self, name, path=None, target=None):\n"
            f"        if name == {module!r}:\n"
            "            sys.meta_path.remove(self)\n"
            "            raise KeyboardInterrupt\n"
            "sys.meta_path.insert(0, Interrupt())\n"
            "from wiris_tools.cli import main\n"
            "sys.argv = ['wiris', 'camera', 'info', '--connect', 'udpin:127.0.0.1:0', '--wait', '3']\n"
            "main()\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130, proc.stderr
    assert "HEARTBEAT" not in proc.stderr


def _scripted_camera(answer, component: int = 100):
    """A camera on a real UDP socket: `answer(msg)` returns (MAV_RESULT, [messages to send after the ACK]) for
    each COMMAND_LONG it gets; the commands are recorded with their params."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    cam = Link("udpin:127.0.0.1:0", system=1, component=component, mav_type=m.MAV_TYPE_CAMERA, heartbeat_s=0.2)
    seen: list[tuple[int, tuple[float, ...]]] = []

    def on_cmd(msg):
        params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        seen.append((msg.command, params))
        result, after = answer(msg, params)
        cam.send(cam.mav.command_ack_encode(msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()))
        for out in after:
            cam.send(out)

    cam.subscribe(on_cmd, "COMMAND_LONG", to_me=True)
    return cam, seen


def _camera_information(mav):
    from pymavlink.dialects.v20 import ardupilotmega as m

    return mav.camera_information_encode(0, b"ACME".ljust(32, b"\0"), b"Cam".ljust(32, b"\0"), 0, 4.0, 0, 0, 640,
                                         480, 0, m.CAMERA_CAP_FLAGS_CAPTURE_IMAGE, 0, b"")


@pytest.mark.parametrize("refusal", ["MAV_RESULT_UNSUPPORTED", "MAV_RESULT_DENIED"])
def test_info_of_a_camera_that_refuses_storage_and_capture_status_reports_them_missing(refusal):
    """CAMERA_INFORMATION arrived: a camera that answers the storage and capture status requests UNSUPPORTED
    or DENIED (one without storage) gets "not reported" (null with --json); `camera info` used to exit 1."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    def answer(msg, params):
        if msg.command == m.MAV_CMD_REQUEST_MESSAGE and params[0] == m.MAVLINK_MSG_ID_CAMERA_INFORMATION:
            return m.MAV_RESULT_ACCEPTED, [_camera_information(cam.mav)]
        if msg.command == m.MAV_CMD_REQUEST_MESSAGE:
            return getattr(m, refusal), []
        return m.MAV_RESULT_UNSUPPORTED, []

    cam, _ = _scripted_camera(answer)
    url = f"udpout:127.0.0.1:{cam.local_port}"
    try:
        text = CliRunner().invoke(cli, ["camera", "info", "--connect", url, "--timeout", "0.3"])
        as_json = CliRunner().invoke(cli, ["camera", "info", "--connect", url, "--timeout", "0.3", "--json"])
    finally:
        cam.close()
    assert text.exit_code == 0, text.output
    assert "ACME Cam" in text.output and "storage: not reported" in text.output
    assert "capture: not reported" in text.output
    assert as_json.exit_code == 0, as_json.output
    doc = json.loads(as_json.output)
    assert doc["camera"]["model"] == "Cam" and doc["storage"] is None and doc["capture_status"] is None


def test_silence_to_the_storage_request_is_still_an_error():
    """Only a refusal means "not reported": no answer at all says something about the link."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    def answer(msg, params):
        if params[0] == m.MAVLINK_MSG_ID_CAMERA_INFORMATION:
            return m.MAV_RESULT_ACCEPTED, [_camera_information(cam.mav)]
        return m.MAV_RESULT_ACCEPTED, []        # acknowledged, and then nothing

    cam, _ = _scripted_camera(answer)
    try:
        r = CliRunner().invoke(cli, ["camera", "info", "--connect", f"udpout:127.0.0.1:{cam.local_port}",
                                     "--timeout", "0.3"])
    finally:
        cam.close()
    assert r.exit_code == 1 and "sent no STORAGE_INFORMATION" in r.output and "  hint: " in r.output


def test_requests_send_common_xml_values_in_their_unused_params():
    """An older, strict camera: REQUEST_MESSAGE is UNSUPPORTED, and the dedicated requests' MAV_BOOL params
    are checked as common.xml says ("values not equal to 0 or 1 are invalid"). The fallback 525 used to carry
    NaN in param2 ("Request storage information (MAV_BOOL_TRUE)"), and REQUEST_MESSAGE NaN in params 3-7
    ("by default assumed not used (0)"); the stop of a periodic capture NaN in param1, which such a camera
    refuses (and the client ignored the refusal: the camera went on capturing)."""
    from pymavlink.dialects.v20 import ardupilotmega as m

    def boolean(v):
        return v in (0.0, 1.0)

    def answer(msg, params):
        if msg.command == m.MAV_CMD_REQUEST_MESSAGE:
            return m.MAV_RESULT_UNSUPPORTED, []
        if msg.command == m.MAV_CMD_REQUEST_CAMERA_INFORMATION and boolean(params[0]):
            return m.MAV_RESULT_ACCEPTED, [_camera_information(cam.mav)]
        if msg.command == m.MAV_CMD_REQUEST_STORAGE_INFORMATION and boolean(params[1]):
            return m.MAV_RESULT_ACCEPTED, [cam.mav.storage_information_encode(
                0, 1, 1, m.STORAGE_STATUS_READY, 1000, 10, 990, 0, 0, m.STORAGE_TYPE_MICROSD, b"SD", 0)]
        if msg.command == m.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS and boolean(params[0]):
            return m.MAV_RESULT_ACCEPTED, [cam.mav.camera_capture_status_encode(0, 0, 0, 0, 0, 990, 7)]
        if msg.command == m.MAV_CMD_IMAGE_START_CAPTURE and params[0] == 0:
            return m.MAV_RESULT_ACCEPTED, [cam.mav.camera_image_captured_encode(
                0, 0, 100, 0, 0, 0, 0, [1, 0, 0, 0], i, 1, b"") for i in range(2)]
        if msg.command == m.MAV_CMD_IMAGE_STOP_CAPTURE and params[0] == 0:
            return m.MAV_RESULT_ACCEPTED, []    # common.xml: param1 0 = all cameras; other values are NACKed
        return m.MAV_RESULT_DENIED, []

    cam, seen = _scripted_camera(answer)
    try:
        with Link(f"udpout:127.0.0.1:{cam.local_port}", heartbeat_s=0.2) as link:
            client = CameraClient(link, timeout_s=0.3, retries=0)
            assert client.information().model == "Cam"
            assert [s["name"] for s in client.storage()] == ["SD"]
            assert client.capture_status()["image_count"] == 7
            assert [shot.index for shot in client.capture(interval_s=1, count=2)] == [0, 1]
    finally:
        cam.close()
    sent = {command: params for command, params in seen}
    assert sent[m.MAV_CMD_IMAGE_START_CAPTURE][3:6] == (0, 0, 0)      # common.xml defaults; 0 keeps on a WIRIS
    assert sent[m.MAV_CMD_IMAGE_STOP_CAPTURE][0] == 0
    assert sent[m.MAV_CMD_REQUEST_STORAGE_INFORMATION] == (0, 1, 0, 0, 0, 0, 0)
    assert sent[m.MAV_CMD_REQUEST_CAMERA_INFORMATION] == (1, 0, 0, 0, 0, 0, 0)
    assert sent[m.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS] == (1, 0, 0, 0, 0, 0, 0)
    requests = [params for command, params in seen if command == m.MAV_CMD_REQUEST_MESSAGE]
    assert len(requests) == 3 and all(p[1:] == (0, 0, 0, 0, 0, 0) for p in requests)


def test_set_gives_up_on_a_camera_that_answers_in_progress_for_ever():
    """A camera repeating PARAM_ACK_IN_PROGRESS and never finishing kept set_param_ext waiting for ever (each
    report extended the wait); the module promises that every wait is bounded."""
    import threading

    from pymavlink.dialects.v20 import ardupilotmega as m

    from wiris_tools.link import IN_PROGRESS_TIMEOUTS

    cam = Link("udpin:127.0.0.1:0", system=1, component=100, mav_type=m.MAV_TYPE_CAMERA, heartbeat_s=0.2)
    stop = threading.Event()
    pending = []

    def busy():
        while not stop.is_set():
            for msg in list(pending):
                cam.send(cam.mav.param_ext_ack_encode(msg._param_id_raw, msg._param_value_raw, msg.param_type,
                                                      m.PARAM_ACK_IN_PROGRESS))
            stop.wait(0.05)

    cam.subscribe(pending.append, "PARAM_EXT_SET", to_me=True)
    reporter = threading.Thread(target=busy, daemon=True)
    reporter.start()
    try:
        with Link(f"udpout:127.0.0.1:{cam.local_port}", heartbeat_s=0.2) as link:
            client = CameraClient(link, timeout_s=0.1, retries=2)
            call = timed_call(lambda: client.set_param_ext("EMISSIVITY", 0.9, "float"),
                              IN_PROGRESS_TIMEOUTS * 0.1 + 5)
            assert call.finished, "still waiting on a camera that only answers IN_PROGRESS"
    finally:
        stop.set()
        reporter.join(2)
        cam.close()
    err = call.error
    assert "PARAM_ACK_IN_PROGRESS" in err.message and err.where == "EMISSIVITY" and "--timeout" in err.hint
    assert IN_PROGRESS_TIMEOUTS * 0.1 <= call.waited < IN_PROGRESS_TIMEOUTS * 0.1 + 3


def test_the_client_loads_no_emulator():
    """The definition reader and the PARAM_EXT codec that client and emulators share live beside both, so a
    ground station loads no emulator code (it used to find them under wiris_tools/emulate/)."""
    import subprocess
    import sys

    code = ("import sys, wiris_tools.camera_client\n"
            "print(sorted(m for m in sys.modules if m.startswith('wiris_tools.emulate')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# -- `wiris camera apply --payload NAME`: one payload's steps of a compiled two-camera sequence -------------------

@pytest.fixture(scope="module")
def two_camera_setup(tmp_path_factory):
    """field-multispectral's NAME.setup.json: a WIRIS Pro as component 101, a RedEdge-MX as 100."""
    from missions.compile import compile_plan
    from missions.formats.outputs import write_outputs

    out = tmp_path_factory.mktemp("two-cameras")
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    compiled = compile_plan(root / "examples" / "field-multispectral.yaml")
    write_outputs(compiled, out)
    return out / f"{compiled.name}.setup.json", compiled


def test_apply_runs_only_the_chosen_payloads_steps(two_camera_setup):
    path, compiled = two_camera_setup
    thermal = [s for s in compiled.setup if s.payload == "thermal"]
    assert thermal and len(thermal) < len(compiled.setup)
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", component=101) as emu:
        result = CliRunner().invoke(cli, ["camera", "apply", str(path), "--payload", "thermal", "--connect",
                                          _url(emu), "--json"])
        assert result.exit_code == 0, result.output
        out = json.loads(result.output)
        assert out["ok"] and [s["description"] for s in out["completed"]] == [s.description for s in thermal]
        with emu.lock:
            assert emu.state.value("emissivity") == pytest.approx(0.98)    # the thermal steps did run


@pytest.mark.parametrize("name,fragment", [("thermall", "did you mean 'thermal'?"),
                                           ("zoom", "the payloads of this file: multispectral, thermal")])
def test_apply_with_an_unknown_payload_sends_nothing(two_camera_setup, name, fragment):
    path, _ = two_camera_setup
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", component=101) as emu:
        result = CliRunner().invoke(cli, ["camera", "apply", str(path), "--payload", name, "--connect", _url(emu)])
        assert result.exit_code == 1, result.output
        assert f"no step is for payload '{name}'" in result.output and fragment in result.output
        assert str(path) in result.output and "Traceback" not in result.output
        with emu.lock:
            assert emu.state.value("emissivity") != pytest.approx(0.98)    # nothing reached the camera


def test_a_setup_step_whose_payload_is_no_name_is_refused_where_it_is(tmp_path):
    path = tmp_path / "flight.setup.json"
    doc = json.loads(dumps_setup("flight", _compiled_like_steps()))
    doc["steps"][1]["payload"] = 7
    path.write_text(json.dumps(doc))
    result = CliRunner().invoke(cli, ["camera", "apply", str(path), "--payload", "thermal", "--connect",
                                      "udpout:127.0.0.1:9"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert f"{path}: step 2" in result.output and "payload 7 is not a payload name" in result.output
    assert "hint: " in result.output


def test_apply_payload_on_a_file_whose_steps_name_none(tmp_path):
    path = _setup_file(tmp_path, _compiled_like_steps())       # SetupStep's payload left empty
    result = CliRunner().invoke(cli, ["camera", "apply", path, "--payload", "thermal", "--connect",
                                      "udpout:127.0.0.1:9"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "no step names its payload" in result.output and "compile the plan again" in result.output
