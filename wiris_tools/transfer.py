"""Mission, fence and rally transfer over the MAVLink mission protocol (ground-station side).

    client = MissionClient(link, target_system=1, target_component=1)
    result = client.upload(items, mission_type=MISSION_TYPE_MISSION, progress=lambda done, total: ...)
    items, result = client.download(mission_type=MISSION_TYPE_MISSION)
    result = client.upload_verified(items)          # upload + read-back, as the firmware keeps it

Files (what `wiris mission upload/download` call): load_for_upload(path, type) reads a .plan,
a WPL 110 file or a capture plan (compiled with missions.compile); upload_file(link, path, ...)
puts the file's home in as item 0 when the vehicle's HEARTBEAT says ArduPilot (as QGC and MAVSDK
do); download_file(link, out) splits ArduPilot's item 0 off as the file's home and writes .plan
(mission, fence, rally) or .waypoints atomically - after the writers' check (missions.formats.itemcheck) that
every position is a real one and every value one that upload reads back, else PlanError naming the item
and field, and nothing written.

Only MISSION_ITEM_INT is sent. Requests may come as MISSION_REQUEST_INT or the legacy
MISSION_REQUEST (ArduPilot's own request path still sends the legacy one); both get the INT item.

Timing (all in `Timeouts`; the defaults are the spec's or tighter):
  * Waiting passively for the vehicle (first request after MISSION_COUNT, MISSION_COUNT after
    MISSION_REQUEST_LIST, the final ack): at most `ack_s` = 1.5 s per try, starting at 0.5 s and
    doubling, `retries` = 5 resends.
  * Upload is driven by the vehicle's requests, so it resumes wherever the vehicle asks - never from
    item 0 again. After sending item k we expect the request for k+1 within one round trip. When it
    is overdue (RTO from a smoothed RTT measured on this link, RFC 6298 style, never above
    `ack_s`, doubling on each resend) we resend item k at once instead of waiting for the
    vehicle's own re-request timer (1 s on ArduPilot): that is the fast retransmit. From the second
    resend on, item k+1 goes out unasked after it: a vehicle whose request for k+1 was lost ignores a
    repeated k without a word (MAVSDK's MissionRawServer, PX4) until its own timer. Duplicated
    requests within half an RTT of our last answer are not answered twice.
  * Download requests one item at a time (PX4 insists on order) and re-requests after the RTO,
    capped at `item_s` = 250 ms, `retries` times per item. Only the item asked for is accepted, so
    a late duplicate can never fill another slot.
  * Download deadline: the per-item limits alone let a vehicle that claims 65535 items and answers
    only every 6th request hold the download for about 11 hours. So a download also ends, with
    LinkError, at a deadline: `deadline_s` when given (`wiris mission download --deadline`), else
    download_deadline_s(count, round trip measured on this link).
  * Error NACKs: ArduPilot answers a duplicate or out-of-order item with MISSION_ACK
    INVALID_SEQUENCE and keeps going (Cockpit PR #2067: it "sends fail ACKs even if it intends to
    keep trying"). So a MISSION_ACK with an error is noted, not fatal: the upload fails with that
    error only if no further request arrives within `nack_grace_s`.
  * A final MISSION_ACK ACCEPTED counts only after the vehicle has requested the last item, so a
    stale or duplicated ack from an earlier transfer cannot end this one early. An error ack after
    the last item went out (ArduPilot's ERROR once it has finished, its INVALID_SEQUENCE while it
    defers the ACCEPTED to compute its mission id, or a late answer to a duplicate) is only a hint:
    the ACCEPTED still gets the spec's ack timeout before the upload is called unconfirmed.
  * A failed ArduPilot upload says the vehicle's mission (or rally list) is now partly overwritten:
    ArduPilot cuts it at MISSION_COUNT and replaces it item by item.
  * Download: DENIED (ArduPilot busy receiving an upload) is asked again until the retries run
    out; UNSUPPORTED to the list request raises ListUnsupported (the firmware has no such list).

Verification (`upload_verified`): download after upload and compare each item as the vehicle's
firmware keeps it (readback.compare_items with readback_rule: ArduPilot and PX4 drop params a command does
not use, round altitudes, report other frames; the command, coordinates and every kept value must
match); also compare ArduPilot's opaque_id from the upload's MISSION_ACK with the download's
MISSION_COUNT when both carry one. Any difference raises LinkError naming the first differing item
and field. ArduPilot replaces mission item 0 with its home position, so for an ArduPilot vehicle
(from its HEARTBEAT) item 0 of a MISSION (not fence/rally) is compared by command only.
"""

from __future__ import annotations

import contextlib
import glob
import math
import re
import struct
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf.float32 import FLOAT32_MAX
from missions.compile import compile_plan
from missions.emit.items import FRAME_GLOBAL, MISSION_TYPE_MISSION, MissionItem, deg_to_e7
from missions.errors import PlanError
from missions.formats.planfile import atomic_write, check_writable, load_plan_file, write_plan
from missions.formats.wpl import LIST_NAMES, load_wpl_file, write_wpl
from missions.measure.report import report
from wiris_tools.errors import LinkError
from wiris_tools.link import Link, command_name
from wiris_tools.readback import compare_items, readback_firmware

Progress = Callable[[int, int], None]

TYPE_NAMES = {mavlink2.MAV_MISSION_TYPE_MISSION: "mission", mavlink2.MAV_MISSION_TYPE_FENCE: "fence",
              mavlink2.MAV_MISSION_TYPE_RALLY: "rally"}


def mission_result_name(result: int) -> str:
    entry = mavlink2.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT {result}"


# What to do when the vehicle refuses a download with an answer _NACK_HINTS has no word for.
_DOWNLOAD_NACK_HINT = "retry the download; close other ground stations that may be talking to the vehicle"

_NACK_HINTS = {
    mavlink2.MAV_MISSION_NO_SPACE: "the vehicle holds fewer items (PX4: 500 by default, ArduPilot: about 700 on "
                                   "common boards); split the plan or use fewer items",
    mavlink2.MAV_MISSION_UNSUPPORTED: "the vehicle's firmware does not accept this command in a mission; "
                                      "compile the plan for this firmware",
    mavlink2.MAV_MISSION_UNSUPPORTED_FRAME: "the vehicle does not accept this frame; compile for this firmware",
    mavlink2.MAV_MISSION_DENIED: "the vehicle refused the transfer (another ground station busy? wrong sysid?)",
}


# Answers that end an upload when no further request follows (the others - ERROR,
# INVALID_SEQUENCE - are ArduPilot's transient complaints and only noted).
_FATAL_NACKS = frozenset({
    mavlink2.MAV_MISSION_NO_SPACE, mavlink2.MAV_MISSION_UNSUPPORTED, mavlink2.MAV_MISSION_UNSUPPORTED_FRAME,
    mavlink2.MAV_MISSION_DENIED, mavlink2.MAV_MISSION_INVALID, mavlink2.MAV_MISSION_OPERATION_CANCELLED,
    *range(mavlink2.MAV_MISSION_INVALID_PARAM1, mavlink2.MAV_MISSION_INVALID_PARAM7 + 1),
})


def _describe(item: MissionItem) -> str:
    return command_name(item.command)


@dataclass(frozen=True)
class Timeouts:
    ack_s: float = 1.5          # spec: waiting for the other side to start/finish
    item_s: float = 0.25        # spec: actively re-requesting a missing item
    retries: int = 5            # spec: resends before giving up
    nack_grace_s: float = 2.5   # ArduPilot re-requests 1 s (+ link slowdown) after a transient NACK
    min_rto_s: float = 0.02
    first_s: float = 0.5        # first resend of MISSION_COUNT / MISSION_REQUEST_LIST
    deadline_floor_s: float = 30.0  # a download's derived deadline: this plus time per item (download_deadline_s)


