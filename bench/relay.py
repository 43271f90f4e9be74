"""A UDP relay on 127.0.0.1 that behaves like a 57600-baud telemetry radio pair, for benchmarks.

    with Relay(vehicle_port=14550, loss=0.05, seed=7) as relay:     # the vehicle listens (udpin) on 14550
        ... connect the ground station to udpout:127.0.0.1:{relay.port}
    with Relay(loss=0.05, seed=7) as relay:                         # the vehicle sends to relay.vehicle_side
        ... (ArduPilot SITL: --serialN udpclient:127.0.0.1:{relay.vehicle_side})

Each direction on its own: a datagram is dropped with probability `loss` (its own seeded random stream per
direction, decided in arrival order), else it waits for the line to be free, takes len * 10 / baud seconds
on it (8N1: 10 bits per byte) and arrives `latency_s` after its last byte left. Written independently of
tests/linkemu.py, so the bench does not measure the uploader against the project's own emulator only.
Each side's peer is the last address a datagram came from (the vehicle side's: `vehicle_port` when given).
"""

from __future__ import annotations

import heapq
import random
import select
import socket
import threading
import time
from dataclasses import dataclass, field


@dataclass
class _Direction:
    """One way through the relay: its line, its loss stream and the datagrams in flight."""
    rng: random.Random
    line_free_at: float = 0.0
    in_flight: list[tuple[float, int, bytes]] = field(default_factory=list)   # (arrival, order, data)
    order: int = 0
    dropped: int = 0
    passed: int = 0

    def admit(self, data: bytes, now: float, loss: float, byte_s: float, latency_s: float) -> None:
        if self.rng.random() < loss:
            self.dropped += 1
            return
        self.line_free_at = max(self.line_free_at, now) + len(data) * byte_s
        self.order += 1
        heapq.heappush(self.in_flight, (self.line_free_at + latency_s, self.order, data))
        self.passed += 1

    def due(self, now: float) -> list[bytes]:
        out = []
        while self.in_flight and self.in_flight[0][0] <= now:
            out.append(heapq.heappop(self.in_flight)[2])
        return out


class Relay:
    """The relay, running on its own thread until close()."""

    def __init__(self, vehicle_port: int | None = None, *, loss: float = 0.0, seed: int = 0, baud: int = 57600,
                 latency_s: float = 0.020) -> None:
        self.loss, self.latency_s, self.byte_s = loss, latency_s, 10.0 / baud
        self.gcs_sock = self._bound()
        self.veh_sock = self._bound()
        self.port = self.gcs_sock.getsockname()[1]
        self.vehicle_side = self.veh_sock.getsockname()[1]
        self.gcs_peer: tuple[str, int] | None = None
        self.veh_peer = ("127.0.0.1", vehicle_port) if vehicle_port is not None else None
        self.up = _Direction(random.Random(f"{seed}-up"))      # ground station -> vehicle
        self.down = _Direction(random.Random(f"{seed}-down"))  # vehicle -> ground station
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="relay")
        self._thread.start()

    @staticmethod
    def _bound() -> socket.socket:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind(("127.0.0.1", 0))
        s.setblocking(False)
        return s

    def _run(self) -> None:
        while not self._stop.is_set():
            now = time.monotonic()
            nxt = min([d.in_flight[0][0] for d in (self.up, self.down) if d.in_flight] or [now + 0.05])
            ready, _, _ = select.select([self.gcs_sock, self.veh_sock], [], [], max(0.0, min(nxt - now, 0.05)))
            now = time.monotonic()
            for s in ready:
                self._receive(s, now)
            self._deliver(now)

    def _receive(self, s: socket.socket, now: float) -> None:
        while True:
            try:
                data, addr = s.recvfrom(65535)
            except (BlockingIOError, ConnectionRefusedError):
                return
            if s is self.gcs_sock:
                self.gcs_peer = addr
                self.up.admit(data, now, self.loss, self.byte_s, self.latency_s)
            else:
                self.veh_peer = addr
                self.down.admit(data, now, self.loss, self.byte_s, self.latency_s)

    def _deliver(self, now: float) -> None:
        for direction, sock, peer in ((self.up, self.veh_sock, self.veh_peer),
                                      (self.down, self.gcs_sock, self.gcs_peer)):
            for data in direction.due(now):
                if peer is not None:
                    try:
                        sock.sendto(data, peer)
                    except OSError:
                        pass   # the peer is gone: a radio would lose it too

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self.gcs_sock.close()
        self.veh_sock.close()

    def __enter__(self) -> "Relay":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
