"""A small vehicle-side mission server, for tests and benchmarks (not a flight simulator).

It holds a mission, a fence and a rally list, and plays the vehicle's half of the mission protocol
with the behaviours that matter to a ground station, modelled on the real autopilots:

flavour "ardupilot" (ArduPilot's GCS_MAVLink/MissionItemProtocol.cpp and GCS_Common.cpp):
  * requests with the legacy MISSION_REQUEST, re-sent when nothing arrives for 1 s; gives up
    after 8 s without items with MISSION_ACK OPERATION_CANCELLED;
  * an item that is not the one requested (a duplicate, a reordered one) gets MISSION_ACK
    INVALID_SEQUENCE and the transfer goes on - the "transient error NACK"; an item when no
    upload is being received (a repeated last item after completion) gets MISSION_ACK ERROR;
  * MISSION_COUNT cuts the mission (and rally list) to the new count at once and each item then
    replaces or appends one (a failed upload leaves old and new items mixed); the fence is
    replaced only when complete;
  * list and item requests during an upload get MISSION_ACK DENIED;
  * optional `ack_defer_s`: the final ACCEPTED waits that long (a build with the mission's opaque
    id, AP_MAVLINK_MISSION_OPAQUE_ID_ENABLED: it is sent once the mission has been unchanged for
    500 ms and its checksum is computed) and the upload counts as still being received meanwhile;
  * optional `nack_rate`: an extra transient MISSION_ACK ERROR instead of accepting an item
    (the item is dropped and re-requested later), seeded;
  * optional `home`: item 0 of a downloaded MISSION is the vehicle's home, as ArduPilot does;
  * optional `mavlink1`: every message framed as MAVLink 1 (SERIALn_PROTOCOL = 1); a fence or
    rally transfer then gets UNSUPPORTED (GCS_Common.cpp mavlink2_requirement_met) in an ack whose
    MAVLink 1 payload has no mission_type, so it reads as being about the mission.
flavour "px4" (PX4's mavlink_mission.cpp):
  * MISSION_REQUEST_INT, re-sent after 250 ms; gives up after 5 s;
  * an out-of-order item is ignored and the expected one re-requested;
  * an item limit (default 500, PX4 PR #18827): a larger MISSION_COUNT gets NO_SPACE;
  * the last item arriving again after completion gets the ACCEPTED ack again.
Both: MISSION_ACK ACCEPTED carries an opaque_id (CRC32 of the stored items, as ArduPilot's is a
CRC32 of the item fields), MISSION_COUNT on download carries it too; MISSION_CLEAR_ALL clears;
MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES and MAV_CMD_REQUEST_MESSAGE(AUTOPILOT_VERSION) get MAV_RESULT_ACCEPTED and
an AUTOPILOT_VERSION (the firmware's version number and the mission-protocol capabilities it has); any other
COMMAND_LONG gets MAV_RESULT_UNSUPPORTED (ground stations probe capabilities). With
`stores_like_firmware=True` a download gives each item back as that firmware does (params it
does not keep as 0, whole numbers, centimetre altitudes, its frames, PX4's yaw through radians;
firmware_readback, from readback.readback_rule); otherwise exactly as it was sent.

    with VehicleSim("udpin:127.0.0.1:0", flavour="px4") as sim:
        url = f"udpout:127.0.0.1:{sim.port}"        # point a ground station at it
        ...
        sim.items(MISSION_TYPE_MISSION)               # what it holds
"""

from __future__ import annotations

import math
import random
import struct
import threading
import time
import zlib
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MissionItem
from wiris_tools.link import Link
from wiris_tools.readback import ALT_REFERENCE, ap_float16, ap_loiter_radius, ap_loiter_turns, readback_rule
from wiris_tools.transfer import item_from_msg, with_opaque_id


@dataclass(frozen=True)
class Flavour:
    name: str
    autopilot: int
    legacy_requests: bool
    rerequest_s: float
    abort_s: float
    nack_out_of_order: bool
    item_limit: int | None