# The derived download deadline: a floor (Timeouts.deadline_floor_s) for small lists and slow starts, then a
# generous allowance per item of round trips at the link's measured pace. A link losing a third of the packets
# each way needs about five round trips per item on average (each loss costs a re-request timer of about two
# round trips); eight leave room for bursts. The margin is the vehicle's own time per item and a
# MISSION_ITEM_INT's longer airtime than the MISSION_COUNT the round trip was measured on.
DEADLINE_ROUND_TRIPS_PER_ITEM = 8
DEADLINE_ITEM_MARGIN_S = 0.01


def worst_item_s(t: Timeouts) -> float:
    """The longest one item can take within the per-item limits: every re-request timer at its cap."""
    return sum(min(t.item_s * 2 ** k, t.ack_s) for k in range(t.retries + 1))


def download_deadline_s(count: int, srtt: float | None, t: Timeouts) -> float:
    """Seconds a download of `count` items may take in all, from the smoothed round trip `srtt` measured on
    the link (None: not yet measured, the spec's per-item time is assumed). The round trip is capped at that
    per-item time: a vehicle answering the count slowly does not earn hours more; and no item is allowed more
    than the per-item limits allow anyway."""
    rtt = t.item_s if srtt is None else min(srtt, t.item_s)
    per_item = min(DEADLINE_ROUND_TRIPS_PER_ITEM * (rtt + DEADLINE_ITEM_MARGIN_S), worst_item_s(t))
    return t.deadline_floor_s + count * per_item


@dataclass(frozen=True)
class TransferResult:
    mission_type: int
    count: int
    seconds: float
    opaque_id: int = 0          # 0: the vehicle did not report one
    resent: int = 0             # messages we sent again (lost items, counts, requests)
    nacks_tolerated: int = 0    # error MISSION_ACKs followed by further requests
    notes: tuple[str, ...] = ()
    mavlink1: bool = False      # download: the vehicle answered in MAVLink 1 framing
    verified: bool = False      # upload_verified: the read-back matched what was sent


class UploadUnconfirmed(LinkError):
    """Every item was requested and sent, but no ACCEPTED ack arrived: only a read-back can tell."""


class VehicleRefused(LinkError):
    """The vehicle ended an upload with a MISSION_ACK error (`result`, a MAV_MISSION_RESULT)."""

    def __init__(self, message: str, *, result: int, where: str | None = None, hint: str | None = None) -> None:
        super().__init__(message, where=where, hint=hint)
        self.result = result


class ListUnsupported(LinkError):
    """The vehicle answered MAV_MISSION_UNSUPPORTED to a list request: it has no such list (ArduPilot built
    without fences or rally points, GCS_Common.cpp handle_mission_request_list). Not a failed download."""


class RttEstimator:
    """Smoothed round-trip time (RFC 6298): srtt, rttvar; samples only from first transmissions."""

    def __init__(self) -> None:
        self.srtt: float | None = None
        self.rttvar = 0.0

    def sample(self, rtt: float) -> None:
        if rtt <= 0:
            return
        if self.srtt is None:
            self.srtt, self.rttvar = rtt, rtt / 2
        else:
            self.rttvar = 0.75 * self.rttvar + 0.25 * abs(self.srtt - rtt)
            self.srtt = 0.875 * self.srtt + 0.125 * rtt

    def rto(self, floor: float, cap: float, initial: float) -> float:
        if self.srtt is None:
            return min(initial, cap)
        return min(max(self.srtt + 4 * self.rttvar, 1.5 * self.srtt, floor), cap)


class _Extended:
    """A message packed with MAVLink 2 extension bytes that the installed dialect does not define.

    pymavlink 2.4.50's common.xml predates `opaque_id` (MISSION_COUNT/MISSION_ACK extensions), but
    an extension is just bytes after the known payload, covered by the same CRC_EXTRA.
    """

    def __init__(self, msg, extra: bytes) -> None:
        self._msg = msg
        self._extra = extra

    def get_type(self) -> str:
        return self._msg.get_type()

    def pack(self, mav, force_mavlink1: bool = False) -> bytes:
        m = self._msg
        base = m.unpacker.pack(*(getattr(m, n) for n in m.ordered_fieldnames))
        return m._pack(mav, m.crc_extra, base if force_mavlink1 else base + self._extra, force_mavlink1)


def with_opaque_id(msg, opaque: int):
    """MISSION_COUNT or MISSION_ACK carrying `opaque_id` (sent as MAVLink 2 extension bytes)."""
    return _Extended(msg, struct.pack("<I", opaque)) if opaque else msg


# Byte offset of opaque_id in the MAVLink 2 payload: after the base fields and the mission_type extension.
_OPAQUE_OFFSET = {"MISSION_ACK": 4, "MISSION_COUNT": 5}


def opaque_id_of(msg) -> int:
    """The opaque_id of a received MISSION_ACK/MISSION_COUNT; 0 when absent (or MAVLink 1)."""
    off = _OPAQUE_OFFSET.get(msg.get_type())
    buf = msg.get_msgbuf()
    if off is None or not buf or buf[0] != 0xFD:
        return 0
    payload = bytes(buf[10:10 + buf[1]]) + bytes(8)  # MAVLink 2 trims trailing zero bytes
    return struct.unpack_from("<I", payload, off)[0]


def _check_encodable(items: Sequence[MissionItem], where: str) -> None:
    """LinkError naming the first item whose fields MISSION_ITEM_INT cannot carry - before MISSION_COUNT,
    which on ArduPilot already cuts the vehicle's mission to the new count."""
    for i, it in enumerate(items):
        for name in ("param1", "param2", "param3", "param4", "z"):
            v = getattr(it, name)
            if math.isfinite(v) and abs(v) > FLOAT32_MAX:
                raise LinkError(f"item {i} ({_describe(it)}) has {name} = {v:g}, beyond the float32 range "
                                "MISSION_ITEM_INT carries", where=f"{where}, item {i}",
                                hint="fix the value in the file (at most ±3.4e38); nothing was sent")
        for name, lo, hi in (("x", -2**31, 2**31 - 1), ("y", -2**31, 2**31 - 1), ("command", 0, 65535),
                             ("frame", 0, 255), ("autocontinue", 0, 255), ("current", 0, 255)):
            v = getattr(it, name)
            if not lo <= v <= hi:
                raise LinkError(f"item {i} ({_describe(it)}) has {name} = {v}, outside {lo}..{hi}",
                                where=f"{where}, item {i}", hint="fix the value in the file; nothing was sent")


def _past_deadline(deadline_s: float, given: bool, received: str, where: str, t: Timeouts) -> LinkError:
    source = "given" if given else (f"{t.deadline_floor_s:g} s plus {DEADLINE_ROUND_TRIPS_PER_ITEM} measured round "
                                    "trips per item")
    return LinkError(f"the download did not finish within its deadline of {deadline_s:.3g} s ({source}): {received}",
                     where=where, hint="a slow or lossy link may need longer: raise it with --deadline SECONDS; a "
                                       "vehicle that answers this rarely on a good link is faulty")


def item_from_msg(msg) -> MissionItem:
    return MissionItem(command=msg.command, frame=msg.frame, param1=msg.param1, param2=msg.param2,
                       param3=msg.param3, param4=msg.param4, x=msg.x, y=msg.y, z=msg.z,
                       autocontinue=msg.autocontinue, current=msg.current,
                       mission_type=getattr(msg, "mission_type", 0))


