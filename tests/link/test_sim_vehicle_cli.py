"""`wiris sim vehicle` as a real child process on 127.0.0.1: `wiris mission upload --verify` (mission and fence) and
`download` against it for both firmwares, AUTOPILOT_VERSION, Ctrl-C / SIGTERM stopping it cleanly, bad input."""

from __future__ import annotations

import re
import signal

import pytest
from click.testing import CliRunner

from cli_child import stop, wiris_child
from mission_plans import small_plan
from missions.compile import compile_plan
from missions.formats.outputs import write_outputs
from missions.formats.planfile import load_plan
from wiris_tools.cli import cli


def run(*args):
    return CliRunner().invoke(cli, list(map(str, args)))


def _port(first_line: str) -> int:
    m = re.search(r"on udpin:127\.0\.0\.1:(\d+)", first_line)
    assert m, first_line
    return int(m.group(1))


def _zone_plan(tmp_path, firmware: str):
    path = small_plan(tmp_path, firmware=firmware, camera_change=False)
    path.write_text(path.read_text().replace(
        "      altitude_m: 40\n",
        "      altitude_m: 40\n      exclude: [[[50.1114, 14.5048], [50.1114, 14.5052], [50.1116, 14.5052], "
        "[50.1116, 14.5048]]]\n", 1) + "fence: {margin_m: 30}\n")
    return path


@pytest.mark.parametrize("firmware,signum", [("ardupilot", signal.SIGINT), ("px4", signal.SIGTERM)])
def test_upload_verify_and_download_against_the_simulated_vehicle(tmp_path, firmware, signum):
    compiled = compile_plan(_zone_plan(tmp_path, firmware))
    out = tmp_path / "out"
    write_outputs(compiled, out)
    plan = out / f"{compiled.name}.plan"
    with wiris_child("sim", "vehicle", "--connect", "udpin:127.0.0.1:0", "--firmware", firmware) as proc:
        first = proc.stderr.readline()
        assert first.startswith(f"simulated {firmware} vehicle (system 1) on udpin:127.0.0.1:"), first
        gcs = f"udpout:127.0.0.1:{_port(first)}"
        up = run("mission", "upload", plan, "--verify", "--connect", gcs)
        assert up.exit_code == 0, up.output
        assert f"({firmware})" in up.output and "verified by read-back" in up.output
        fence = run("mission", "upload", plan, "--type", "fence", "--verify", "--connect", gcs)
        assert fence.exit_code == 0, fence.output
        assert f"uploaded {len(compiled.fence)} fence items" in fence.output
        back = tmp_path / "back.plan"
        down = run("mission", "download", "-o", back, "--connect", gcs)
        assert down.exit_code == 0, down.output
        rest = stop(proc, signum)
    assert rest.rstrip().endswith(f"vehicle stopped, holding {len(compiled.items) + (firmware == 'ardupilot')} "
                                  f"mission, {len(compiled.fence)} fence, 0 rally items"), rest
    items, fence_items, rally, _home = load_plan(back)
    assert len(items) == len(compiled.items) and not rally
    assert [(f.command, f.x, f.y) for f in fence_items] == [(f.command, f.x, f.y) for f in compiled.fence]


@pytest.mark.parametrize("firmware,major", [("ardupilot", 4), ("px4", 1)])
def test_the_simulated_vehicle_answers_autopilot_version(firmware, major):
    from pymavlink.dialects.v20 import common as mav

    from wiris_tools.link import Link

    with wiris_child("sim", "vehicle", "--connect", "udpin:127.0.0.1:0", "--firmware", firmware) as proc:
        port = _port(proc.stderr.readline())
        with Link(f"udpout:127.0.0.1:{port}", system=255, component=190) as gcs:
            beat = gcs.wait_heartbeat(timeout=10)
            assert beat.autopilot == (mav.MAV_AUTOPILOT_ARDUPILOTMEGA if firmware == "ardupilot"
                                      else mav.MAV_AUTOPILOT_PX4)
            box = gcs.inbox(["AUTOPILOT_VERSION", "COMMAND_ACK"])
            version = None
            for _ in range(20):          # UDP: ask again until it answers (bounded)
                gcs.send(gcs.mav.command_long_encode(1, 1, mav.MAV_CMD_REQUEST_MESSAGE, 0,
                                                     mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION, 0, 0, 0, 0, 0, 0))
                msg = box.get(0.5)
                while msg is not None and msg.get_type() != "AUTOPILOT_VERSION":
                    msg = box.get(0.5)
                if msg is not None:
                    version = msg
                    break
            box.close()
        stop(proc, signal.SIGTERM)
    assert version is not None
    assert version.flight_sw_version >> 24 == major
    assert version.capabilities & mav.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
    assert version.capabilities & mav.MAV_PROTOCOL_CAPABILITY_MISSION_INT


@pytest.mark.parametrize("args,code,fragment", [
    (["--connect", "udpin:127.0.0.1:99999", "--firmware", "px4"], 1, "port 99999 is not 0-65535"),
    (["--connect", "udpin:127.0.0.1:0", "--firmware", "inav"], 2, "'inav' is not one of"),
    (["--connect", "udpin:127.0.0.1:0", "--firmware", "ardupilot", "--home", "-35.3,149.1"], 2, "LAT,LON,ALT"),
    (["--connect", "udpin:127.0.0.1:0", "--firmware", "ardupilot", "--home", "95,149.1,584"], 2, "-90..90"),
    (["--firmware", "px4"], 2, "--connect"),
])
def test_bad_sim_vehicle_input_is_refused_with_a_message(args, code, fragment):
    r = run("sim", "vehicle", *args, "--duration", "0.1")
    assert r.exit_code == code, r.output
    assert fragment in r.output and "Traceback" not in r.output


def test_fence_upload_straight_from_a_capture_plan(tmp_path):
    from missions.emit.items import MISSION_TYPE_FENCE
    from wiris_tools.vehicle_sim import VehicleSim

    path = _zone_plan(tmp_path, "px4")
    compiled = compile_plan(path)
    with VehicleSim(flavour="px4") as sim:
        r = run("mission", "upload", path, "--type", "fence", "--verify", "--connect", f"udpout:127.0.0.1:{sim.port}")
        assert r.exit_code == 0, r.output
        held = sim.items(MISSION_TYPE_FENCE)
    assert [(f.command, f.param1, f.x, f.y) for f in held] == [(f.command, f.param1, f.x, f.y) for f in compiled.fence]


def test_fence_upload_of_a_capture_plan_without_a_fence_says_how_to_get_one(tmp_path):
    path = small_plan(tmp_path, camera_change=False)
    r = run("mission", "upload", path, "--type", "fence", "--connect", "udpout:127.0.0.1:9")
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert f"{path}: the capture plan has no fence" in r.output and "fence: {margin_m: 30}" in r.output
