"""`wiris mission audit` on real logs: ArduPilot SITL flies a compiled survey with the WIRIS emulator on the
camera link, faults injected as in the field; the audit of the tlog and the DataFlash log finds exactly those
faults, and flying its refly plan closes the gaps (union coverage >= 99.5 %). A plan split into two sorties is
flown as two flights (SITL started afresh for each, as after a battery swap) and audited together; PX4 SITL
flies the survey and its ULog's camera_capture rows are audited."""

from __future__ import annotations

import shapely
import pytest

import sitl_plans
from sitl_audit_flights import fly
from missions.compile import compile_plan
from wiris_tools.audit.logs import read_log
from wiris_tools.audit.measure import audit_flight
from wiris_tools.audit.refly import refly_yaml
from wiris_tools.emulate.wiris import CaptureFaults

pytestmark = [pytest.mark.sitl, pytest.mark.slow]


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    path = sitl_plans.write_plan(tmp_path_factory.mktemp("plan"), "survey")
    return path, compile_plan(path)


def _row(label: str, flown, audit) -> str:
    """One row of the audit table (printed: `pytest -s` shows it)."""
    s = audit.steps[0]
    row = (f"AUDIT {label:<28} planned {s.planned:3d}  triggered {audit.triggered}  captured {audit.captured}  "
           f"(emulator asked {flown.requests}, took {flown.taken})  coverage {100 * s.coverage:5.1f} %  "
           f"gaps {len(s.gaps)} ({s.gap_m2:.0f} m2)  missing {s.missing_planned}  "
           f"not captured {len(audit.triggered_not_captured)}  left plan: {'; '.join(audit.flight.left_plan) or '-'}")
    print(row)
    return row


def _union(compiled, *audits) -> float:
    from missions.measure.flight import simulate
    from missions.measure.report import area_geometry
    geom = area_geometry(compiled.areas[0].area, simulate(compiled).projection)
    union = shapely.union_all([a.steps[0].footprints.polygons for a in audits])
    return float(shapely.intersection(geom, union).area / geom.area)


def test_dropped_and_stopped_captures_are_found_and_the_refly_closes_them(sitl_dir, plan, tmp_path):
    path, compiled = plan
    flown = fly(sitl_dir, tmp_path / "a", path, CaptureFaults(drop_every=5, stop_after=45))
    audit = audit_flight(compiled, read_log(flown.tlog), str(path))
    _row("drop every 5th, stop at 45", flown, audit)
    assert audit.captured == flown.taken
    assert audit.triggered == flown.requests
    # the trigger numbers (CAMERA_FEEDBACK.img_idx, from 1) of exactly the requests the camera missed
    assert audit.triggered_not_captured == flown.dropped
    assert audit.captured_not_triggered == ()
    step = audit.steps[0]
    assert step.gaps and step.coverage < 0.9
    # the DataFlash log holds the triggers: as many as the camera was asked for
    df = read_log(flown.bins[-1])
    assert len(df.triggers) == flown.requests
    df_audit = audit_flight(compiled, df, str(path))
    _row("same flight, DataFlash .BIN", flown, df_audit)
    assert df_audit.photos_source == "triggers"
    # the refly plan, flown without faults, closes the gaps
    refly = tmp_path / "survey-refly.yaml"   # the file name is the compiled outputs' NAME
    refly.write_text(refly_yaml(path, audit), encoding="utf-8")
    again = fly(sitl_dir, tmp_path / "r", refly)
    refly_audit = audit_flight(compiled, read_log(again.tlog), str(path))
    union = _union(compiled, audit, refly_audit)
    _row("refly of its gaps", again, refly_audit)
    print(f"AUDIT union coverage after the refly: {100 * union:.2f} %  (refly plan: {compile_plan(refly).areas and len(compile_plan(refly).areas)} area(s), {again.requests} photos)")
    assert union >= 0.995