FLAVOURS = {
    "ardupilot": Flavour("ardupilot", mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, True, 1.0, 8.0, True, None),
    "px4": Flavour("px4", mavlink2.MAV_AUTOPILOT_PX4, False, 0.25, 5.0, False, 500),
}
# AUTOPILOT_VERSION.flight_sw_version: (major, minor, patch) of a current release of each firmware, released
# (FIRMWARE_VERSION_TYPE_OFFICIAL in the low byte)
SOFTWARE_VERSION = {"ardupilot": (4, 5, 7), "px4": (1, 15, 4)}
# what both firmwares report and the simulator does: MISSION_ITEM_INT missions, fence and rally lists, MAVLink 2
CAPABILITIES = (mavlink2.MAV_PROTOCOL_CAPABILITY_MISSION_INT | mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | mavlink2.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE | mavlink2.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
                | mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2)
# the lists a vehicle keeps (MAV_MISSION_TYPE_ALL names them all at once)
MISSION_TYPES = (mavlink2.MAV_MISSION_TYPE_MISSION, mavlink2.MAV_MISSION_TYPE_FENCE, mavlink2.MAV_MISSION_TYPE_RALLY)


@dataclass
class _Upload:
    partner: tuple[int, int]
    mission_type: int
    count: int
    expected: int = 0
    items: list[MissionItem] = field(default_factory=list)
    last_request: float = 0.0
    last_rx: float = 0.0
    ack_at: float | None = None      # ArduPilot deferring its final ACCEPTED until then


def _f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


def _px4_yaw(deg: float) -> float:
    """PX4 keeps a heading as wrap_2pi(radians(deg)) in a float and sends degrees(yaw) back."""
    r = _f32(math.radians(deg))
    if not math.isnan(r) and not 0.0 <= r < 2 * math.pi:
        r = _f32(r - 2 * math.pi * math.floor(r / (2 * math.pi)))
    return _f32(math.degrees(r))


def _kept(kind: str, v):
    """What the firmware sends back of value `v` kept as `kind` (the letters of readback.readback_rule)."""
    if kind == "-":
        return 0 if isinstance(v, int) else 0.0
    if kind == "e":
        return v
    if kind == "g":
        return int(round(_f32(float(v))))
    if kind in "ic":
        n = math.trunc(v) if math.isfinite(v) else 0
        return float(min(255, n) if kind == "c" else n)
    if kind == "b":
        return 1.0 if v > 0 else 0.0
    if kind == "s":
        return -1.0 if v < 0 else 1.0
    if kind == "y":
        return _px4_yaw(v)
    if kind == "t":
        return ap_loiter_turns(v)
    if kind == "r":
        return ap_loiter_radius(v)
    if kind == "k":
        return ap_float16(v)
    if kind == "h":   # ArduPilot: Location.alt = z * 100.0f (int32 cm), sent back as alt * 0.01f
        return _f32(math.trunc(_f32(_f32(v) * 100.0)) * _f32(0.01))
    return _f32(v)


_FRAMES = {"ardupilot": {"amsl": mavlink2.MAV_FRAME_GLOBAL, "home": mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                         "terrain": mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT},
           "px4": {"amsl": mavlink2.MAV_FRAME_GLOBAL_INT, "home": mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                   "terrain": mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT}}


def firmware_readback(item: MissionItem, firmware: str) -> MissionItem:
    """`item` as `firmware` ("ardupilot", "arduplane" or "px4") sends it back after storing it."""
    rule = readback_rule(firmware, item)
    names = ("param1", "param2", "param3", "param4", "x", "y", "z")
    out = item.with_(**{n: _kept(k, getattr(item, n)) for k, n in zip(rule, names)})
    frames = _FRAMES["px4" if firmware == "px4" else "ardupilot"]
    if rule[7] == "L" and item.frame in ALT_REFERENCE:
        out = out.with_(frame=frames[ALT_REFERENCE[item.frame]])
    elif rule[7] == "-":   # not kept: ArduPilot sends 0, PX4 a fence point in GLOBAL_INT
        out = out.with_(frame=frames["amsl"] if firmware == "px4" else mavlink2.MAV_FRAME_GLOBAL)
    if firmware != "px4":  # ArduPilot sends autocontinue 1 for a mission item, leaves it 0 otherwise
        out = out.with_(autocontinue=int(item.mission_type == mavlink2.MAV_MISSION_TYPE_MISSION))
    return out


