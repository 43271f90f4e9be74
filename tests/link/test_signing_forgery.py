"""A forged signed frame must not lock a signed peer out (MAVLink 2 signing spec: a stream's timestamp
moves only on a message whose signature verifies). Each signed endpoint, over real UDP on 127.0.0.1,
first receives frames that claim its peer's system/component/link ids but carry no valid signature -
one with no key at all dated 2^48-1 (the largest timestamp there is), one signed with a wrong key dated
10 s ahead - and then the real peer's correctly signed traffic, which must work.

The cameras and the vehicle listen (udpin), so their forged frames come after a first session and before
a restarted ground station's; the ground-station tools (camera client, mission upload and download) are
attacked at start-up, before the camera's or vehicle's first frame, with the peer sending to them."""

from __future__ import annotations

import socket
import time
from contextlib import contextmanager

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.camera_client import CameraClient
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.signing import key_from_text, signing_timestamp
from wiris_tools.transfer import MissionClient, Timeouts, find_autopilot
from wiris_tools.vehicle_sim import VehicleSim

KEY = key_from_text("the key both real peers hold")
WRONG_KEY = key_from_text("a key the attacker made up")
LARGEST_TIMESTAMP = 2**48 - 1
GCS = (255, mavlink2.MAV_COMP_ID_MISSIONPLANNER)          # what a Link is by default
CAMERA = (1, mavlink2.MAV_COMP_ID_CAMERA)                 # the WIRIS emulator's default ids
VEHICLE = (1, mavlink2.MAV_COMP_ID_AUTOPILOT1)            # VehicleSim's
# Short waits, so that on a link that drops the real peer a call gives up well inside the 10 s for which
# a wrong-key frame dated 10 s ahead held the stream (with it the test could not fail before the fix).
FAST = Timeouts(ack_s=0.4, item_s=0.1, retries=3, nack_grace_s=0.8, first_s=0.2)
ITEMS_ON_THE_WIRE = 4


def forged_heartbeat(ids: tuple[int, int], variant: str) -> bytes:
    """A signed HEARTBEAT frame claiming `ids` on signing link 0 that no key holder sent."""
    mav = mavlink2.MAVLink(None, srcSystem=ids[0], srcComponent=ids[1])
    mav.signing.sign_outgoing = True
    mav.signing.link_id = 0
    if variant == "no-key":
        mav.signing.secret_key = bytes(32)
        mav.signing.timestamp = LARGEST_TIMESTAMP
    else:
        mav.signing.secret_key = WRONG_KEY
        mav.signing.timestamp = signing_timestamp(time.time() + 10.0)
    frame = bytearray(mav.heartbeat_encode(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0,
                                           mavlink2.MAV_STATE_ACTIVE).pack(mav))
    if variant == "no-key":
        frame[-6:] = bytes(6)   # the signature: someone without any key can only make it up
    return bytes(frame)


VARIANTS = pytest.mark.parametrize("variant", ["no-key", "wrong-key"],
                                   ids=["no-key-ts-2^48-1", "wrong-key-ts-plus-10s"])


@contextmanager
def attacker():
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        yield sock
    finally:
        sock.close()


def forge(victim: Link, ids: tuple[int, int], variant: str) -> None:
    """Send the forged frame to `victim` and wait (bounded) until it has read and rejected it."""
    before = victim.stats["rejected_signature"]
    with attacker() as sock:
        sock.sendto(forged_heartbeat(ids, variant), ("127.0.0.1", victim.local_port))
        for _ in range(500):
            if victim.stats["rejected_signature"] > before:
                return
            time.sleep(0.01)
    raise AssertionError("the victim never read the forged frame")


def waypoints() -> list:
    from missions.emit.items import FRAME_GLOBAL_RELATIVE_ALT, MissionItem
    return [MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                        x=490000000 + 1000 * i, y=160000000, z=40.0) for i in range(ITEMS_ON_THE_WIRE)]


def gcs_to(port: int) -> Link:
    return Link(f"udpout:127.0.0.1:{port}", heartbeat_s=0.2, signing_key=KEY)


# -- the listening endpoints: the WIRIS emulator and the vehicle (mission upload/download's peer) --------

@VARIANTS
def test_wiris_emulator_keeps_a_restarted_ground_station_after_a_forged_frame(variant):
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", signing_key=KEY) as emu:
        with gcs_to(emu.link.local_port) as first:
            assert CameraClient(first, timeout_s=0.5, retries=2).information().model
        forge(emu.link, GCS, variant)
        with gcs_to(emu.link.local_port) as restarted:
            info = CameraClient(restarted, timeout_s=0.5, retries=2).information()
        assert (info.system, info.component) == CAMERA
        assert emu.link.stats["rejected_signature"] == 1


@VARIANTS
def test_vehicle_keeps_a_restarted_ground_station_after_a_forged_frame(variant):
    with VehicleSim(flavour="px4", signing_key=KEY, heartbeat_s=0.2) as sim:
        with gcs_to(sim.port) as first:
            find_autopilot(first, 1, timeout=3)
            MissionClient(first, *VEHICLE, timeouts=FAST).upload(waypoints())
        forge(sim.link, GCS, variant)
        with gcs_to(sim.port) as restarted:
            find_autopilot(restarted, 1, timeout=3)
            client = MissionClient(restarted, *VEHICLE, timeouts=FAST)
            client.upload(waypoints()[:2])
            got, _ = client.download()
        assert len(got) == 2 and len(sim.items()) == 2
        assert sim.link.stats["rejected_signature"] == 1


def test_the_rededge_emulator_is_not_a_signed_endpoint():
    # RedEdge talks MAVLink 1 (its serial API), which has no signature: it cannot take a key at all.
    with pytest.raises(LinkError, match="MAVLink 1 cannot be signed"):
        start_emulator("rededge-mx", "udpin:127.0.0.1:0", signing_key=KEY)


# -- the ground-station tools, attacked before the peer's first frame ---------------------------------

@contextmanager
def listening_gcs():
    with Link("udpin:127.0.0.1:0", heartbeat_s=0.2, signing_key=KEY) as link:
        yield link


@VARIANTS
def test_camera_client_takes_the_camera_after_a_forged_frame(variant):
    with listening_gcs() as gcs:
        forge(gcs, CAMERA, variant)
        with start_emulator("wiris-pro", f"udpout:127.0.0.1:{gcs.local_port}", signing_key=KEY):
            info = CameraClient(gcs, find_timeout_s=3, timeout_s=0.5, retries=2).information()
        assert (info.system, info.component) == CAMERA
        assert gcs.stats["rejected_signature"] == 1


@VARIANTS
def test_mission_upload_and_download_take_the_vehicle_after_a_forged_frame(variant):
    with listening_gcs() as gcs:
        forge(gcs, VEHICLE, variant)
        with VehicleSim(f"udpout:127.0.0.1:{gcs.local_port}", flavour="ardupilot", signing_key=KEY,
                        heartbeat_s=0.2) as sim:
            hb = find_autopilot(gcs, None, timeout=3)
            client = MissionClient(gcs, hb.get_srcSystem(), VEHICLE[1], timeouts=FAST)
            client.upload(waypoints())
            got, _ = client.download()
        assert len(got) == ITEMS_ON_THE_WIRE and len(sim.items()) == ITEMS_ON_THE_WIRE
        assert gcs.stats["rejected_signature"] == 1
