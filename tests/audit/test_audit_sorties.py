"""A plan split into sorties (a battery swap between them) flown as separate flights, one tlog each, audited
together: each log against the sortie it flew, and their union against the plan's areas."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from audit_logs import Faults, write_tlog
from audit_sorties import write_sortie_plan
from missions.compile import compile_plan
from missions.sorties import as_sortie
from wiris_tools.audit.flights import audit_flights, format_multi
from wiris_tools.audit.logs import read_log
from wiris_tools.cli import cli


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    path = write_sortie_plan(tmp_path_factory.mktemp("sorties"))
    compiled = compile_plan(path)
    assert len(compiled.sorties) == 2
    return path, compiled


def _fly(compiled, sortie, path, faults=Faults()):
    return write_tlog(path, as_sortie(compiled, sortie.items), faults=faults)


def test_two_sorties_each_audited_and_their_union_complete(plan, tmp_path):
    path, compiled = plan
    one, two = compiled.sorties
    f1 = _fly(compiled, one, tmp_path / "a.tlog")
    f2 = _fly(compiled, two, tmp_path / "b.tlog")
    # given in the other order: each log is matched to the sortie it flew by where its photos lie
    multi = audit_flights(compiled, [read_log(tmp_path / "b.tlog"), read_log(tmp_path / "a.tlog")], str(path))
    second, first = multi.flights
    assert (first.sortie, second.sortie) == (1, 2) and multi.sorties_planned == 2 and multi.notes == ()
    for f, s, facts in ((first, one, f1), (second, two, f2)):
        (step,) = f.audit.steps
        assert f.audit.captured == facts["photos"] == s.photos
        assert step.planned == s.photos and step.missing_planned == 0
        assert step.coverage < 0.9                       # one sortie alone covers part of the area
        assert f.audit.flight.mission_items == len(s.items) and f.audit.flight.left_plan == ()
    (u,) = multi.union.steps
    assert multi.union.captured == one.photos + two.photos == u.captured
    assert u.coverage >= 0.995 and multi.complete and u.gaps == ()
    assert u.front_min >= 0.73 and u.side_min >= 0.58               # the seam between the sorties holds too
    assert "sortie 1:" in format_multi(multi) and "all flights together:" in format_multi(multi)


def test_a_second_sortie_cut_short_leaves_a_gap_the_union_reflies(plan, tmp_path):
    path, compiled = plan
    one, two = compiled.sorties
    _fly(compiled, one, tmp_path / "a.tlog")
    _fly(compiled, two, tmp_path / "b.tlog", Faults(rtl_after=6))      # RTL early on the second battery
    res = CliRunner().invoke(cli, ["mission", "audit", str(path), str(tmp_path / "a.tlog"), str(tmp_path / "b.tlog"),
                                   "--json", "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert [f["sortie"] for f in doc["flights"]] == [1, 2]
    assert doc["flights"][1]["captured"] == 6
    assert any("RTL before the mission's end" in s for s in doc["flights"][1]["flight"]["left_plan"])
    assert any(s.startswith("sortie 2: RTL") for s in doc["union"]["flight"]["left_plan"])
    assert doc["complete"] is False and doc["union"]["steps"][0]["gaps"] >= 1
    assert doc["flights"][1]["steps"][0]["missing_planned"] == two.photos - 6
    refly = compile_plan(tmp_path / "out" / "survey-refly.yaml")
    assert refly.areas and json.loads((tmp_path / "out" / "survey.audit.json").read_text())["flights"]


def test_a_sortie_without_a_log_is_said(plan, tmp_path):
    path, compiled = plan
    one, _ = compiled.sorties
    _fly(compiled, one, tmp_path / "a.tlog")
    _fly(compiled, one, tmp_path / "a2.tlog")                      # the first sortie flown twice
    multi = audit_flights(compiled, [read_log(tmp_path / "a.tlog"), read_log(tmp_path / "a2.tlog")], str(path))
    assert [f.sortie for f in multi.flights] == [1, 1]
    assert "no log of sortie(s) 2 of 2" in multi.notes
    assert any("flown more than once" in n for n in multi.notes) and not multi.complete
