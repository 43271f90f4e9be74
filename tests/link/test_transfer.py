"""Mission transfer against our vehicle-side server over real UDP on 127.0.0.1: round trips of all
three mission types, legacy requests, NACK tolerance, item limits, verification catching a changed
item, ArduPilot's home row, stale acks, and clear errors when nobody answers."""

from __future__ import annotations

import math
import re

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import (FRAME_GLOBAL_RELATIVE_ALT, FRAME_MISSION, MISSION_TYPE_FENCE, MISSION_TYPE_MISSION,
                            MISSION_TYPE_RALLY, MissionItem)
from raw_peers import lose_accepted_acks, rarely_answering_vehicle, scripted_vehicle, timed_call
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.readback import compare_items
from wiris_tools.transfer import MissionClient, Timeouts, UploadUnconfirmed
from wiris_tools.vehicle_sim import VehicleSim

FAST = Timeouts(ack_s=0.4, item_s=0.1, retries=3, nack_grace_s=0.8, first_s=0.2)


def waypoints(n: int, mission_type: int = MISSION_TYPE_MISSION) -> list[MissionItem]:
    out = []
    for i in range(n):
        if i % 7 == 3:
            out.append(MissionItem(command=mavlink2.MAV_CMD_IMAGE_START_CAPTURE, frame=FRAME_MISSION,
                                   param2=2.0, param3=0, param4=math.nan, mission_type=mission_type))
        else:
            out.append(MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL_RELATIVE_ALT,
                                   param4=math.nan, x=490000000 + 137 * i, y=160000000 - 91 * i, z=50.25 + i,
                                   mission_type=mission_type, current=int(i == 0)))
    return out


@pytest.fixture(params=["ardupilot", "px4"])
def vehicle(request):
    with VehicleSim(flavour=request.param, heartbeat_s=0.2) as sim, \
            Link(f"udpout:127.0.0.1:{sim.port}", heartbeat_s=0.2) as link:
        link.wait_heartbeat(timeout=3, system=1)
        yield sim, MissionClient(link, 1, 1)


def test_mission_round_trip_is_identical(vehicle):
    sim, client = vehicle
    items = waypoints(60)
    seen = []
    up = client.upload(items, progress=lambda done, total: seen.append((done, total)))
    assert up.count == 60 and up.opaque_id != 0
    assert all(a.same_on_wire(b) for a, b in zip(items, sim.items()))
    got, down = client.download()
    compare_items(items, got)
    assert down.opaque_id == up.opaque_id
    assert seen[-1] == (60, 60) and [d for d, _ in seen] == sorted(d for d, _ in seen)


def test_verified_is_a_field_of_the_result_not_a_note(vehicle):
    _sim, client = vehicle
    assert client.upload(waypoints(4)).verified is False
    result = client.upload_verified(waypoints(4))
    assert result.verified is True and "verified" not in result.notes


@pytest.mark.parametrize("kind", [MISSION_TYPE_FENCE, MISSION_TYPE_RALLY])
def test_fence_and_rally_lists_are_separate(vehicle, kind):
    sim, client = vehicle
    client.upload(waypoints(5))
    other = [MissionItem(command=mavlink2.MAV_CMD_NAV_RALLY_POINT if kind == MISSION_TYPE_RALLY
                         else mavlink2.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, param1=150.0, x=490000000, y=160000000,
                         mission_type=kind)]
    client.upload_verified(other, mission_type=kind)
    assert len(sim.items(MISSION_TYPE_MISSION)) == 5 and len(sim.items(kind)) == 1


def test_legacy_mission_request_is_answered_with_the_int_item():
    # The ArduPilot flavour requests with MISSION_REQUEST and refuses float MISSION_ITEMs, so a
    # completed upload proves the INT item went out for every legacy request.
    with VehicleSim(flavour="ardupilot", legacy_requests=True) as sim, \
            Link(f"udpout:127.0.0.1:{sim.port}") as link:
        MissionClient(link).upload(waypoints(12))
        assert sim.stats["items"] == 12 and sim.stats["nacks"] == 0


def test_transient_nacks_are_tolerated():
    with VehicleSim(flavour="ardupilot", nack_rate=0.3, seed=4, rerequest_s=0.1) as sim, \
            Link(f"udpout:127.0.0.1:{sim.port}") as link:
        items = waypoints(30)
        result = MissionClient(link).upload_verified(items)
        assert result.nacks_tolerated > 0 and sim.stats["nacks"] > 0
        compare_items(items, sim.items())


def test_px4_item_limit_gives_no_space_with_a_hint():
    with VehicleSim(flavour="px4", item_limit=20) as sim, Link(f"udpout:127.0.0.1:{sim.port}") as link:
        with pytest.raises(LinkError) as err:
            MissionClient(link, timeouts=FAST).upload(waypoints(21))
        assert "MAV_MISSION_NO_SPACE" in str(err.value) and "fewer items" in err.value.hint
        assert sim.items() == []


