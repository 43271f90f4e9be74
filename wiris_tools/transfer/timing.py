"""How long a transfer waits: the time-outs (Timeouts), the smoothed round trip (RttEstimator) and a download's
derived deadline.
"""

from __future__ import annotations

from dataclasses import dataclass


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
