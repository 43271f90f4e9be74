"""200 seeded upload + read-back trials through the link emulator with mixed loss (0-30 %),
duplication (0-20 %) and reordering (0-20 %), against ArduPilot-like (some with transient NACKs)
and PX4-like vehicles: every trial must end in a verified identical mission or a clear LinkError -
never in a reported success while the vehicle holds something else."""

from __future__ import annotations

import re

import pytest

from transfer_trials import run_trials


@pytest.mark.slow
def test_200_trials_no_silent_corruption():
    outcomes = run_trials(range(200), workers=4)
    assert len(outcomes) == 200
    silent = [o for o in outcomes if o.silent_corruption]
    assert silent == []
    failed = [o for o in outcomes if not o.ok]
    # A failure must say what happened, where, and what to do.
    for o in failed:
        # "mission on system 1: ..." or, where one item is at fault (a read-back that differs), "..., item N: ..."
        assert re.match(r"mission on system 1(, item \d+)?: ", o.error) and "hint:" in o.error, o
    # The trials exercise the lossy paths (not a vacuous pass): most still succeed, and the
    # lossless ones always do.
    assert sum(o.ok for o in outcomes) >= 180
    assert all(o.ok for o in outcomes if o.loss == 0 and o.duplicate == 0 and o.reorder == 0)
    assert {o.loss for o in outcomes} == {0.0, 0.05, 0.1, 0.2, 0.3}