class MissionClient:
    """Upload/download/verify against one vehicle over a Link; keeps an RTT estimate across calls."""

    def __init__(self, link: Link, target_system: int = 1, target_component: int = 1, *,
                 timeouts: Timeouts = Timeouts()) -> None:
        self.link = link
        self.target_system = target_system
        self.target_component = target_component
        self.timeouts = timeouts
        self.rtt = RttEstimator()

    # -- helpers -------------------------------------------------------------------------------
    def _where(self, mission_type: int) -> str:
        return f"{TYPE_NAMES.get(mission_type, mission_type)} on system {self.target_system}"

    def _from_vehicle(self, msg) -> bool:
        if msg.get_srcSystem() != self.target_system:
            return False
        return not self.target_component or msg.get_srcComponent() == self.target_component

    def _mission_filter(self, mission_type: int):
        def ok(msg) -> bool:
            return self._from_vehicle(msg) and getattr(msg, "mission_type", 0) == mission_type
        return ok

    def _inbox(self, types: list[str], mission_type: int):
        return self.link.inbox(types, to_me=True, predicate=self._mission_filter(mission_type))

    def _encode_item(self, seq: int, item: MissionItem, mission_type: int):
        return self.link.mav.mission_item_int_encode(
            self.target_system, self.target_component, seq, item.frame, item.command, item.current,
            item.autocontinue, item.param1, item.param2, item.param3, item.param4, int(item.x), int(item.y),
            float(item.z), mission_type)

    def _heartbeat(self):
        return self.link.heartbeats().get((self.target_system, self.target_component)) or next(
            (h for (s, _c), h in self.link.heartbeats().items() if s == self.target_system
             and h.autopilot != mavlink2.MAV_AUTOPILOT_INVALID), None)

    def is_ardupilot(self) -> bool:
        hb = self._heartbeat()
        return hb is not None and hb.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA

    # -- upload --------------------------------------------------------------------------------
    def upload(self, items: Sequence[MissionItem], *, mission_type: int = MISSION_TYPE_MISSION,
               progress: Progress | None = None) -> TransferResult:
        """Send `items` to the vehicle; returns when it acknowledged them (LinkError otherwise)."""
        where = self._where(mission_type)
        if not items:
            raise LinkError("nothing to upload: the list is empty", where=where,
                            hint="an empty upload would clear the vehicle's list; clear it from the ground station")
        if len(items) > 65535:
            raise LinkError(f"{len(items)} items do not fit the protocol's 16-bit count", where=where,
                            hint="at most 65535 items, ArduPilot's home item 0 included: split the mission")
        _check_encodable(items, where)
        return _Upload(self, list(items), mission_type, where, progress).run()

    # -- download ------------------------------------------------------------------------------
    def download(self, *, mission_type: int = MISSION_TYPE_MISSION, progress: Progress | None = None,
                 deadline_s: float | None = None) -> tuple[list[MissionItem], TransferResult]:
        """Read the vehicle's list of `mission_type`; returns (items, result). It ends with LinkError
        `deadline_s` seconds after it started, or when given None at download_deadline_s of the count."""
        with self._inbox(["MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ACK"], mission_type) as box:
            return _Download(self, box, mission_type, progress, deadline_s).run()

    # -- upload + read-back --------------------------------------------------------------------
    def upload_verified(self, items: Sequence[MissionItem], *, mission_type: int = MISSION_TYPE_MISSION,
                        progress: Progress | None = None) -> TransferResult:
        """Upload, download again and compare; LinkError naming the first difference otherwise.

        The comparison follows the firmware of the vehicle's HEARTBEAT (compare_items, readback_rule):
        what ArduPilot or PX4 normally does to an item it stores is not a difference. If the upload
        itself failed only at the final acknowledgement (every item was sent), the read-back decides:
        a vehicle that holds our items counts as success.
        """
        note: tuple[str, ...] = ()
        try:
            up = self.upload(items, mission_type=mission_type, progress=progress)
        except UploadUnconfirmed:
            up = TransferResult(mission_type, len(items), 0.0)
            note = ("the vehicle's final MISSION_ACK never arrived; the read-back below proves the upload",)
        got, down = self.download(mission_type=mission_type)
        if self._heartbeat() is None:
            # The vehicle's firmware decides how its read-back is judged (and whether item 0 is ArduPilot's
            # home); without its HEARTBEAT every field is compared - a false alarm at worst.
            with contextlib.suppress(LinkError):
                self.link.wait_heartbeat(timeout=self.timeouts.ack_s, system=self.target_system)
        compare_items(items, got, where=self._where(mission_type),
                      home_replaced=self.is_ardupilot() and mission_type == MISSION_TYPE_MISSION,
                      firmware=readback_firmware(self._heartbeat()))
        if up.opaque_id and down.opaque_id and up.opaque_id != down.opaque_id:
            raise LinkError(f"the vehicle's mission id changed between upload ({up.opaque_id:#010x}) and "
                            f"read-back ({down.opaque_id:#010x})", where=self._where(mission_type),
                            hint="someone else changed the mission meanwhile; upload again")
        return TransferResult(mission_type, len(items), up.seconds + down.seconds, up.opaque_id or down.opaque_id,
                              up.resent + down.resent, up.nacks_tolerated, up.notes + note, verified=True)


