"""A UDP relay on 127.0.0.1 between a ground station and a vehicle that drops chosen MISSION_REQUEST_INTs (or legacy MISSION_REQUESTs) on
their way from the vehicle: the first `times` requests for each seq in `drop_seqs`. Deterministic, so a test
knows which loss it provokes (the vehicle got the item, its request for the next one was lost).

    with RequestDropper(vehicle_port, drop_seqs={3, 7}) as relay:
        link = Link(f"udpout:127.0.0.1:{relay.port}")
"""

from __future__ import annotations

import select
import socket
import threading
from collections import Counter

from pymavlink.dialects.v20 import ardupilotmega as mavlink2


class RequestDropper:
    def __init__(self, vehicle_port: int, drop_seqs: set[int], times: int = 1) -> None:
        self.vehicle = ("127.0.0.1", vehicle_port)
        self.drop_seqs, self.times = drop_seqs, times
        self.dropped: Counter[int] = Counter()
        self.requests: Counter[int] = Counter()   # requests seen from the vehicle per seq, dropped or not
        self.gcs_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.gcs_sock.bind(("127.0.0.1", 0))
        self.veh_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.veh_sock.bind(("127.0.0.1", 0))
        self.port = self.gcs_sock.getsockname()[1]
        self.gcs: tuple[str, int] | None = None
        self._parser = mavlink2.MAVLink(None)
        self._parser.robust_parsing = True
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _drop(self, data: bytes) -> bool:
        """Whether this datagram from the vehicle is a request to lose (its frames are parsed whole)."""
        for msg in self._parser.parse_buffer(data) or []:
            if msg.get_type() not in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
                continue
            self.requests[msg.seq] += 1
            if msg.seq in self.drop_seqs and self.dropped[msg.seq] < self.times:
                self.dropped[msg.seq] += 1
                return True
        return False

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.gcs_sock, self.veh_sock], [], [], 0.05)
            for s in ready:
                data, addr = s.recvfrom(65535)
                if s is self.gcs_sock:
                    self.gcs = addr
                    self.veh_sock.sendto(data, self.vehicle)
                elif self.gcs is not None and not self._drop(data):
                    self.gcs_sock.sendto(data, self.gcs)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self.gcs_sock.close()
        self.veh_sock.close()

    def __enter__(self) -> "RequestDropper":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
