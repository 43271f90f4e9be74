"""Truth for the validator, measured against the real parsers on the 23 public CDFs.

MAVSDK 4.1.0's camera plugin loads each file from a pymavlink fake camera over HTTP (tests/peers.py);
MAVProxy's CameraDefinition parses it. Claims tested:
- profile `mavsdk` reports an error exactly when MAVSDK rejects (or crashes on) the file or silently drops
  a parameter, and the parameters its drop rules name are exactly the ones MAVSDK dropped;
- profile `strict` reports an error for every file that either real parser rejects.
The per-file table is printed (also: bench/corpus_agreement.py).
"""

from __future__ import annotations

import pytest

import corpus
import peers

PATHS = corpus.cdf_files()

pytestmark = [pytest.mark.peer, pytest.mark.slow]


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    # 22 copied files, and the SIYI definition when ../shared is beside the repo (tests/corpus.py)
    assert len(PATHS) in (22, 23), PATHS
    return peers.corpus_agreement(PATHS, tmp_path_factory.mktemp("mavsdk-corpus"), workers=3)


def test_print_agreement_table(rows, capsys):
    with capsys.disabled():
        print("\n" + peers.format_agreement(rows))
    # the harness really ran MAVSDK: every file got a verdict, none timed out or lost its camera
    assert all(r.mavsdk.outcome in ("accepted", "rejected", "crashed") for r in rows), \
        [(r.file, r.mavsdk.outcome, r.mavsdk.log[-500:]) for r in rows]


def test_mavsdk_profile_errors_exactly_when_mavsdk_rejects_or_drops(rows):
    wrong = []
    for r in rows:
        mavsdk_unhappy = (not r.mavsdk.accepted) or bool(r.mavsdk.dropped)
        if mavsdk_unhappy == r.reports["mavsdk"].valid:
            wrong.append((r.file, r.mavsdk_cell(), r.profile_cell("mavsdk"), r.mavsdk.dropped))
    assert wrong == []


def test_predicted_drops_are_the_measured_drops(rows):
    for r in rows:
        if r.mavsdk.accepted:
            assert set(r.predicted_drops) == set(r.mavsdk.dropped), r.file


def test_strict_rejects_whatever_either_parser_rejects(rows):
    for r in rows:
        if not r.mavsdk.accepted or r.mavsdk.dropped or not r.mavproxy.accepted:
            assert not r.reports["strict"].valid, r.file


def test_qgc_profile_accepts_the_files_both_gcs_parsers_load(rows):
    # QGC itself cannot run here; every corpus file is loaded by at least one real GCS parser and none
    # breaks a QGC reject rule (reference §B predicts QGC "ok" for all of them).
    assert all(r.reports["qgc"].valid for r in rows)


def test_corpus_has_both_outcomes(rows):
    # guards against a harness that accepts or rejects everything
    cells = {r.mavsdk_cell().split()[0] for r in rows}
    assert {"accepts", "rejects", "drops"} <= cells
    assert any(not r.mavproxy.accepted for r in rows) and any(r.mavproxy.accepted for r in rows)