class _Upload:
    """One upload. Requests are answered on the link's receive thread (no thread hand-off between a
    request and its item: on a slow radio every round trip counts); timers, acks and progress
    are handled by the calling thread, polling at least every `_POLL_S`."""

    _POLL_S = 0.02

    def __init__(self, client: "MissionClient", items: list[MissionItem], mission_type: int, where: str,
                 progress: Progress | None) -> None:
        self.c = client
        self.t = client.timeouts
        self.items = items
        self.count = len(items)
        self.mission_type = mission_type
        self.where = where
        self.progress = progress
        self.lock = threading.Lock()
        self.start = time.monotonic()
        self.resent = 0
        self.nacks = 0
        self.fatal_nack: tuple[int, int] | None = None   # (result, item sent last) awaiting the grace period
        self.fatal_at = 0.0
        self.last_nack: int | None = None
        self.sent_at: dict[int, float] = {}              # last transmission time per seq
        self.first_sent_at: dict[int, float] = {}        # only first transmissions give RTT samples (Karn)
        self.retransmitted: set[int] = set()
        self.pushed: dict[int, int] = {}                 # unsolicited sends per seq
        self.requested_max = -1
        self.last_item: int | None = None                # the item we sent last
        self.final_hint: int | None = None               # an error ack after the last item went out
        self.tries = 0
        self.count_wait = self.t.first_s
        self.deadline = 0.0
        # A vehicle that keeps asking for the same item forever must not keep us here forever.
        self.stall_s = (self.t.retries + 1) * self.t.ack_s + self.t.nack_grace_s
        self.last_progress = self.start

    # -- sending (callers hold the lock) -------------------------------------------------------
    def send_count(self) -> None:
        c = self.c
        c.link.send(c.link.mav.mission_count_encode(c.target_system, c.target_component, self.count,
                                                    self.mission_type))

    def send_item(self, seq: int) -> None:
        now = time.monotonic()
        if seq in self.sent_at:
            self.retransmitted.add(seq)
        else:
            self.first_sent_at[seq] = now
        self.sent_at[seq] = now
        self.c.link.send(self.c._encode_item(seq, self.items[seq], self.mission_type))

    def rto(self) -> float:
        return self.c.rtt.rto(self.t.min_rto_s, self.t.ack_s, self.t.item_s)

    def unconfirmed(self, why: str) -> UploadUnconfirmed:
        return UploadUnconfirmed(f"all {self.count} items were sent but {why}", where=self.where,
                                 hint="the vehicle probably holds the mission: download it, or upload with "
                                      "--verify, which reads it back and compares")

    # -- the receive thread: requests ----------------------------------------------------------
    def on_request(self, msg) -> None:
        seq = msg.seq
        if seq >= self.count:
            return  # not ours to answer (another transfer, or a broken vehicle)
        with self.lock:
            now = time.monotonic()
            self.fatal_nack = None
            if seq > self.requested_max:
                prev = seq - 1
                if prev in self.first_sent_at and prev not in self.retransmitted:
                    self.c.rtt.sample(now - self.first_sent_at[prev])
                self.requested_max = seq
                self.last_progress = now
            self.tries = 0
            self.final_hint = None
            srtt = self.c.rtt.srtt or 0.0
            if seq == self.last_item and now - self.sent_at.get(seq, 0.0) < 0.5 * srtt:
                return  # a duplicated request: the answer is already on its way
            if seq in self.sent_at:
                self.resent += 1
            self.last_item = seq
            self.send_item(seq)
            self.deadline = now + self.rto()

    # -- the calling thread: acks, timers, progress --------------------------------------------
    def on_ack(self, msg, now: float) -> TransferResult | None:
        count = self.count
        if msg.type == mavlink2.MAV_MISSION_ACCEPTED:
            if (count - 1) in self.sent_at:
                return TransferResult(self.mission_type, count, time.monotonic() - self.start, opaque_id_of(msg),
                                      self.resent, self.nacks)
            return None  # stale: an ack from an earlier transfer
        self.nacks += 1
        self.last_nack = msg.type
        if msg.type in _FATAL_NACKS:
            # Still not believed at once (a stale ack of an earlier transfer looks the same):
            # fatal only if the vehicle asks for nothing more.
            if self.fatal_nack is None:
                self.fatal_nack = (msg.type, self.last_item if self.last_item is not None else -1)
                self.fatal_at = now
            return None
        last = self.last_item
        if last == count - 1 and last == self.requested_max and msg.type in (mavlink2.MAV_MISSION_ERROR,
                                                                            mavlink2.MAV_MISSION_INVALID_SEQUENCE):
            # The vehicle asked for the last item and has it, or will ask again: an error now is a hint,
            # never the end. Released ArduPilot answers any item with ERROR once it is no longer receiving
            # (GCS_Common.cpp handle_mission_item: !prot->receiving) - its ACCEPTED was lost or is still on
            # the way; a build that defers its ACCEPTED until the mission id is computed (>= 500 ms without a
            # change, MissionItemProtocol.cpp transfer_is_complete/update_checksum) answers a repeated item
            # with INVALID_SEQUENCE meanwhile; and an INVALID_SEQUENCE can be the late answer to a duplicated
            # earlier item while the ACCEPTED is still coming. So stop resending and give the ACCEPTED the
            # spec's ack timeout; a vehicle that lacks the item asks for it again (1 s on ArduPilot).
            if self.final_hint is None:
                self.final_hint = msg.type
                self.tries = max(self.tries, self.t.retries)
                self.deadline = max(self.deadline, now + self.t.ack_s)
            return None
        if msg.type == mavlink2.MAV_MISSION_INVALID_SEQUENCE and last is not None and last == self.requested_max:
            # ArduPilot answers an item it no longer expects this way: it already has `last` and
            # its request for the next one was lost.
            nxt = last + 1
            if nxt < count and self.pushed.get(nxt, 0) < 3 and (nxt not in self.sent_at or nxt in self.pushed):
                # Push the next item rather than wait for the vehicle's re-request timer (1 s on
                # ArduPilot); if we guessed wrong it answers with one more INVALID_SEQUENCE.
                self.pushed[nxt] = self.pushed.get(nxt, 0) + 1
                self.send_item(nxt)
                self.retransmitted.add(nxt)  # no RTT sample from an unsolicited item
        return None

    def on_timeout(self, now: float) -> None:
        t = self.t
        if self.tries >= t.retries:
            if self.last_item is None:
                raise LinkError(f"no request after MISSION_COUNT ({self.count} items), {t.retries + 1} tries",
                                where=self.where, hint="check the connection, the target system/component, and "
                                                       "that the vehicle supports this mission type")
            if (self.count - 1) in self.sent_at:
                if self.final_hint is not None:
                    raise self.unconfirmed(f"no MISSION_ACK ACCEPTED came within {t.ack_s:g} s of the vehicle's "
                                           f"{mission_result_name(self.final_hint)} to the repeated last item")
                raise self.unconfirmed("the vehicle never acknowledged the upload")
            raise LinkError(f"the vehicle stopped requesting after item {self.last_item} of {self.count}"
                            + self._last_answer(), where=self.where,
                            hint="the link is too lossy or was lost; retry the upload")
        self.tries += 1
        self.resent += 1
        if self.last_item is None:
            self.send_count()
            self.count_wait = min(self.count_wait * 2, t.ack_s)
            self.deadline = now + self.count_wait
        else:
            # Fast retransmit: the vehicle's next request is overdue.
            self.send_item(self.last_item)
            self.push_next_after_silence()
            wait = min(self.rto() * (2 ** self.tries), t.ack_s)
            if self.tries >= t.retries and self.last_item == self.count - 1:
                # After the last try of the last item the vehicle gets the spec's whole ack timeout: an
                # ArduPilot that defers its ACCEPTED (see on_ack) must not lose to our fast retransmits.
                wait = t.ack_s
            self.deadline = now + wait

    def push_next_after_silence(self) -> None:
        """After a resend of the last item got no answer at all, send the next item too, unasked. A vehicle
        that already has the last item (its request for the next one was lost) ignores the repeat without a
        word - MAVSDK's MissionRawServer and PX4 do; ArduPilot at least NACKs it, see on_ack - and asks again
        only at its own timer (about 1 s on MAVSDK's server): the next item is what it waits for. A vehicle
        that lacked the last item gets it first, and the next one is then either what it asks for anyway or a
        repeat it drops."""
        nxt = self.last_item + 1
        if self.tries >= 2 and nxt < self.count and self.last_item == self.requested_max:
            self.send_item(nxt)
            self.retransmitted.add(nxt)  # no RTT sample from an unsolicited item

    def explain_partial(self, err: LinkError) -> None:
        """Say what a failed upload left on an ArduPilot vehicle. ArduPilot cuts its mission and its rally
        list to the new count when MISSION_COUNT arrives, then replaces them item by item
        (MissionItemProtocol.cpp handle_mission_count -> truncate, handle_mission_item -> replace_item /
        append_item): after a failure they hold a mix of old and new items. Its fence is written only when
        complete (MissionItemProtocol_Fence.cpp complete), and PX4 switches to a new list only when complete
        (mavlink_mission.cpp, update_active_mission): nothing to add for those."""
        if self.mission_type == mavlink2.MAV_MISSION_TYPE_FENCE or not self.c.is_ardupilot():
            return
        if self.fatal_nack is not None and self.fatal_nack[1] < 0:
            return  # MISSION_COUNT itself refused (DENIED, NO_SPACE): checked before the list is cut
        kind = TYPE_NAMES.get(self.mission_type, str(self.mission_type))
        if isinstance(err, UploadUnconfirmed):
            err.hint = (f"{err.hint}; do not fly it before that: ArduPilot replaces its {kind} item by item, so an "
                        "upload that did not complete leaves old and new items mixed")
        elif self.last_item is None:
            err.message += f"; if MISSION_COUNT reached the vehicle, ArduPilot has already cut its {kind} to " \
                           f"{self.count} items"
            err.hint = f"do not fly the vehicle's {kind} before an upload succeeds; {err.hint}"
        else:
            err.message += (f"; the vehicle's {kind} is now partly overwritten (ArduPilot cut it to {self.count} "
                            "items at MISSION_COUNT and replaces them one by one: old and new items are mixed)")
            err.hint = f"do not fly the vehicle's {kind} before an upload succeeds; {err.hint}"

    def _last_answer(self) -> str:
        return f" (last answer: {mission_result_name(self.last_nack)})" if self.last_nack is not None else ""

    def check(self, now: float, waited_out: bool) -> None:
        t = self.t
        if self.fatal_nack is not None and (now - self.fatal_at >= t.nack_grace_s
                                            or (waited_out and self.tries >= t.retries)):
            result, seq = self.fatal_nack
            raise VehicleRefused(f"the vehicle answered {mission_result_name(result)}"
                                 + (f" to item {seq} ({_describe(self.items[seq])})" if seq >= 0 else
                                    f" to MISSION_COUNT ({self.count} items)"), result=result, where=self.where,
                                 hint=_NACK_HINTS.get(result, "check the item the error names"))
        if now - self.last_progress > self.stall_s:
            if (self.count - 1) in self.sent_at:
                raise self.unconfirmed(f"no MISSION_ACK came within {self.stall_s:g} s")
            raise LinkError(f"no progress for {self.stall_s:g} s: stuck at item {max(self.requested_max, 0)} of "
                            f"{self.count}" + self._last_answer(), where=self.where,
                            hint="the link is too lossy or was lost; retry the upload")

    def run(self) -> TransferResult:
        c = self.c
        ok = c._mission_filter(self.mission_type)
        reported = -1
        with c.link.inbox("MISSION_ACK", to_me=True, predicate=ok) as acks:
            sub = c.link.subscribe(self.on_request, ["MISSION_REQUEST_INT", "MISSION_REQUEST"], to_me=True,
                                   predicate=ok)
            try:
                with self.lock:
                    self.send_count()
                    self.deadline = time.monotonic() + self.count_wait
                while True:
                    with self.lock:
                        wait = self.deadline - time.monotonic()
                        if self.fatal_nack is not None:
                            wait = min(wait, self.fatal_at + self.t.nack_grace_s - time.monotonic())
                    msg = acks.get(min(max(wait, 0.0), self._POLL_S))
                    with self.lock:
                        now = time.monotonic()
                        if msg is not None:
                            done = self.on_ack(msg, now)
                            if done is not None:
                                if self.progress:
                                    self.progress(self.count, self.count)
                                return done
                        waited_out = msg is None and now >= self.deadline
                        self.check(now, waited_out)
                        if waited_out:
                            self.on_timeout(now)
                        progressed = self.requested_max
                    if self.progress and progressed > reported:
                        reported = progressed
                        self.progress(progressed, self.count)
            except LinkError as err:
                with self.lock:
                    self.explain_partial(err)
                raise
            finally:
                c.link.unsubscribe(sub)


