"""One download: the count, then each item in order, re-requested after the RTO, within the download's
deadline.
"""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MissionItem
from wiris_tools.errors import LinkError
from wiris_tools.transfer.results import (ListUnsupported, Progress, TYPE_NAMES, TransferResult, _DOWNLOAD_NACK_HINT,
                                          _FATAL_NACKS, _NACK_HINTS, mission_result_name)
from wiris_tools.transfer.timing import DEADLINE_ROUND_TRIPS_PER_ITEM, Timeouts, download_deadline_s
from wiris_tools.transfer.wire import item_from_msg, opaque_id_of


def _past_deadline(deadline_s: float, given: bool, received: str, where: str, t: Timeouts) -> LinkError:
    source = "given" if given else (f"{t.deadline_floor_s:g} s plus {DEADLINE_ROUND_TRIPS_PER_ITEM} measured round "
                                    "trips per item")
    return LinkError(f"the download did not finish within its deadline of {deadline_s:.3g} s ({source}): {received}",
                     where=where, hint="a slow or lossy link may need longer: raise it with --deadline SECONDS; a "
                                       "vehicle that answers this rarely on a good link is faulty")


class Download:
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
