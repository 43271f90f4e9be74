"""Uploads whose vehicle's requests get lost, over real UDP through tests/request_dropper.py. MAVSDK 4.1.0's
mission_raw_server ignores a repeated item without a word and asks again only at its own timer (about 1 s):
the next item, sent unasked once a resend got no answer, must reach it first, and it must end up with
exactly our items. vehicle_sim (ArduPilot-/PX4-like) gets the same upload right."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

import mission_peers
from request_dropper import RequestDropper
from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MissionItem
from wiris_tools.link import Link
from wiris_tools.readback import compare_items
from wiris_tools.transfer import MissionClient
from wiris_tools.vehicle_sim import VehicleSim

DROPPED = {3, 7, 10}   # not adjacent: the item after a lost request is pushed, not the one after that


def mission(n: int) -> list[MissionItem]:
    return [MissionItem(command=mavlink2.MAV_CMD_IMAGE_START_CAPTURE, frame=FRAME_MISSION, param2=2.0, param4=0.0)
            if i % 5 == 4 else
            MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL_RELATIVE_ALT, param4=math.nan,
                        x=490000000 + 100 * i, y=160000000 + 77 * i, z=50.0 + i, current=int(i == 0))
            for i in range(n)]


@pytest.mark.peer
def test_mavsdk_server_gets_the_next_item_before_it_asks_again(tmp_path):
    server = mission_peers.MavsdkServer(tmp_path)
    try:
        with RequestDropper(server.port, DROPPED) as relay:
            link = Link(f"udpout:127.0.0.1:{relay.port}", heartbeat_s=0.5)
            try:
                link.wait_heartbeat(timeout=20, system=1, component=1)
                items = mission(12)
                MissionClient(link, 1, 1).upload(items)
            finally:
                link.close()
            assert sorted(relay.dropped) == sorted(DROPPED)
            # The item after each lost request reached the server before its own re-request timer (about
            # 1 s) ran out: it asked for each of those items once, the request that was lost.
            assert {s: relay.requests[s] for s in DROPPED} == {s: 1 for s in DROPPED}
        incoming = server.incoming(timeout=30)
        assert incoming is not None
        result, got = incoming
        assert result == "SUCCESS"
        assert len(got) == len(items)
        compare_items(items, got, where="MAVSDK incoming_mission")
    finally:
        server.close()


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_vehicle_sim_upload_survives_lost_requests(flavour):
    with VehicleSim(flavour=flavour, item_limit=None, heartbeat_s=0.5) as sim, \
            RequestDropper(sim.port, DROPPED) as relay:
        link = Link(f"udpout:127.0.0.1:{relay.port}", heartbeat_s=0.5)
        try:
            link.wait_heartbeat(timeout=20, system=1)
            items = mission(12)
            result = MissionClient(link, 1, 1).upload(items)
        finally:
            link.close()
        assert sorted(relay.dropped) == sorted(DROPPED)
        assert result.resent >= len(DROPPED)   # each lost request answered by a resend, not by waiting only
        assert result.count == len(items)
        compare_items(items, sim.items())
