"""Mission, fence and rally transfer over the MAVLink mission protocol (ground-station side).

    client = MissionClient(link, target_system=1, target_component=1)
    result = client.upload(items, mission_type=MISSION_TYPE_MISSION, progress=lambda done, total: ...)
    items, result = client.download(mission_type=MISSION_TYPE_MISSION)
    result = client.upload_verified(items)          # upload + read-back, as the firmware keeps it

Files (what `wiris mission upload/download` call; modules file_lists, file_upload, file_download):
load_for_upload(path, type) reads a .plan, a WPL 110 file or a capture plan (compiled with missions.compile);
upload_file(link, path, ...) puts the file's home in as item 0 when the vehicle's HEARTBEAT says ArduPilot (as
QGC and MAVSDK do); download_file(link, out) splits ArduPilot's item 0 off as the file's home and writes .plan
(mission, fence, rally) or .waypoints atomically - after the writers' check (missions.formats.itemcheck) that
every position is a real one and every value one that upload reads back, else PlanError naming the item and
field, and nothing written.

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

The modules: `client` (MissionClient), `upload` and `download` (one transfer each), `timing` (Timeouts, the
round trip, deadlines), `results` (TransferResult, the errors, the vehicle's answers), `wire` (items as MAVLink
messages), and the file side above.
"""

# The package's public names: the CLI, the SITL harness, benches and tests import them from wiris_tools.transfer.
from wiris_tools.transfer.results import (Progress, TYPE_NAMES, mission_result_name, TransferResult, UploadUnconfirmed,
                                          VehicleRefused, ListUnsupported)
from wiris_tools.transfer.timing import (Timeouts, DEADLINE_ROUND_TRIPS_PER_ITEM, DEADLINE_ITEM_MARGIN_S, worst_item_s,
                                         download_deadline_s, RttEstimator)
from wiris_tools.transfer.wire import with_opaque_id, opaque_id_of, item_from_msg
from wiris_tools.transfer.client import MissionClient, find_autopilot
from wiris_tools.transfer.file_lists import (PLAN_SUFFIXES, WPL_SUFFIXES, CAPTURE_SUFFIXES, Home, LoadedList,
                                             CHECKED_FIRMWARES, FIRMWARE_LABELS, load_for_upload)
from wiris_tools.transfer.file_upload import (home_item, upload_file, firmware_mismatch, check_firmware,
                                              split_files_beside, too_big_hint)
from wiris_tools.transfer.file_download import download_file
