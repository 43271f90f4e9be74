"""What a transfer returns and how it fails: TransferResult, the errors (UploadUnconfirmed, VehicleRefused,
ListUnsupported), and the vehicle's MAV_MISSION_RESULT answers: their names, hints, and which of them end an
upload.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from wiris_tools.errors import LinkError


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
