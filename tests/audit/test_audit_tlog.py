"""The audit of tlogs written as a ground station writes them, from a compiled plan's flight with the faults of
the field: what it finds is exactly what was dropped."""

from __future__ import annotations


from pathlib import Path

import pytest


import sitl_plans  # noqa: E402
from audit_logs import Faults, write_tlog  # noqa: E402

from missions.compile import compile_plan
from wiris_tools.audit.logs import read_log
from wiris_tools.audit.measure import audit_flight


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    path = sitl_plans.write_plan(d, "survey")
    return path, compile_plan(path)


def test_a_full_flight_is_complete(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled)
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    (step,) = audit.steps
    assert audit.captured == audit.triggered == facts["photos"]
    assert audit.triggered_not_captured == ()
    assert step.missing_planned == 0
    assert step.coverage >= 0.995 and audit.complete
    assert step.front_min == pytest.approx(0.75, abs=0.02)
    assert audit.flight.left_plan == ()


def test_every_fifth_capture_dropped_is_found_exactly(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(drop_every=5))
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert list(audit.triggered_not_captured) == facts["dropped"]
    assert audit.captured == facts["photos"] - len(facts["dropped"])
    assert audit.steps[0].missing_planned >= len([k for k in facts["dropped"]]) - 2


def test_rtl_cut_short_is_said_and_leaves_a_gap(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(rtl_after=20))
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert audit.triggered == 20
    assert any("RTL before the mission's end" in s for s in audit.flight.left_plan)
    assert audit.steps[0].coverage < 0.9 and audit.steps[0].gaps
    assert not audit.complete
