"""Mission items on the wire: MISSION_ITEM_INT to and from MissionItem, the range MISSION_ITEM_INT carries, and
ArduPilot's opaque_id (MAVLink 2 extension bytes the installed dialect does not define).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

from cdf.float32 import FLOAT32_MAX
from missions.emit.items import MissionItem
from wiris_tools.errors import LinkError
from wiris_tools.link import command_name


def describe_item(item: MissionItem) -> str:
    return command_name(item.command)


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


def check_encodable(items: Sequence[MissionItem], where: str) -> None:
    """LinkError naming the first item whose fields MISSION_ITEM_INT cannot carry - before MISSION_COUNT,
    which on ArduPilot already cuts the vehicle's mission to the new count."""
    for i, it in enumerate(items):
        for name in ("param1", "param2", "param3", "param4", "z"):
            v = getattr(it, name)
            if math.isfinite(v) and abs(v) > FLOAT32_MAX:
                raise LinkError(f"item {i} ({describe_item(it)}) has {name} = {v:g}, beyond the float32 range "
                                "MISSION_ITEM_INT carries", where=f"{where}, item {i}",
                                hint="fix the value in the file (at most ±3.4e38); nothing was sent")
        for name, lo, hi in (("x", -2**31, 2**31 - 1), ("y", -2**31, 2**31 - 1), ("command", 0, 65535),
                             ("frame", 0, 255), ("autocontinue", 0, 255), ("current", 0, 255)):
            v = getattr(it, name)
            if not lo <= v <= hi:
                raise LinkError(f"item {i} ({describe_item(it)}) has {name} = {v}, outside {lo}..{hi}",
                                where=f"{where}, item {i}", hint="fix the value in the file; nothing was sent")


def item_from_msg(msg) -> MissionItem:
    return MissionItem(command=msg.command, frame=msg.frame, param1=msg.param1, param2=msg.param2,
                       param3=msg.param3, param4=msg.param4, x=msg.x, y=msg.y, z=msg.z,
                       autocontinue=msg.autocontinue, current=msg.current,
                       mission_type=getattr(msg, "mission_type", 0))
