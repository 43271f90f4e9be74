"""Real peers: MAVSDK 4.1.0's mission_raw_server as the vehicle receives our uploads (1, 100, 1000
items) and our read-back matches; MAVSDK's mission_raw as the ground station uploads to and
downloads from our vehicle_sim. MAVSDK runs in a child process (tests/mission_peers.py)."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

import mission_peers
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem
from wiris_tools.link import Link
from wiris_tools.readback import compare_items
from wiris_tools.transfer import MissionClient
from wiris_tools.vehicle_sim import VehicleSim

pytestmark = pytest.mark.peer


def mission(n: int) -> list[MissionItem]:
    out = []
    for i in range(n):
        if i % 10 == 5:
            out.append(MissionItem(command=mavlink2.MAV_CMD_IMAGE_START_CAPTURE, frame=FRAME_MISSION, param2=2.0,
                                   param4=math.nan))
        else:
            out.append(MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                                   param4=math.nan, x=490000000 + 100 * i, y=160000000 + 77 * i,
                                   z=50.0 + 0.25 * (i % 40), current=int(i == 0)))
    return out


@pytest.fixture(scope="module")
def mavsdk_vehicle(tmp_path_factory):
    server = mission_peers.MavsdkServer(tmp_path_factory.mktemp("mavsdk-server"))
    link = Link(f"udpout:127.0.0.1:{server.port}", heartbeat_s=0.5)
    try:
        link.wait_heartbeat(timeout=20, system=1, component=1)
        yield server, MissionClient(link, 1, 1)
    finally:
        link.close()
        server.close()


@pytest.mark.parametrize("n", [1, 100, 1000])
def test_our_upload_to_mavsdk_server_is_identical(mavsdk_vehicle, n):
    server, client = mavsdk_vehicle
    items = mission(n)   # never an empty upload: MISSION_COUNT 0 wedges the MAVSDK server
    client.upload(items)
    incoming = server.incoming(timeout=30)
    assert incoming is not None
    result, got = incoming
    assert result == "SUCCESS"
    compare_items(items, got, where="MAVSDK incoming_mission")
    back, _ = client.download()
    compare_items(items, back, where="our read-back from MAVSDK")


def test_upload_verified_against_mavsdk_server(mavsdk_vehicle):
    server, client = mavsdk_vehicle
    result = client.upload_verified(mission(30))
    assert result.verified
    assert server.incoming(timeout=30)[0] == "SUCCESS"


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_mavsdk_ground_station_uploads_to_and_downloads_from_vehicle_sim(tmp_path, flavour):
    items = mission(120)
    with VehicleSim(flavour=flavour, heartbeat_s=0.5) as sim:
        client = mission_peers.MavsdkClient(sim.port, tmp_path)
        try:
            up = client.upload(items)
            assert up["ok"], up
            compare_items(items, sim.items(), where="vehicle_sim after MAVSDK upload")
            down = client.download()
            assert down["ok"], down
            compare_items(items, down["items"], where="MAVSDK download from vehicle_sim")
        finally:
            client.close()