class _Download:
    """One download, in two steps: the count (the list request asked again, doubling the wait, until a
    MISSION_COUNT comes), then each item in order (PX4 refuses out-of-order requests), re-requested after the
    RTO. Every wait also ends at the download's deadline, which the count sets when none was given.

    Error acks are judged like on upload: a transient one (ERROR, INVALID_SEQUENCE - often a stale answer to
    a duplicated packet of the previous transfer) is ignored; any other ends the download when the wait it
    arrived in passes without an answer. DENIED is ArduPilot's "busy": it refuses list and item requests
    while an upload is being received, and until the deferred ACCEPTED of its last one is out
    (MissionItemProtocol.cpp) - asked again until the retries run out."""

    def __init__(self, client: "MissionClient", box, mission_type: int, progress: Progress | None,
                 deadline_s: float | None) -> None:
        self.c = client
        self.t = client.timeouts
        self.box = box
        self.mission_type = mission_type
        self.where = client._where(mission_type)
        self.progress = progress
        self.start = time.monotonic()
        self.given = deadline_s is not None
        self.deadline_s = deadline_s
        self.end = self.start + deadline_s if deadline_s is not None else math.inf
        self.resent = 0
        self.busy = False                   # a DENIED came to a list request
        self.fatal: int | None = None       # an error ack that ends the step it came in
        self.last_answer: int | None = None  # the last ack among the items

    def run(self) -> tuple[list[MissionItem], TransferResult]:
        count_msg = self.count()
        count = count_msg.count
        if not self.given:
            self.deadline_s = download_deadline_s(count, self.c.rtt.srtt, self.t)
            self.end = self.start + self.deadline_s
        self.fatal = None  # an error ack that came with (or before) the count was not about the items
        items = []
        for seq in range(count):
            items.append(self.item(seq, count))
            if self.progress:
                self.progress(seq + 1, count)
        c = self.c
        c.link.send(c.link.mav.mission_ack_encode(c.target_system, c.target_component, mavlink2.MAV_MISSION_ACCEPTED,
                                                  self.mission_type))
        mavlink1 = (count_msg.get_msgbuf() or b"\xfd")[0] == mavlink2.PROTOCOL_MARKER_V1
        return items, TransferResult(self.mission_type, count, time.monotonic() - self.start, opaque_id_of(count_msg),
                                     self.resent, mavlink1=mavlink1)

    def _wait(self, deadline: float):
        return self.box.get(max(0.0, deadline - time.monotonic()))

    def _past_deadline(self, received: str) -> LinkError:
        return _past_deadline(self.deadline_s, self.given, received, self.where, self.t)

    # -- step 1: the count ---------------------------------------------------------------------
    def count(self):
        """The vehicle's MISSION_COUNT; LinkError (ListUnsupported: it has no such list) otherwise."""
        t = self.t
        wait = t.first_s
        for attempt in range(t.retries + 1):
            msg = self.ask_for_count(wait, first=attempt == 0)
            if msg is not None:
                return msg
            self.check_list_refused()
            if time.monotonic() >= self.end:
                raise self._past_deadline("no MISSION_COUNT came")
            self.resent += 1
            wait = min(wait * 2, t.ack_s)
        if self.busy:
            raise LinkError(f"the vehicle answered MAV_MISSION_DENIED to all {t.retries + 1} list requests",
                            where=self.where, hint="it is busy receiving an upload (another ground station?); "
                                                   "retry when that has finished")
        raise LinkError(f"no MISSION_COUNT after {t.retries + 1} list requests", where=self.where,
                        hint="check the connection and the target system/component")

    def ask_for_count(self, wait: float, first: bool):
        """Send one list request; the MISSION_COUNT that answers it within `wait`, else None (noting the
        error acks that came meanwhile)."""
        c = self.c
        c.link.send(c.link.mav.mission_request_list_encode(c.target_system, c.target_component, self.mission_type))
        sent = time.monotonic()
        deadline = min(sent + wait, self.end)
        while (msg := self._wait(deadline)) is not None:
            if msg.get_type() == "MISSION_COUNT":
                if first:
                    c.rtt.sample(time.monotonic() - sent)
                return msg
            if msg.get_type() != "MISSION_ACK":
                continue
            if msg.type == mavlink2.MAV_MISSION_DENIED:
                self.busy = True
            elif msg.type in _FATAL_NACKS:
                self.fatal = msg.type
        return None

    def check_list_refused(self) -> None:
        fatal = self.fatal
        if fatal == mavlink2.MAV_MISSION_UNSUPPORTED:
            raise ListUnsupported(f"the vehicle has no {TYPE_NAMES.get(self.mission_type, self.mission_type)} list "
                                  "(it answered MAV_MISSION_UNSUPPORTED to the list request)", where=self.where,
                                  hint="nothing to download: this firmware was built without it")
        if fatal is not None:
            raise LinkError(f"the vehicle answered {mission_result_name(fatal)} to the list request",
                            where=self.where, hint=_NACK_HINTS.get(fatal, _DOWNLOAD_NACK_HINT))

    # -- step 2: the items, one at a time -------------------------------------------------------
    def item(self, seq: int, count: int) -> MissionItem:
        """Item `seq`, asked for up to `retries` + 1 times; LinkError when it never comes."""
        t = self.t
        for tries in range(t.retries + 1):
            item = self.ask_for_item(seq, tries)
            if item is not None:
                return item
            if self.fatal is not None:
                raise LinkError(f"the vehicle answered {mission_result_name(self.fatal)} to the request for item "
                                f"{seq}", where=self.where, hint=_NACK_HINTS.get(self.fatal, _DOWNLOAD_NACK_HINT))
            if time.monotonic() >= self.end:
                raise self._past_deadline(f"{seq} of {count} items had arrived (item {seq} was asked for "
                                          f"{tries + 1} times)")
            self.resent += 1
        answer = "" if self.last_answer is None else f" (last answer: {mission_result_name(self.last_answer)})"
        raise LinkError(f"item {seq} of {count} never arrived after {t.retries + 1} requests{answer}",
                        where=self.where, hint="the link is too lossy or was lost; retry the download")

    def ask_for_item(self, seq: int, tries: int) -> MissionItem | None:
        """Send the request for item `seq` (the `tries`-th time); the item if it comes within the RTO (doubled
        per earlier try, at most `ack_s`), else None."""
        c, t = self.c, self.t
        c.link.send(c.link.mav.mission_request_int_encode(c.target_system, c.target_component, seq,
                                                          self.mission_type))
        sent = time.monotonic()
        rto = c.rtt.rto(t.min_rto_s, max(t.item_s, t.min_rto_s), t.item_s)
        deadline = min(sent + min(rto * (2 ** tries), t.ack_s), self.end)
        while (msg := self._wait(deadline)) is not None:
            if msg.get_type() == "MISSION_ITEM_INT":
                # Only the item asked for: a late duplicate of an older item (or of an earlier transfer)
                # must never fill another slot.
                if msg.seq == seq:
                    if tries == 0:
                        c.rtt.sample(time.monotonic() - sent)
                    return item_from_msg(msg)
            elif msg.get_type() == "MISSION_ACK":
                self.last_answer = msg.type
                if msg.type in _FATAL_NACKS and msg.type != mavlink2.MAV_MISSION_DENIED:
                    self.fatal = msg.type
        return None


