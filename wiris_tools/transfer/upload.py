"""One upload: the state machine driven by the vehicle's requests (fast retransmit, unasked pushes, NACK grace,
the final ack), as the package's docstring describes.
"""

from __future__ import annotations

import threading
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from missions.emit.items import MissionItem
from wiris_tools.errors import LinkError
from wiris_tools.transfer.results import (Progress, TYPE_NAMES, TransferResult, UploadUnconfirmed, VehicleRefused,
                                          _FATAL_NACKS, _NACK_HINTS, mission_result_name)
from wiris_tools.transfer.wire import describe_item, opaque_id_of


class Upload:
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
                                 + (f" to item {seq} ({describe_item(self.items[seq])})" if seq >= 0 else
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
