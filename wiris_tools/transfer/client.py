"""MissionClient: upload, download and upload with read-back against one vehicle over a Link; and finding the
vehicle's autopilot by its HEARTBEAT.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MISSION_TYPE_MISSION, MissionItem
from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.readback import compare_items, readback_firmware
from wiris_tools.transfer.results import Progress, TYPE_NAMES, TransferResult, UploadUnconfirmed
from wiris_tools.transfer.timing import RttEstimator, Timeouts
from wiris_tools.transfer.wire import check_encodable
from wiris_tools.transfer.upload import Upload
from wiris_tools.transfer.download import Download


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
        check_encodable(items, where)
        return Upload(self, list(items), mission_type, where, progress).run()

    # -- download ------------------------------------------------------------------------------
    def download(self, *, mission_type: int = MISSION_TYPE_MISSION, progress: Progress | None = None,
                 deadline_s: float | None = None) -> tuple[list[MissionItem], TransferResult]:
        """Read the vehicle's list of `mission_type`; returns (items, result). It ends with LinkError
        `deadline_s` seconds after it started, or when given None at download_deadline_s of the count."""
        with self._inbox(["MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ACK"], mission_type) as box:
            return Download(self, box, mission_type, progress, deadline_s).run()

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