class TamperingSim(VehicleSim):
    """Stores what it got but reports item 4 with another altitude - a vehicle that rounds or loses."""

    def _download_view(self, kind):
        items = list(super()._download_view(kind))
        if len(items) > 4:
            items[4] = items[4].with_(z=items[4].z + 0.5)
        return items


def test_verify_names_the_first_differing_item_and_field():
    with TamperingSim(flavour="px4") as sim, Link(f"udpout:127.0.0.1:{sim.port}") as link:
        with pytest.raises(LinkError) as err:
            MissionClient(link).upload_verified(waypoints(8))
    assert "item 4 differs in z" in str(err.value) and "upload again" in err.value.hint


def test_ardupilot_home_row_is_not_a_difference():
    home = MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=0, x=491111111, y=161111111, z=312.0)
    with VehicleSim(flavour="ardupilot", home=home) as sim, Link(f"udpout:127.0.0.1:{sim.port}") as link:
        link.wait_heartbeat(timeout=3, system=1)
        client = MissionClient(link)
        client.upload_verified(waypoints(6))
        got, _ = client.download()
        assert got[0].x == home.x  # the vehicle really reports its home in item 0
        with pytest.raises(LinkError, match="item 0 differs"):
            compare_items(waypoints(6), got)


def test_compare_items_float32_nan_and_length():
    a = MissionItem(command=16, param1=0.1, param4=math.nan, z=10.0)
    compare_items([a], [a.with_(param1=0.100000001)])          # equal as float32
    with pytest.raises(LinkError, match="item 0 differs in param4") as err:
        compare_items([a], [a.with_(param4=0.0)])
    assert err.value.hint
    with pytest.raises(LinkError, match="holds 0 items, 1 were sent") as err:
        compare_items([a], [])
    assert err.value.hint


def test_no_vehicle_is_a_clear_error():
    with Link("udpout:127.0.0.1:9", heartbeat_s=0) as link:   # discard port: nobody answers
        with pytest.raises(LinkError) as err:
            MissionClient(link, timeouts=FAST).upload(waypoints(3))
        assert "no request after MISSION_COUNT" in str(err.value) and err.value.hint
        with pytest.raises(LinkError, match="no MISSION_COUNT") as err:
            MissionClient(link, timeouts=FAST).download()
        assert err.value.hint


def test_empty_or_oversized_upload_is_refused():
    with Link("udpout:127.0.0.1:9", heartbeat_s=0) as link:
        with pytest.raises(LinkError, match="empty") as err:
            MissionClient(link).upload([])
        assert err.value.hint
        # a .plan's 65535 items plus ArduPilot's home row: refused before anything is sent
        with pytest.raises(LinkError, match="65536 items do not fit the protocol's 16-bit count") as err:
            MissionClient(link).upload(waypoints(1) * 65536)
        assert err.value.where == "mission on system 1" and "split the mission" in err.value.hint


def test_stale_accepted_ack_does_not_end_an_upload():
    got = []

    def script(veh, m):
        src = (m.get_srcSystem(), m.get_srcComponent())
        if m.get_type() == "MISSION_COUNT":
            veh.send(veh.mav.mission_ack_encode(*src, mavlink2.MAV_MISSION_ACCEPTED, 0))   # stale
            veh.send(veh.mav.mission_request_int_encode(*src, 0, 0))
        else:
            got.append(m.seq)
            nxt = m.seq + 1
            if nxt < 4:
                veh.send(veh.mav.mission_request_int_encode(*src, nxt, 0))
            else:
                veh.send(veh.mav.mission_ack_encode(*src, mavlink2.MAV_MISSION_ACCEPTED, 0))

    veh = scripted_vehicle(script)
    try:
        with Link(f"udpout:127.0.0.1:{veh.local_port}") as link:
            MissionClient(link).upload(waypoints(4))
        assert got == [0, 1, 2, 3]
    finally:
        veh.close()


def test_fatal_nack_without_further_requests_names_the_item():
    def script(veh, m):
        src = (m.get_srcSystem(), m.get_srcComponent())
        if m.get_type() == "MISSION_COUNT":
            veh.send(veh.mav.mission_request_int_encode(*src, 0, 0))
        elif m.seq == 0:
            veh.send(veh.mav.mission_request_int_encode(*src, 1, 0))
        else:
            veh.send(veh.mav.mission_ack_encode(*src, mavlink2.MAV_MISSION_UNSUPPORTED, 0))

    veh = scripted_vehicle(script)
    try:
        with Link(f"udpout:127.0.0.1:{veh.local_port}") as link:
            with pytest.raises(LinkError) as err:
                MissionClient(link, timeouts=FAST).upload(waypoints(3))
        text = str(err.value)
        assert "MAV_MISSION_UNSUPPORTED to item 1 (MAV_CMD_NAV_WAYPOINT)" in text and "firmware" in err.value.hint
    finally:
        veh.close()


