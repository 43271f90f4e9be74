"""The link emulator's properties: byte rate, latency, loss/duplication/reordering fractions for a
seed, determinism, and that the UDP relay really relays (127.0.0.1 only)."""

from __future__ import annotations

import math
import random
import socket

import pytest

from linkemu import LinkEmulator, LinkProfile, Wire


def wire(seed=1, **kw) -> Wire:
    return Wire(LinkProfile(**kw), random.Random(seed))


def test_serial_profile_counts_start_and_stop_bits():
    assert LinkProfile.serial(57600).bytes_per_s == 5760


def test_byte_rate_and_latency_are_exact_for_back_to_back_packets():
    w = wire(bytes_per_s=1000, latency_s=0.02)
    arrivals = [w.submit(0.0, 50)[0] for _ in range(10)]
    # each 50-byte packet occupies the wire 50 ms after the previous one, then 20 ms of latency
    assert arrivals == pytest.approx([0.05 * (i + 1) + 0.02 for i in range(10)])
    # an idle wire starts at once
    assert w.submit(10.0, 100)[0] == pytest.approx(10.0 + 0.1 + 0.02)


def test_queue_longer_than_limit_overflows():
    w = wire(bytes_per_s=100, max_queue_s=1.0)
    fates = [w.submit(0.0, 50) for _ in range(5)]   # 0.5 s each: the 4th would wait 1.5 s
    assert [bool(f) for f in fates] == [True, True, True, False, False]
    assert w.stats["overflow"] == 2


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("p", [0.05, 0.2])
def test_loss_fraction_within_binomial_bounds(seed, p):
    n = 4000
    w = wire(seed, loss=p)
    lost = sum(1 for _ in range(n) if not w.submit(0.0, 10))
    sigma = math.sqrt(n * p * (1 - p))
    assert abs(lost - n * p) < 4 * sigma
    assert w.stats["dropped"] == lost


def test_duplication_and_reordering_fractions():
    n = 4000
    w = wire(5, duplicate=0.1, reorder=0.1, reorder_delay_s=0.05, latency_s=0.01)
    fates = [w.submit(i * 0.001, 10) for i in range(n)]
    dups = sum(1 for f in fates if len(f) == 2)
    late = sum(1 for i, f in enumerate(fates) if f[0] > i * 0.001 + 0.01 + 1e-9)
    for count in (dups, late):
        assert abs(count - 0.1 * n) < 4 * math.sqrt(n * 0.09)
    # a reordered packet really is overtaken: some later packet arrives before it
    firsts = [f[0] for f in fates]
    assert any(firsts[i] > firsts[i + 1] for i in range(n - 1))


def test_same_seed_same_fates_other_seed_other_fates():
    prof = dict(bytes_per_s=5760, latency_s=0.02, loss=0.1, duplicate=0.05, reorder=0.05)

    def run(seed):
        w = wire(seed, **prof)
        return [tuple(w.submit(i * 0.01, 40 + i % 7)) for i in range(500)]

    assert run(42) == run(42)
    assert run(42) != run(43)


def test_bad_profiles_are_refused():
    with pytest.raises(ValueError):
        LinkProfile(loss=1.5)
    with pytest.raises(ValueError):
        LinkProfile(bytes_per_s=0)
    with pytest.raises(ValueError):
        LinkEmulator(1, host="10.0.0.1")


def test_relay_both_ways_with_loss_seeded():
    target = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target.bind(("127.0.0.1", 0))
    target.settimeout(2)
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    gcs.settimeout(2)
    with LinkEmulator(target.getsockname()[1], profile=LinkProfile(latency_s=0.005), seed=3) as emu:
        gcs.sendto(b"hello", ("127.0.0.1", emu.port))
        data, emu_addr = target.recvfrom(100)
        assert data == b"hello"
        target.sendto(b"back", emu_addr)
        assert gcs.recvfrom(100)[0] == b"back"
        assert emu.stats["up"]["delivered"] == 1 and emu.stats["down"]["delivered"] == 1
    target.close()
    gcs.close()


def test_relay_keeps_order_and_accounts_every_byte():
    """Rate-limited relay: FIFO order without reordering, and the wire saw every byte."""
    target = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target.bind(("127.0.0.1", 0))
    target.settimeout(3)
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with LinkEmulator(target.getsockname()[1], profile=LinkProfile(bytes_per_s=20000)) as emu:
        for i in range(100):
            gcs.sendto(bytes([i]) * 100, ("127.0.0.1", emu.port))
        got = [target.recvfrom(200)[0][0] for _ in range(100)]
        assert emu.stats["up"]["bytes"] == 100 * 100
    assert got == list(range(100))
    target.close()
    gcs.close()