# -- files <-> vehicle (what `wiris mission upload/download` run) -------------------------------------

PLAN_SUFFIXES = (".plan",)
WPL_SUFFIXES = (".waypoints", ".wpl", ".txt")
CAPTURE_SUFFIXES = (".yaml", ".yml")


Home = tuple[float, float, float]


class LoadedList(NamedTuple):
    """What load_for_upload read: the items of one list, without a home row, and the file's home; the
    MAV_AUTOPILOT the file was made for (None: it does not say) and what the reader repaired or skipped."""
    items: list[MissionItem]
    home: Home | None
    firmware: int | None = None
    notes: tuple[str, ...] = ()


# The firmwares whose files differ (ArduPilot's item 0 is home, commands and frames each accepts): a file made
# for one of them is checked against the vehicle's HEARTBEAT; a generic one (firmwareType 0) is not.
CHECKED_FIRMWARES = {mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA: "ardupilot", mavlink2.MAV_AUTOPILOT_PX4: "px4"}
FIRMWARE_LABELS = {"ardupilot": "ArduPilot", "px4": "PX4"}


def load_for_upload(path: str, mission_type: int = MISSION_TYPE_MISSION, *, part: int | None = None,
                    firmware: str | None = None) -> LoadedList:
    """The items of `mission_type` in a .plan, a WPL 110 file (a mission, or a fence or rally list as
    Mission Planner saves one) or a capture plan (compiled on the fly), without a home row, and the file's
    home. PlanError/LinkError for anything unusable."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in PLAN_SUFFIXES:
        loaded = _list_of_plan_file(p, mission_type)
    elif suffix in WPL_SUFFIXES:
        loaded = _list_of_wpl_file(p, mission_type)
    elif suffix in CAPTURE_SUFFIXES and mission_type == mavlink2.MAV_MISSION_TYPE_FENCE:
        loaded = _capture_plan_fence(p, firmware)
    elif suffix in CAPTURE_SUFFIXES:
        _require_mission(p, mission_type, "a capture plan compiles to a mission")
        loaded = _capture_plan_part(p, part, firmware)
    else:
        raise PlanError(f"unknown file type {suffix or '(no suffix)'!r}", where=str(p),
                        hint="upload a .plan, a .waypoints (QGC WPL 110) or a capture plan .yaml")
    chosen = [it.with_(mission_type=mission_type) for it in loaded.items]
    if not chosen:
        raise PlanError(f"the file holds no {TYPE_NAMES.get(mission_type, str(mission_type))} items", where=str(p),
                        hint="check --type (mission, fence or rally); to clear a list, use the ground station")
    return loaded._replace(items=chosen)


def _list_of_plan_file(p, mission_type: int) -> LoadedList:
    read = load_plan_file(p)
    chosen = {MISSION_TYPE_MISSION: read.items, mavlink2.MAV_MISSION_TYPE_FENCE: read.fence,
              mavlink2.MAV_MISSION_TYPE_RALLY: read.rally}[mission_type]
    firmware = read.firmware if read.firmware in CHECKED_FIRMWARES else None
    return LoadedList(chosen, read.home, firmware, tuple(map(str, read.notes)))


def _list_of_wpl_file(p, mission_type: int) -> LoadedList:
    """A WPL 110 file's list, which must be the one asked for: a Mission Planner fence file is no mission."""
    read = load_wpl_file(p)
    if read.mission_type != mission_type:
        held, asked = LIST_NAMES[read.mission_type], TYPE_NAMES.get(mission_type, str(mission_type))
        if read.mission_type == MISSION_TYPE_MISSION:
            hint = f"upload a {asked} from a .plan file or from a WPL file of {asked} rows"
        else:
            hint = f"to send it to the vehicle's {held} list, give --type {held}"
        raise PlanError(f"the file holds a {held} list ({len(read.items)} rows), not a {asked}", where=str(p),
                        hint=hint)
    return LoadedList(read.items, read.home, None, tuple(map(str, read.notes)))


def _require_mission(p, mission_type: int, what: str) -> None:
    """PlanError unless a mission is asked for: a capture plan compiles to a mission only."""
    if mission_type != MISSION_TYPE_MISSION:
        raise PlanError(f"{what}, not a {TYPE_NAMES.get(mission_type, str(mission_type))} list", where=str(p),
                        hint="upload fence and rally from a .plan file")