@pytest.mark.parametrize("refused,answer,text", [
    ("MISSION_REQUEST_LIST", mavlink2.MAV_MISSION_INVALID, "MAV_MISSION_INVALID to the list request"),
    ("MISSION_REQUEST_INT", mavlink2.MAV_MISSION_OPERATION_CANCELLED,
     "MAV_MISSION_OPERATION_CANCELLED to the request for item 0"),
])
def test_download_refused_by_the_vehicle_says_what_to_do(refused, answer, text):
    # answers that _NACK_HINTS has no word for still come with a hint
    def script(veh, m):
        src = (m.get_srcSystem(), m.get_srcComponent())
        if m.get_type() == refused:
            veh.send(veh.mav.mission_ack_encode(*src, answer, 0))
        elif m.get_type() == "MISSION_REQUEST_LIST":
            veh.send(veh.mav.mission_count_encode(*src, 2, 0))

    veh = scripted_vehicle(script, ("MISSION_REQUEST_LIST", "MISSION_REQUEST_INT"))
    try:
        with Link(f"udpout:127.0.0.1:{veh.local_port}") as link:
            with pytest.raises(LinkError) as err:
                MissionClient(link, timeouts=FAST).download()
        assert text in str(err.value) and err.value.where == "mission on system 1"
        assert "retry the download" in err.value.hint
    finally:
        veh.close()


def test_lost_final_ack_is_unconfirmed_and_verify_settles_it():
    """ArduPilot answers a repeated last item with MAV_MISSION_ERROR once it is done (GCS_Common.cpp); if
    its ACCEPTED ack was lost, upload says 'unconfirmed' and upload_verified proves it by read-back."""
    with VehicleSim(flavour="ardupilot") as sim:
        lost = lose_accepted_acks(sim)
        with Link(f"udpout:127.0.0.1:{sim.port}") as link:
            client = MissionClient(link, timeouts=FAST)
            with pytest.raises(UploadUnconfirmed):
                client.upload(waypoints(5))
            lost["n"] = 1
            result = client.upload_verified(waypoints(5))
            assert result.verified and any("final MISSION_ACK" in n for n in result.notes)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from wiris_tools.transfer import RttEstimator  # noqa: E402


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(min_value=0.0, max_value=10.0), max_size=50),
       st.floats(min_value=0.001, max_value=0.1), st.floats(min_value=0.2, max_value=3.0))
def test_rto_stays_between_floor_and_cap_and_above_srtt(samples, floor, cap):
    est = RttEstimator()
    for s in samples:
        est.sample(s)
    rto = est.rto(floor, cap, 0.25)
    assert floor <= rto <= cap or (est.srtt is None and rto == min(0.25, cap))
    if est.srtt is not None and 1.5 * est.srtt <= cap:
        assert rto >= 1.5 * est.srtt - 1e-12   # never retransmit before a normal round trip is over


@pytest.mark.parametrize("deadline_s,source", [(1.0, "1 s (given)"), (None, "s (0.5 s plus 8 measured round trips")])
def test_download_from_a_vehicle_answering_rarely_ends_at_its_deadline(deadline_s, source):
    # 65535 items when the deadline is given; for the derived one a count whose deadline is a few seconds
    # (0.5 s + 40 items x 8 round trips) while the vehicle's pace needs about 40 x 0.6 s.
    count = 65535 if deadline_s is not None else 40
    veh, seen = rarely_answering_vehicle(count)
    try:
        with Link(f"udpout:127.0.0.1:{veh.local_port}") as link:
            client = MissionClient(link, timeouts=Timeouts(deadline_floor_s=0.5))
            call = timed_call(lambda: client.download(deadline_s=deadline_s), limit_s=120)
        assert call.finished and call.error is not None, call
        text = str(call.error)
        assert "the download did not finish within its deadline of " in text and source in text, text
        assert f"of {count} items had arrived" in text and "--deadline SECONDS" in call.error.hint
        arrived = int(re.search(r"(\d+) of \d+ items had arrived", text).group(1))
        assert seen["requests"] > 0 and arrived < count   # it gave up before the vehicle had given everything
    finally:
        veh.close()


def test_derived_download_deadline_grows_with_count_and_round_trip():
    from wiris_tools.transfer import download_deadline_s, worst_item_s

    t = Timeouts()
    assert download_deadline_s(0, 0.001, t) == t.deadline_floor_s
    assert download_deadline_s(700, 0.1, t) > 700 * 0.1 * 4          # a clean radio link has room to spare
    assert download_deadline_s(700, 0.2, t) > download_deadline_s(700, 0.1, t)
    # a slow answer to the list request earns no more than the spec's per-item time per round trip
    assert download_deadline_s(65535, 5.0, t) == download_deadline_s(65535, t.item_s, t)
    assert download_deadline_s(65535, 5.0, t) <= t.deadline_floor_s + 65535 * worst_item_s(t)
    # the finding's hostile vehicle on a fast link (every 6th request answered, ~0.62 s per item) gets far less
    assert download_deadline_s(65535, 0.001, t) < 65535 * 0.62 / 5