def opaque_id(items: list[MissionItem]) -> int:
    """A CRC32 over the stored fields (ArduPilot hashes the same fields); never 0 (0 = not given)."""
    crc = 0
    for it in items:
        crc = zlib.crc32(struct.pack("<BHBffffiif", it.frame, it.command, it.autocontinue, it.param1, it.param2,
                                     it.param3, it.param4, it.x, it.y, it.z), crc)
    return crc or 0xFFFFFFFF


class VehicleSim:
    """The vehicle side of the mission protocol on its own Link and thread (see module docstring)."""

    def __init__(self, url: str = "udpin:127.0.0.1:0", *, flavour: str = "ardupilot", system: int = 1,
                 component: int = 1, item_limit: int | None = None, nack_rate: float = 0.0, seed: int = 0,
                 home: MissionItem | None = None, legacy_requests: bool | None = None,
                 rerequest_s: float | None = None, signing_key: bytes | None = None,
                 heartbeat_s: float = 0.5, ack_defer_s: float = 0.0, stores_like_firmware: bool = False,
                 mavlink1: bool = False) -> None:
        f = FLAVOURS[flavour]
        self.flavour = Flavour(f.name, f.autopilot,
                               f.legacy_requests if legacy_requests is None else legacy_requests,
                               f.rerequest_s if rerequest_s is None else rerequest_s, f.abort_s,
                               f.nack_out_of_order, item_limit if item_limit is not None else f.item_limit)
        self.nack_rate = nack_rate
        self.home = home
        self.ack_defer_s = ack_defer_s
        self.stores_like_firmware = stores_like_firmware
        self._rng = random.Random(seed)
        self._lock = threading.Lock()
        self._store: dict[int, list[MissionItem]] = {t: [] for t in MISSION_TYPES}
        self._upload: _Upload | None = None
        self._done: dict[int, tuple[tuple[int, int], int]] = {}   # type -> (partner, count) of last upload
        self.stats = {"requests": 0, "rerequests": 0, "items": 0, "nacks": 0, "uploads": 0, "downloads": 0}
        self.link = Link(url, system=system, component=component, mav_type=mavlink2.MAV_TYPE_QUADROTOR,
                         autopilot=self.flavour.autopilot, heartbeat_s=heartbeat_s, signing_key=signing_key,
                         mavlink1=mavlink1)
        self._stop = threading.Event()
        self._box = self.link.inbox(["MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_LIST",
                                     "MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK", "MISSION_CLEAR_ALL",
                                     "COMMAND_LONG"], to_me=True)
        self._thread = threading.Thread(target=self._run, name="vehicle-sim", daemon=True)
        self._thread.start()

    @property
    def port(self) -> int | None:
        return self.link.local_port

    def items(self, mission_type: int = 0) -> list[MissionItem]:
        with self._lock:
            return list(self._store[mission_type])

    def set_items(self, items: list[MissionItem], mission_type: int = 0) -> None:
        with self._lock:
            self._store[mission_type] = list(items)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self._box.close()
        self.link.close()

    def __enter__(self) -> "VehicleSim":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the loop ------------------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            msg = self._box.get(0.02)
            with self._lock:
                if msg is not None:
                    self._handle(msg)
                self._timers(time.monotonic())

    def _ack(self, to: tuple[int, int], result: int, mission_type: int, opaque: int = 0) -> None:
        if result != mavlink2.MAV_MISSION_ACCEPTED:
            self.stats["nacks"] += 1
        self.link.send(with_opaque_id(self.link.mav.mission_ack_encode(to[0], to[1], result, mission_type), opaque))

    def _request(self, up: _Upload) -> None:
        self.stats["requests"] += 1
        if self.flavour.legacy_requests:
            msg = self.link.mav.mission_request_encode(up.partner[0], up.partner[1], up.expected, up.mission_type)
        else:
            msg = self.link.mav.mission_request_int_encode(up.partner[0], up.partner[1], up.expected,
                                                           up.mission_type)
        up.last_request = time.monotonic()
        self.link.send(msg)

    def _timers(self, now: float) -> None:
        up = self._upload
        if up is None:
            return
        if up.ack_at is not None:
            if now >= up.ack_at:
                self._complete(up)
            return
        if now - up.last_rx > self.flavour.abort_s:
            self._upload = None
            self._ack(up.partner, mavlink2.MAV_MISSION_OPERATION_CANCELLED, up.mission_type)
        elif now - up.last_request > self.flavour.rerequest_s:
            self.stats["rerequests"] += 1
            self._request(up)

    def _handle(self, msg) -> None:
        mtype = msg.get_type()
        src = (msg.get_srcSystem(), msg.get_srcComponent())
        kind = getattr(msg, "mission_type", 0)
        if mtype == "COMMAND_LONG":
            self._on_command(msg, src)
            return
        if kind not in self._store:
            self._ack(src, mavlink2.MAV_MISSION_UNSUPPORTED, kind)
            return
        if self.link.mavlink1 and kind != mavlink2.MAV_MISSION_TYPE_MISSION:
            # pymavlink would pack mission_type into a MAVLink 1 frame; ArduPilot's C library does not
            self._ack(src, mavlink2.MAV_MISSION_UNSUPPORTED, mavlink2.MAV_MISSION_TYPE_MISSION)
            return
        if mtype == "MISSION_COUNT":
            self._on_count(msg, src, kind)
        elif mtype == "MISSION_ITEM_INT":
            self._on_item(msg, src, kind)
        elif mtype == "MISSION_ITEM":
            # Float items lose precision; both autopilots want MISSION_ITEM_INT from a modern GCS.
            self._ack(src, mavlink2.MAV_MISSION_UNSUPPORTED, kind)
        elif mtype in ("MISSION_REQUEST_LIST", "MISSION_REQUEST_INT", "MISSION_REQUEST") and self._ap_busy(kind):
            # ArduPilot refuses to send a list while it is receiving that list, until done or timed out
            # (MissionItemProtocol.cpp handle_mission_request_list / handle_mission_request_int)
            self._ack(src, mavlink2.MAV_MISSION_DENIED, kind)
        elif mtype == "MISSION_REQUEST_LIST":
            self.stats["downloads"] += 1
            stored = self._download_view(kind)
            self.link.send(with_opaque_id(self.link.mav.mission_count_encode(src[0], src[1], len(stored), kind),
                                          opaque_id(self._store[kind])))
        elif mtype in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            stored = self._download_view(kind)
            if msg.seq >= len(stored):
                self._ack(src, mavlink2.MAV_MISSION_INVALID_SEQUENCE, kind)
                return
            it = stored[msg.seq]
            self.link.send(self.link.mav.mission_item_int_encode(
                src[0], src[1], msg.seq, it.frame, it.command, it.current, it.autocontinue, it.param1, it.param2,
                it.param3, it.param4, it.x, it.y, it.z, kind))
        elif mtype == "MISSION_CLEAR_ALL":
            kinds = MISSION_TYPES if kind == mavlink2.MAV_MISSION_TYPE_ALL else (kind,)
            for k in kinds:
                self._store[k] = []
            self._ack(src, mavlink2.MAV_MISSION_ACCEPTED, kind)
        # MISSION_ACK from the GCS ends a download; nothing to do.

    def _on_command(self, msg, src: tuple[int, int]) -> None:
        asks_version = (msg.command == mavlink2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES
                        or (msg.command == mavlink2.MAV_CMD_REQUEST_MESSAGE
                            and int(msg.param1) == mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION))
        result = mavlink2.MAV_RESULT_ACCEPTED if asks_version else mavlink2.MAV_RESULT_UNSUPPORTED
        self.link.send(self.link.mav.command_ack_encode(msg.command, result, 0, 0, src[0], src[1]))
        if asks_version:
            self.link.send(self._autopilot_version())

    def _autopilot_version(self):
        major, minor, patch = SOFTWARE_VERSION[self.flavour.name]
        version = (major << 24) | (minor << 16) | (patch << 8) | mavlink2.FIRMWARE_VERSION_TYPE_OFFICIAL
        return self.link.mav.autopilot_version_encode(CAPABILITIES, version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8,
                                                      0, 0, 0)

    def _ap_busy(self, kind: int) -> bool:
        return self.flavour.name == "ardupilot" and self._upload is not None and self._upload.mission_type == kind

    def _download_view(self, kind: int) -> list[MissionItem]:
        stored = self._store[kind]
        if self.stores_like_firmware:
            stored = [firmware_readback(it, self.flavour.name) for it in stored]
        if self.flavour.name == "ardupilot" and kind == mavlink2.MAV_MISSION_TYPE_MISSION and self.home is not None \
                and stored:
            return [self.home.with_(current=0)] + stored[1:]
        return stored

    def _cuts_at_count(self, kind: int) -> bool:
        """ArduPilot's mission and rally list are cut at MISSION_COUNT and written item by item
        (MissionItemProtocol::handle_mission_count -> truncate); its fence and PX4's lists are replaced
        only when the upload completes."""
        return self.flavour.name == "ardupilot" and kind != mavlink2.MAV_MISSION_TYPE_FENCE

    def _on_count(self, msg, src: tuple[int, int], kind: int) -> None:
        now = time.monotonic()
        up = self._upload
        if up is not None and up.partner != src:
            self._ack(src, mavlink2.MAV_MISSION_DENIED, kind)
            return
        limit = self.flavour.item_limit
        if limit is not None and msg.count > limit:
            self._ack(src, mavlink2.MAV_MISSION_NO_SPACE, kind)
            return
        if msg.count == 0:
            self._store[kind] = []
            self._upload = None
            self._ack(src, mavlink2.MAV_MISSION_ACCEPTED, kind, opaque_id([]))
            return
        if up is not None and self.flavour.name == "px4" and up.expected > 0:
            return  # PX4: "Mission upload busy" - a repeated count mid-transfer is ignored
        if self._cuts_at_count(kind):
            del self._store[kind][msg.count:]
        self._upload = _Upload(src, kind, msg.count, last_rx=now)
        self._request(self._upload)

    def _on_item(self, msg, src: tuple[int, int], kind: int) -> None:
        up = self._upload
        if up is None or up.mission_type != kind:
            done = self._done.get(kind)
            if self.flavour.name == "px4" and done == (src, msg.seq + 1):
                self._ack(src, mavlink2.MAV_MISSION_ACCEPTED, kind, opaque_id(self._store[kind]))
            else:
                # ArduPilot: GCS_Common.cpp handle_mission_item, `if (!prot->receiving)` -> ERROR
                self._ack(src, mavlink2.MAV_MISSION_ERROR, kind)
            return
        if src != up.partner:
            self._ack(src, mavlink2.MAV_MISSION_DENIED, kind)
            return
        up.last_rx = time.monotonic()
        if msg.seq != up.expected:
            if self.flavour.nack_out_of_order:
                self._ack(src, mavlink2.MAV_MISSION_INVALID_SEQUENCE, kind)
            else:
                self._request(up)
            return
        if self.nack_rate and self._rng.random() < self.nack_rate:
            self._ack(src, mavlink2.MAV_MISSION_ERROR, kind)   # dropped; the re-request timer asks again
            return
        self.stats["items"] += 1
        item = item_from_msg(msg)
        up.items.append(item)
        if self._cuts_at_count(kind):   # replace_item / append_item at once
            store = self._store[kind]
            if msg.seq < len(store):
                store[msg.seq] = item
            else:
                store.append(item)
        up.expected += 1
        if up.expected < up.count:
            self._request(up)
            return
        if self.ack_defer_s and self.flavour.name == "ardupilot":
            up.ack_at = time.monotonic() + self.ack_defer_s   # still "receiving" until the ack goes out
            return
        self._complete(up)

    def _complete(self, up: _Upload) -> None:
        kind = up.mission_type
        self._store[kind] = up.items
        self._upload = None
        self._done[kind] = (up.partner, up.count)
        self.stats["uploads"] += 1
        self._ack(up.partner, mavlink2.MAV_MISSION_ACCEPTED, kind, opaque_id(up.items))