def _capture_plan_part(p, part: int | None, firmware: str | None) -> LoadedList:
    """The mission of capture plan `p` compiled for `firmware` (None: the plan's), its sortie `part` (1..N) when
    it is flown in sorties (missions.sorties)."""
    compiled = _compiled_without_errors(p, firmware)
    parts = list(compiled.parts) if compiled.parts else [compiled.items]
    made_for = next((code for code, name in CHECKED_FIRMWARES.items() if name == compiled.firmware), None)
    return LoadedList(list(parts[_part_index(p, part, len(parts), compiled.item_limit)]), compiled.home, made_for)


def _capture_plan_fence(p, firmware: str | None) -> LoadedList:
    """The fence capture plan `p` compiles to: its exclusion zones and `fence: {margin_m}` inclusion polygon."""
    compiled = _compiled_without_errors(p, firmware)
    if not compiled.fence:
        raise PlanError("the capture plan has no fence: no step has no_fly: or exclude: zones and it has no fence: key",
                        where=str(p), hint="add fence: {margin_m: 30} for an inclusion fence around the flight")
    made_for = next((code for code, name in CHECKED_FIRMWARES.items() if name == compiled.firmware), None)
    return LoadedList(list(compiled.fence), compiled.home, made_for)


def _compiled_without_errors(p, firmware: str | None):
    """missions.compile.compile_plan of `p`; PlanError when the report of the compiled mission finds errors."""
    compiled = compile_plan(str(p), firmware=firmware)
    try:
        errors = [e.to_json() for e in report(compiled).errors]
    except PlanError as err:  # from measuring the mission (a photo budget): about the plan as a whole
        err.where = err.where or str(p)
        raise
    if errors:
        raise PlanError(f"the compiled mission has {len(errors)} error(s): {errors[0]}", where=str(p),
                        hint="run `wiris mission check` and fix the plan before uploading")
    return compiled


def _part_index(p, part: int | None, count: int, item_limit: int) -> int:
    """The index into the `count` sorties of --sortie `part` (None: the only one); PlanError when it names none."""
    if count > 1 and part is None:
        raise PlanError(f"the mission is flown in {count} sorties (one battery or {item_limit} items each)",
                        where=str(p), hint=f"choose one with --sortie 1..{count}")
    if part is not None and not 1 <= part <= count:
        raise PlanError(f"--sortie {part}: the mission has {count} sortie(s)", where=str(p),
                        hint="leave out --sortie: the mission is flown in one" if count == 1
                        else f"give --sortie 1..{count}: each sortie is a complete mission, flown in turn")
    return (part or 1) - 1


def home_item(home: Home | None) -> MissionItem:
    """ArduPilot's item 0: the home position (it replaces it with its own home on upload)."""
    lat, lon, alt = home if home is not None else (0.0, 0.0, 0.0)
    return MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=FRAME_GLOBAL, x=deg_to_e7(lat),
                       y=deg_to_e7(lon), z=float(alt))


def find_autopilot(link: Link, target_system: int | None, timeout: float):
    """The HEARTBEAT of the vehicle's autopilot (MAV_AUTOPILOT set, not a GCS), else LinkError."""
    deadline = time.monotonic() + timeout
    while True:
        for (s, _c), hb in sorted(link.heartbeats().items()):
            if (target_system is None or s == target_system) and hb.autopilot != mavlink2.MAV_AUTOPILOT_INVALID \
                    and hb.type != mavlink2.MAV_TYPE_GCS:
                buf = hb.get_msgbuf()
                if not link.signing and buf[0] == 0xFD and buf[2] & mavlink2.MAVLINK_IFLAG_SIGNED:
                    # A signing autopilot drops our unsigned requests without a word.
                    raise LinkError(f"system {s} signs its MAVLink 2 messages and this link has no key",
                                    where=link.url, hint="give --signing-key FILE with the vehicle's key or "
                                                         "passphrase")
                return hb
        if time.monotonic() >= deadline:
            who = f"system {target_system}" if target_system is not None else "any autopilot"
            raise LinkError(f"no autopilot HEARTBEAT from {who} within {timeout:g} s", where=link.url,
                            hint="check --connect, that the vehicle is powered, --target-system and --signing-key")
        time.sleep(0.05)


def upload_file(link: Link, path: str, *, mission_type: int = MISSION_TYPE_MISSION, verify: bool = False,
                target_system: int | None = None, target_component: int = 1, part: int | None = None,
                firmware: str | None = None, timeout: float = 10.0, progress: Progress | None = None,
                loaded: LoadedList | None = None, force: bool = False) -> dict:
    """Load `path` (or take `loaded`, from load_for_upload), check it was made for the vehicle's firmware
    (`force`: upload anyway), upload it (ArduPilot: home as item 0), optionally verify; a summary dict.
    A capture plan is compiled for the vehicle's firmware unless `firmware` names one."""
    loaded = loaded if loaded is not None else load_for_upload(path, mission_type, part=part, firmware=firmware)
    hb = find_autopilot(link, target_system, timeout)
    notes: list[str] = []
    if Path(path).suffix.lower() in CAPTURE_SUFFIXES and firmware is None:
        loaded, note = _compiled_for_the_vehicle(path, loaded, hb.autopilot, part)
        notes += [note] if note else []
    elif not force:
        check_firmware(path, loaded.firmware, hb)
    elif loaded.firmware is not None and loaded.firmware != hb.autopilot:
        notes.append(f"uploaded with --force: {firmware_mismatch(path, loaded.firmware, hb).message}")
    items, home = loaded.items, loaded.home
    system = hb.get_srcSystem()
    ardupilot = hb.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    if ardupilot and mission_type == MISSION_TYPE_MISSION:
        items = [home_item(home)] + items
    client = MissionClient(link, system, target_component)
    try:
        result = (client.upload_verified if verify else client.upload)(items, mission_type=mission_type,
                                                                        progress=progress)
    except VehicleRefused as err:
        if err.result == mavlink2.MAV_MISSION_NO_SPACE:
            err.hint = too_big_hint(path, len(items), mission_type)
        raise
    return {"file": str(path), "type": TYPE_NAMES[mission_type], "target_system": system,
            "autopilot": "ardupilot" if ardupilot else "px4" if hb.autopilot == mavlink2.MAV_AUTOPILOT_PX4
            else str(hb.autopilot), "items": len(items), "home_row": ardupilot and mission_type == MISSION_TYPE_MISSION,
            "seconds": round(result.seconds, 3), "verified": result.verified,
            "opaque_id": result.opaque_id, "resent": result.resent, "nacks_tolerated": result.nacks_tolerated,
            "warnings": list(loaded.notes), "notes": notes + list(result.notes)}


def firmware_mismatch(path, made_for: int, hb) -> LinkError:
    """The error for a file made for firmware `made_for` (a MAV_AUTOPILOT) and a vehicle whose HEARTBEAT says
    otherwise."""
    want = FIRMWARE_LABELS[CHECKED_FIRMWARES[made_for]]
    has = FIRMWARE_LABELS.get(CHECKED_FIRMWARES.get(hb.autopilot, ""), f"MAV_AUTOPILOT {hb.autopilot}")
    return LinkError(f"the file was made for {want} but system {hb.get_srcSystem()} reports {has} in its HEARTBEAT: "
                     f"{has} reads {want}'s mission differently (ArduPilot keeps home as item 0; each accepts "
                     "its own commands, frames and params)", where=str(path),
                     hint=f"compile or save the mission for {has} (a capture plan compiles for the vehicle when "
                          "--firmware is left out), or give --force to upload this file anyway")


def check_firmware(path, made_for: int | None, hb) -> None:
    """LinkError when the file was made for ArduPilot or PX4 and the vehicle's HEARTBEAT reports another
    autopilot. A file that names no firmware (WPL, a generic .plan) is not judged."""
    if made_for is not None and hb.autopilot != made_for:
        raise firmware_mismatch(path, made_for, hb)