def test_an_rtl_cut_short_is_found(sitl_dir, plan, tmp_path):
    path, compiled = plan
    flown = fly(sitl_dir, tmp_path / "b", path, rtl_after=30)
    audit = audit_flight(compiled, read_log(flown.tlog), str(path))
    _row("RTL after 30 photos", flown, audit)
    assert audit.captured == flown.taken and audit.triggered_not_captured == ()
    assert any("RTL before the mission's end" in s for s in audit.flight.left_plan), audit.flight
    assert audit.steps[0].gaps and not audit.complete
    # the camera keeps distance-triggering on the way home: photos after the switch are no planned photos, the
    # 30 before it are
    step = audit.steps[0]
    assert step.planned - flown.taken <= step.missing_planned <= step.planned - 30


def test_two_sorties_flown_as_two_flights_are_audited_together(sitl_dir, tmp_path):
    from audit_sorties import write_sortie_plan
    from wiris_tools.audit.flights import audit_flights, format_multi
    path = write_sortie_plan(tmp_path)
    compiled = compile_plan(path)
    one, two = compiled.sorties
    first = fly(sitl_dir, tmp_path / "s1", path, sortie=1)
    second = fly(sitl_dir, tmp_path / "s2", path, sortie=2, faults=CaptureFaults(drop_every=4))
    logs = [read_log(second.tlog), read_log(first.tlog)]          # in any order
    multi = audit_flights(compiled, logs, str(path))
    print(format_multi(multi))
    b, a = multi.flights
    assert (a.sortie, b.sortie) == (1, 2)
    for f, flown in ((a, first), (b, second)):
        _row(f"sortie {f.sortie}", flown, f.audit)
        assert f.audit.captured == flown.taken and f.audit.triggered == flown.requests
        assert f.audit.flight.left_plan == () and f.audit.flight.last_item == f.audit.flight.mission_items
    assert a.audit.triggered_not_captured == () and b.audit.triggered_not_captured == second.dropped
    assert abs(first.requests - one.photos) <= 2 and abs(second.requests - two.photos) <= 2
    u = multi.union.steps[0]
    assert multi.union.captured == first.taken + second.taken
    assert u.coverage >= 0.995 and multi.complete


def test_px4_sitl_ulog_camera_captures_are_audited(px4_dir, tmp_path):
    from wiris_tools.sitl.px4_flight import fly_compiled_px4
    from sitl_audit_flights import compile_to
    path = sitl_plans.write_plan(tmp_path, "survey", firmware="px4")
    compile_to(path, tmp_path / "out")
    with fly_compiled_px4(px4_dir, tmp_path / "out", path.stem, workdir=tmp_path / "px4", speedup=6.0) as flight:
        fired = flight.trigger_shots()
        ulog = flight.sitl.ulogs()[-1]
    compiled = compile_plan(path)
    log = read_log(ulog)
    audit = audit_flight(compiled, log, str(path))
    s = audit.steps[0]
    print(f"AUDIT PX4 SITL ULog {ulog.stat().st_size} bytes: heard by the camera {fired}, "
          f"camera_capture {audit.captured}, planned {s.planned}, "
          f"coverage {100 * s.coverage:.1f} %, front min {100 * s.front_min:.1f} %, side min {100 * s.side_min:.1f} %")
    assert audit.log_kind == "ulog" and audit.photos_source == "captures"
    # PX4's own record: camera_feedback logs a camera_capture for every shot camera_trigger fires (what
    # reached the emulator over the loaded payload link can be fewer), read here with pyulog on its own
    from pyulog import ULog
    shots = {int(v) for v in ULog(str(ulog), ["camera_trigger"]).get_dataset("camera_trigger").data["seq"]}
    assert audit.captured == audit.triggered == len(shots) and audit.triggered_not_captured == ()
    assert abs(audit.captured - s.planned) <= max(2, 0.01 * s.planned)
    assert s.coverage >= 0.995 and audit.complete
    assert audit.flight.left_plan == () and audit.flight.last_item == len(compiled.items)
