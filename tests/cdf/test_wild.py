"""Definitions from the wild (tests/data/cdf): a UTF-16 file and <exclusions> beside <option>s, through the
validator's profiles and through the real parsers (MAVSDK 4.1.0 and MAVProxy)."""

from __future__ import annotations

from pathlib import Path

import pytest

import peers
from cdf.validate import validate_bytes

DATA = Path(__file__).resolve().parents[1] / "data" / "cdf"
ORIGINAL = DATA.parents[2].parent / "shared" / "corpus" / "cdf" / "mavsdk" / "e90_camera.xml"
UTF16 = DATA / "e90_camera_utf16.xml"
BESIDE = DATA / "e90_camera_exclusions_beside_options.xml"


def errors(path: Path, profile: str) -> set[str]:
    return validate_bytes(path.read_bytes(), path.name, profile).rules("error")


def findings(data: bytes, profile: str) -> set[tuple]:
    return {(f.rule, f.severity, f.line, f.parameter) for f in validate_bytes(data, "x.xml", profile).findings}


def test_utf16_file_is_an_error_where_mavsdk_reads_it():
    assert errors(UTF16, "mavsdk") == {"CDF008"}
    assert errors(UTF16, "strict") == {"CDF008"}
    assert errors(UTF16, "qgc") == set()
    (f,) = [f for f in validate_bytes(UTF16.read_bytes(), UTF16.name, "mavsdk").findings if f.rule == "CDF008"]
    assert f.line == 1 and "UTF-16" in f.message and "UTF-8" in f.message


def test_utf16_file_is_the_original_otherwise():
    text = UTF16.read_bytes().decode("utf-16")
    assert text.replace('encoding="UTF-16"', 'encoding="UTF-8"', 1).encode() == ORIGINAL.read_bytes()
    for profile in ("qgc", "mavsdk", "strict"):
        wide = {f for f in findings(UTF16.read_bytes(), profile) if f[0] not in ("CDF008", "CDF007")}
        assert wide == findings(ORIGINAL.read_bytes(), profile), profile


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be", "utf-16"])  # the last one writes a BOM
def test_utf16_without_declared_encoding_or_mark_is_found_too(encoding):
    text = ORIGINAL.read_bytes().decode().replace(' encoding="UTF-8"', "", 1)
    data = text.encode(encoding)
    assert "CDF008" in validate_bytes(data, "x.xml", "mavsdk").rules("error")


def test_utf8_with_a_byte_order_mark_is_not_wide():
    # MAVSDK loads a UTF-8 file with a BOM (measured with this corpus file)
    data = b"\xef\xbb\xbf" + ORIGINAL.read_bytes()
    assert validate_bytes(data, "x.xml", "mavsdk").rules("error") == set()


def declared_utf16() -> bytes:
    """The original's UTF-8 bytes with a declaration that says UTF-16 (an editor's wrong guess)."""
    return ORIGINAL.read_bytes().replace(b'encoding="UTF-8"', b'encoding="UTF-16"', 1)


def test_utf8_bytes_declared_utf16_are_checked_as_mavsdk_reads_them():
    data = declared_utf16()
    mavsdk = validate_bytes(data, "x.xml", "mavsdk")
    assert mavsdk.valid and [f.severity for f in mavsdk.findings if f.rule == "CDF009"] == ["warning"]
    assert validate_bytes(data, "x.xml", "strict").rules("error") == {"CDF009"}
    for profile in ("qgc", "mavsdk", "strict"):  # every other rule ran on the file
        rest = {f for f in findings(data, profile) if f[0] not in ("CDF009", "CDF007")}
        assert rest == findings(ORIGINAL.read_bytes(), profile), profile


def test_a_broken_file_with_a_wrong_declaration_is_still_not_well_formed():
    data = b'<?xml version="1.0" encoding="UTF-16"?>\n<mavlinkcamera><definition></mavlinkcamera>'
    assert [f.rule for f in validate_bytes(data, "x.xml", "mavsdk").findings] == ["CDF004"]


def test_exclusions_beside_options_warn_in_mavsdk_and_fail_strict():
    assert errors(BESIDE, "mavsdk") == set()
    assert errors(BESIDE, "strict") == {"CDF200"}
    report = validate_bytes(BESIDE.read_bytes(), BESIDE.name, "mavsdk")
    mine = [f for f in report.findings if f.rule == "CDF200"]
    assert len(mine) == 2 and {f.severity for f in mine} == {"warning"}
    assert {f.parameter for f in mine} == {"CAM_EXPMODE"}


@pytest.mark.peer
@pytest.mark.slow
def test_real_parsers_on_the_wild_files(tmp_path):
    original, utf16, beside, declared = peers.mavsdk_load_definitions(
        [ORIGINAL.read_bytes(), UTF16.read_bytes(), BESIDE.read_bytes(), declared_utf16()], tmp_path, workers=2,
        wait_s=30.0, job_timeout_s=90.0)
    assert original.accepted and original.dropped == (), original.log[-800:]
    # MAVSDK: the UTF-16 file is rejected at its first line ...
    assert utf16.outcome == "rejected" and "tinyxml2" in utf16.log, utf16.log[-800:]
    # ... the misplaced exclusions are lost without dropping a parameter: Auto exposure shows ISO and shutter
    assert beside.accepted and beside.dropped == (), beside.log[-800:]
    assert {"CAM_ISO", "CAM_SHUTTERSPD"} <= set(beside.settings) and not {"CAM_ISO", "CAM_SHUTTERSPD"} & set(
        original.settings)
    # UTF-8 declared as UTF-16: MAVSDK ignores the declaration and loads everything; MAVProxy rejects it
    assert declared.accepted and declared.dropped == () and declared.settings == original.settings, declared.log[-800:]
    assert not peers.mavproxy_load_definition(declared_utf16()).accepted
    # MAVProxy loads both; it too loses the misplaced exclusions
    for path in (UTF16, BESIDE):
        assert peers.mavproxy_load_definition(path.read_bytes()).accepted, path
    px_orig = peers.mavproxy_load_definition(ORIGINAL.read_bytes()).settings
    px_beside = peers.mavproxy_load_definition(BESIDE.read_bytes()).settings
    assert "CAM_ISO" in px_beside and "CAM_ISO" not in px_orig
