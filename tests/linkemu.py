"""A UDP relay on 127.0.0.1 that behaves like a telemetry radio: byte rate, latency, loss,
duplication and reordering, all drawn from seeded random generators (random.Random).

    emu = LinkEmulator(vehicle_port, profile=LinkProfile.serial(57600, latency_s=0.02, loss=0.05), seed=7)
    gcs = Link(f"udpout:127.0.0.1:{emu.port}")   # the GCS talks to the emulator ...
    ...                                           # ... which relays to udpin:127.0.0.1:vehicle_port
    emu.close()

Model, per direction (a radio link is full duplex; each direction is its own `Wire`):
  * serialization: a datagram of n bytes occupies the wire for n / bytes_per_s seconds, after the
    datagrams before it (a FIFO). A serial link at B baud with 8N1 framing moves B/10 bytes/s
    (start + 8 data + stop bits): 57600 baud = 5760 bytes/s. `bytes_per_s=None`: no rate limit.
  * a datagram waiting longer than `max_queue_s` to get onto the wire is dropped (radio buffer full).
  * latency: delivered `latency_s` after its last byte left.
  * loss: dropped with probability `loss` (it still used its airtime).
  * duplication: with probability `duplicate` a second copy follows (using airtime too).
  * reordering: with probability `reorder` a datagram is held back `reorder_delay_s` longer, so
    later ones overtake it.
Every datagram consumes exactly four draws from its direction's generator, seeded from
(seed, direction): the same seed and the same traffic give the same fate to every datagram.
"""

from __future__ import annotations

import heapq
import itertools
import random
import select
import socket
import threading
import time
from dataclasses import dataclass, field


@dataclass(frozen=True)
class LinkProfile:
    bytes_per_s: float | None = None
    latency_s: float = 0.0
    loss: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    reorder_delay_s: float = 0.05
    max_queue_s: float = 2.0

    @classmethod
    def serial(cls, baud: int, **kwargs) -> "LinkProfile":
        """A serial radio at `baud` with 8N1 framing: 10 bits on the wire per byte."""
        return cls(bytes_per_s=baud / 10.0, **kwargs)

    def __post_init__(self) -> None:
        for name in ("loss", "duplicate", "reorder"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be a probability in [0, 1], got {v}")
        if self.bytes_per_s is not None and self.bytes_per_s <= 0:
            raise ValueError("bytes_per_s must be positive")


@dataclass
class Wire:
    """One direction of the link: decides when (and whether, and how often) each datagram arrives."""

    profile: LinkProfile
    rng: random.Random
    busy_until: float = 0.0
    stats: dict[str, int] = field(default_factory=lambda: {
        "packets": 0, "bytes": 0, "dropped": 0, "duplicated": 0, "reordered": 0, "overflow": 0, "delivered": 0})

    def _occupy(self, now: float, nbytes: int) -> float | None:
        p = self.profile
        start = max(now, self.busy_until)
        if start - now > p.max_queue_s:
            return None
        done = start + (nbytes / p.bytes_per_s if p.bytes_per_s else 0.0)
        self.busy_until = done
        return done

    def submit(self, now: float, nbytes: int) -> list[float]:
        """Arrival times of this datagram's copies (empty if it is lost)."""
        p = self.profile
        r_loss, r_dup, r_reorder, r_extra = (self.rng.random() for _ in range(4))
        self.stats["packets"] += 1
        self.stats["bytes"] += nbytes
        done = self._occupy(now, nbytes)
        if done is None:
            self.stats["overflow"] += 1
            return []
        if r_loss < p.loss:
            self.stats["dropped"] += 1
            return []
        extra = 0.0
        if r_reorder < p.reorder:
            self.stats["reordered"] += 1
            extra = p.reorder_delay_s * (0.5 + r_extra)
        arrivals = [done + p.latency_s + extra]
        if r_dup < p.duplicate:
            again = self._occupy(now, nbytes)
            if again is not None:
                self.stats["duplicated"] += 1
                arrivals.append(again + p.latency_s)
        self.stats["delivered"] += len(arrivals)
        return arrivals


class LinkEmulator:
    """Relay between a ground station (sends to `.port`) and a vehicle listening on `target_port`."""

    def __init__(self, target_port: int, *, profile: LinkProfile = LinkProfile(),
                 uplink: LinkProfile | None = None, downlink: LinkProfile | None = None, seed: int = 0,
                 host: str = "127.0.0.1", listen_port: int = 0) -> None:
        if host not in ("127.0.0.1", "localhost"):
            raise ValueError("the link emulator only relays on 127.0.0.1")
        self.target = ("127.0.0.1", target_port)
        self.up = Wire(uplink or profile, random.Random(f"{seed}-up"))       # ground -> vehicle
        self.down = Wire(downlink or profile, random.Random(f"{seed}-down"))  # vehicle -> ground
        self._gcs_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._gcs_sock.bind(("127.0.0.1", listen_port))
        self._veh_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._veh_sock.bind(("127.0.0.1", 0))
        for s in (self._gcs_sock, self._veh_sock):
            s.setblocking(False)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self._gcs_addr: tuple[str, int] | None = None
        self._heap: list[tuple[float, int, int, bytes]] = []   # (due, order, direction, data)
        self._order = itertools.count()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="linkemu", daemon=True)
        self._thread.start()

    @property
    def port(self) -> int:
        return self._gcs_sock.getsockname()[1]

    @property
    def stats(self) -> dict[str, dict[str, int]]:
        return {"up": dict(self.up.stats), "down": dict(self.down.stats)}

    def _run(self) -> None:
        socks = [self._gcs_sock, self._veh_sock]
        while not self._stop.is_set():
            now = time.monotonic()
            while self._heap and self._heap[0][0] <= now:
                _due, _n, direction, data = heapq.heappop(self._heap)
                try:
                    if direction == 0:
                        self._veh_sock.sendto(data, self.target)
                    elif self._gcs_addr is not None:
                        self._gcs_sock.sendto(data, self._gcs_addr)
                except OSError:
                    pass
            wait = 0.05 if not self._heap else max(0.0, min(0.05, self._heap[0][0] - time.monotonic()))
            try:
                ready, _, _ = select.select(socks, [], [], wait)
            except (OSError, ValueError):
                return
            now = time.monotonic()
            for sock in ready:
                while True:
                    try:
                        data, addr = sock.recvfrom(65535)
                    except (BlockingIOError, InterruptedError):
                        break
                    except OSError:
                        break
                    if sock is self._gcs_sock:
                        self._gcs_addr = addr
                        wire, direction = self.up, 0
                    else:
                        wire, direction = self.down, 1
                    for due in wire.submit(now, len(data)):
                        heapq.heappush(self._heap, (due, next(self._order), direction, data))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self._gcs_sock.close()
        self._veh_sock.close()

    def __enter__(self) -> "LinkEmulator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
