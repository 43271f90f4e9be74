"""Bad and partial logs: a clear message and exit 1 where nothing can be said, a note where part is known;
nothing invented."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

import sitl_plans
from audit_logs import T0, Faults, write_tlog
from missions.compile import compile_plan
from wiris_tools.audit.logs import read_log
from wiris_tools.audit.measure import audit_flight
from wiris_tools.cli import cli


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    path = sitl_plans.write_plan(d, "survey")
    return path, compile_plan(path)


def _audit_cli(path: Path, log: Path, *extra: str):
    return CliRunner().invoke(cli, ["mission", "audit", str(path), str(log), *extra])


def test_a_log_without_camera_messages_says_so_and_exits_1(survey, tmp_path):
    path, compiled = survey
    from pymavlink.dialects.v20 import ardupilotmega as mavlink2
    ap = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    msg = mavlink2.MAVLink_global_position_int_message(0, int(50.08e7), int(14.42e7), 262000, 0, 0, 0, 0, 0)
    (tmp_path / "f.tlog").write_bytes(int(T0 * 1e6).to_bytes(8, "big") + msg.pack(ap))
    res = _audit_cli(path, tmp_path / "f.tlog")
    assert res.exit_code == 1
    assert "no camera messages" in res.output and "Traceback" not in res.output


def test_another_flights_log_is_refused(survey, tmp_path):
    path, compiled = survey
    write_tlog(tmp_path / "f.tlog", compiled, offset_deg=(1.0, 0.0))     # 111 km north
    res = _audit_cli(path, tmp_path / "f.tlog")
    assert res.exit_code == 1
    assert "another flight" in res.output


@pytest.mark.parametrize("content,words", [(b"", "empty"), (b"hello, this is no log at all\n" * 4, "not a tlog")])
def test_an_empty_or_foreign_file_is_refused(survey, tmp_path, content, words):
    path, _ = survey
    (tmp_path / "f.bin").write_bytes(content)
    res = _audit_cli(path, tmp_path / "f.bin")
    assert res.exit_code == 1 and words in res.output


def test_a_truncated_tlog_is_audited_as_far_as_it_goes(survey, tmp_path):
    path, compiled = survey
    facts = write_tlog(tmp_path / "f.tlog", compiled)
    data = (tmp_path / "f.tlog").read_bytes()
    (tmp_path / "f.tlog").write_bytes(data[: len(data) // 2 + 7])      # cut inside a frame
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert 0 < audit.captured < facts["photos"]
    assert any("not finished" in s for s in audit.flight.left_plan)
    assert not audit.complete


def test_a_clock_jump_is_noted(survey, tmp_path):
    path, compiled = survey
    write_tlog(tmp_path / "a.tlog", compiled)
    data = bytearray((tmp_path / "a.tlog").read_bytes())
    # the second half's time stamps jump back an hour, as a GCS whose clock was reset writes them
    out, k, n = bytearray(), 0, 0
    frames = []
    while k < len(data):
        ts = int.from_bytes(data[k:k + 8], "big")
        length = data[k + 9] + 12 + (13 if data[k + 10] & 1 else 0)   # MAVLink 2: header 10 + crc 2 (+ signature)
        frames.append((ts, bytes(data[k + 8:k + 8 + length])))
        k += 8 + length
    for i, (ts, frame) in enumerate(frames):
        if i >= len(frames) // 2:
            ts -= 3600 * 1_000_000
        out += ts.to_bytes(8, "big") + frame
    (tmp_path / "b.tlog").write_bytes(bytes(out))
    log = read_log(tmp_path / "b.tlog")
    assert any("clock jumps" in n for n in log.notes)
    res = _audit_cli(path, tmp_path / "b.tlog")
    assert res.exit_code == 0 and "clock jumps" in res.output


def test_a_dataflash_log_without_captures_audits_the_triggers_and_says_so(survey, tmp_path):
    # the other way round: a DataFlash log (triggers only) -- needs a real .BIN: the SITL tests audit those
    path, compiled = survey
    write_tlog(tmp_path / "f.tlog", compiled, faults=Faults(stop_after=0))    # the camera took nothing
    audit = audit_flight(compiled, read_log(tmp_path / "f.tlog"), str(path))
    assert audit.photos_source == "triggers" and audit.captured is None
    assert any("whether the camera took them is unknown" in n for n in audit.notes)
