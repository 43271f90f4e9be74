"""Helpers for the emulator tests: messages as they arrive off the wire (packed by a GCS, parsed back)."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

NAN = math.nan


class Wire:
    """Packs messages as a sender would (MAVLink 2, or 1) and parses them back, headers included."""

    def __init__(self, system: int = 255, component: int = 190, mavlink1: bool = False) -> None:
        self.enc = mavlink2.MAVLink(None, srcSystem=system, srcComponent=component)
        self.parser = mavlink2.MAVLink(None)
        self.parser.robust_parsing = True
        self.mavlink1 = mavlink1

    def __call__(self, msg):
        buf = msg.pack(self.enc, force_mavlink1=self.mavlink1)
        self.enc.seq = (self.enc.seq + 1) % 256
        out = self.parser.parse_buffer(buf)
        assert out and len(out) == 1, out
        return out[0]

    def cmd(self, command: int, *params: float, target_system: int = 1, target_component: int = 100):
        p = list(params) + [NAN] * (7 - len(params))
        return self(self.enc.command_long_encode(target_system, target_component, command, 0, *p))

    @property
    def mav(self):
        return self.enc


def types(out) -> list[str]:
    return [m.get_type() for m in out]


def ack_of(out, command: int):
    acks = [m for m in out if m.get_type() == "COMMAND_ACK" and m.command == command]
    assert len(acks) == 1, types(out)
    return acks[0].result


def only(out, mtype: str):
    found = [m for m in out if m.get_type() == mtype]
    assert len(found) == 1, types(out)
    return found[0]