def _compiled_for_the_vehicle(path, loaded: LoadedList, autopilot: int, part: int | None) -> tuple[LoadedList, str]:
    """The capture plan compiled for the vehicle's firmware (a note says so) when it was compiled for another.
    A vehicle that is neither ArduPilot nor PX4 gets the plan's own firmware, and a note."""
    if loaded.firmware == autopilot:
        return loaded, ""
    name = CHECKED_FIRMWARES.get(autopilot)
    if name is None:
        return loaded, (f"the vehicle reports MAV_AUTOPILOT {autopilot}, neither ArduPilot nor PX4: the plan was "
                        "compiled for its own vehicle.firmware")
    return (_capture_plan_part(Path(path), part, name),
            f"compiled for {FIRMWARE_LABELS[name]}, the firmware the vehicle reports (the plan names another)")


def split_files_beside(path) -> list[Path]:
    """The part and sortie files the compiler wrote beside `path`: NAME.partK.SUFFIX / NAME.sortieK.SUFFIX
    with `path`'s suffix (a capture plan's: .plan), NAME being `path`'s stem without a .partK / .sortieK of its
    own; in order of kind and K."""
    p = Path(path)
    stem = re.sub(r"\.(part|sortie)\d+$", "", p.stem)
    suffix = p.suffix if p.suffix.lower() in PLAN_SUFFIXES + WPL_SUFFIXES else ".plan"
    split = re.compile(rf"{re.escape(stem)}\.(part|sortie)(\d+){re.escape(suffix)}")
    found = [(m.group(1), int(m.group(2)), f) for f in p.parent.glob(f"{glob.escape(stem)}.*{suffix}")
             if (m := split.fullmatch(f.name)) and f != p]
    return [f for _kind, _k, f in sorted(found)]


def too_big_hint(path, count: int, mission_type: int) -> str:
    """What to upload instead of `path`'s `count` items, which the vehicle has no room for."""
    kind = TYPE_NAMES.get(mission_type, "mission")
    split = split_files_beside(path)
    already_split = re.search(r"\.(part|sortie)\d+$", Path(path).stem) is not None
    if split and mission_type == MISSION_TYPE_MISSION and not already_split:
        names = ", ".join(f.name for f in split)
        return (f"the vehicle has no room for {count} items; the compiler split this mission into {names} beside "
                "it: upload them one at a time, each after the last is flown")
    if Path(path).suffix.lower() in CAPTURE_SUFFIXES:
        return (f"the vehicle has no room for {count} items: set vehicle.max_mission_items in the plan to the "
                "vehicle's limit (PX4: 500 by default) and upload with --sortie 1..N")
    return (f"the vehicle has no room for {count} {kind} items (PX4 holds 500 by default, ArduPilot about 700 on "
            "common boards): compile the capture plan with vehicle.max_mission_items set to the vehicle's limit to "
            "get NAME.sortieK files, or use fewer items")


def download_file(link: Link, out: str, *, target_system: int | None = None, target_component: int = 1,
                  timeout: float = 10.0, progress: Progress | None = None, deadline_s: float | None = None) -> dict:
    """Download what the vehicle holds and write it to `out` (.plan: mission, fence and rally;
    .waypoints: the mission) atomically; a summary dict. `deadline_s` bounds each list's download
    (None: MissionClient.download's own, from the count and the round trip)."""

    p = Path(out)
    suffix = _output_suffix(p)
    hb = find_autopilot(link, target_system, timeout)
    system = hb.get_srcSystem()
    client = MissionClient(link, system, target_component)
    mission, res = client.download(mission_type=MISSION_TYPE_MISSION, progress=progress, deadline_s=deadline_s)
    items, home = _split_home(mission, hb.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA)
    others = {kind: _download_other_list(client, kind, res.mavlink1, deadline_s)
              for kind in (mavlink2.MAV_MISSION_TYPE_FENCE, mavlink2.MAV_MISSION_TYPE_RALLY)
              } if suffix in PLAN_SUFFIXES else {}
    atomic_write(p, _file_text(p, suffix, items, home, hb, others))
    return {"file": str(p), "target_system": system,
            "items": {"mission": len(items), **{TYPE_NAMES[kind]: len(o.items) for kind, o in others.items()}},
            "home": list(home) if home else None, "opaque_id": res.opaque_id, "seconds": round(res.seconds, 3),
            "notes": [o.note for o in others.values() if o.note is not None]}


def _output_suffix(p) -> str:
    """The suffix of output file `p`, after checking it can be written - before the download, not after it."""

    suffix = p.suffix.lower()
    if suffix not in PLAN_SUFFIXES + WPL_SUFFIXES:
        raise PlanError(f"unknown output type {suffix or '(no suffix)'!r}", where=str(p),
                        hint="write a .plan or a .waypoints file")
    check_writable(p)
    return suffix


def _split_home(items: list[MissionItem], ardupilot: bool) -> tuple[list[MissionItem], Home | None]:
    """The mission without ArduPilot's item 0, and that item's position as the file's home."""
    if not ardupilot or not items:
        return items, None
    h = items[0]
    return items[1:], (h.x / 1e7, h.y / 1e7, h.z)


class _OtherList(NamedTuple):
    """A fence or rally list for a .plan file."""
    items: list[MissionItem]
    note: str | None = None     # why it is empty without having been downloaded


def _download_other_list(client: MissionClient, kind: int, mavlink1: bool, deadline_s: float | None) -> _OtherList:
    """The vehicle's fence or rally list; empty, with a note, when the vehicle cannot give it; LinkError when
    the download fails (an empty list in the file would claim "no fence" for a vehicle that has one)."""
    name = TYPE_NAMES[kind]
    # mission_type is a MAVLink 2 extension: a vehicle that answered our (MAVLink 2) list request in MAVLink 1
    # cannot carry a fence or rally list (ArduPilot answers UNSUPPORTED, GCS_Common.cpp mavlink2_requirement_met,
    # in a MAVLink 1 ack without the mission_type that says which list). Its answer, not its HEARTBEAT: PX4
    # talks MAVLink 1 until it hears MAVLink 2.
    if mavlink1:
        return _OtherList([], f"{name} not downloaded: the vehicle talks MAVLink 1, which cannot carry fence or "
                              "rally lists")
    try:
        items, _ = client.download(mission_type=kind, deadline_s=deadline_s)
    except ListUnsupported as err:      # the vehicle has no such list: an empty one is the truth
        return _OtherList([], f"{name} not downloaded: {err.message}")
    except LinkError as err:
        raise LinkError(f"the {name} list could not be downloaded, so no file was written: {err.message}",
                        where=err.where, hint=f"{err.hint}; to save the mission alone, use -o FILE.waypoints") from None
    return _OtherList(items)


def _file_text(p, suffix: str, items: list[MissionItem], home: Home | None, hb,
               others: dict[int, _OtherList]) -> str:
    """The text of output file `p`; PlanError (where: `p`) when what the vehicle holds does not fit the file
    form (an infinite float)."""

    try:
        if suffix in PLAN_SUFFIXES:
            return write_plan(items, home, firmware=int(hb.autopilot), vehicle=int(hb.type),
                              fence=others[mavlink2.MAV_MISSION_TYPE_FENCE].items,
                              rally=others[mavlink2.MAV_MISSION_TYPE_RALLY].items)
        return write_wpl(items, home)
    except PlanError as err:
        if err.where is None:
            err.where = str(p)
        raise
