"""How a fixed-wing aircraft turns: its radius, and the shortest path between two poses at that radius.

    r = turn_radius_m(speed_mps=16, bank_deg=30)           # 45.2 m
    L = dubins_length_m((0, 0), 0.0, (20, 0), 180.0, r)     # a turnaround onto a line 20 m beside: a loop

A plane cannot turn on the spot: at speed v and bank φ its radius is v² / (g·tan φ) (a coordinated level turn).
The shortest path from one position and heading to another at that radius is a Dubins path (Dubins 1957): two
arcs joined by a straight (LSL, RSR, LSR, RSL) or three arcs (RLR, LRL, the loop a plane flies onto a line closer
than two radii beside the one it leaves). The formulas are the classic ones (Shkel & Lumelsky 2001), in units of
the radius. Headings at this interface are degrees from north, clockwise (the flight model's).
"""

from __future__ import annotations

import math

G_MPS2 = 9.80665
DEFAULT_BANK_DEG = 30.0


def turn_radius_m(speed_mps: float, bank_deg: float = DEFAULT_BANK_DEG) -> float:
    return speed_mps ** 2 / (G_MPS2 * math.tan(math.radians(bank_deg)))


def _mod(a: float) -> float:
    return a % (2.0 * math.pi)


def _words(d: float, a: float, b: float) -> list[float]:
    """Lengths (in radii) of the six Dubins words that exist from heading a to heading b, distance d apart."""
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    out = []
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)                                     # LSL
    if p2 >= 0:
        tmp = math.atan2(cb - ca, d + sa - sb)
        out.append(_mod(-a + tmp) + math.sqrt(p2) + _mod(b - tmp))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)                                     # RSR
    if p2 >= 0:
        tmp = math.atan2(ca - cb, d - sa + sb)
        out.append(_mod(a - tmp) + math.sqrt(p2) + _mod(-b + tmp))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)                                    # LSR
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out.append(_mod(-a + tmp) + p + _mod(-_mod(b) + tmp))
    p2 = -2 + d * d + 2 * cab - 2 * d * (sa + sb)                                    # RSL
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out.append(_mod(a - tmp) + p + _mod(b - tmp))
    tmp = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8                               # RLR
    if abs(tmp) <= 1:
        p = _mod(2 * math.pi - math.acos(tmp))
        t = _mod(a - math.atan2(ca - cb, d - sa + sb) + p / 2)
        out.append(t + p + _mod(a - b - t + p))
    tmp = (6 - d * d + 2 * cab + 2 * d * (-sa + sb)) / 8                              # LRL
    if abs(tmp) <= 1:
        p = _mod(2 * math.pi - math.acos(tmp))
        t = _mod(-a - math.atan2(ca - cb, d + sa - sb) + p / 2)
        out.append(t + p + _mod(_mod(b) - a - t + p))
    return out


def dubins_length_m(p0: tuple[float, float], heading0_deg: float, p1: tuple[float, float], heading1_deg: float,
                    radius_m: float) -> float:
    """Length of the shortest path from p0 flying heading0 to p1 flying heading1, turning at radius_m."""
    dx, dy = p1[0] - p0[0], p1[1] - p0[1]
    dist = math.hypot(dx, dy)
    if radius_m <= 0:
        return dist
    theta = math.atan2(dy, dx)
    # compass degrees (from north, clockwise) to the math angle (from x, counter-clockwise)
    a = _mod(math.radians(90.0 - heading0_deg) - theta)
    b = _mod(math.radians(90.0 - heading1_deg) - theta)
    words = _words(dist / radius_m, a, b)
    return min(words) * radius_m if words else dist
