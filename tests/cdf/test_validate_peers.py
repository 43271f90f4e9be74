"""Crafted definitions through the real parsers: what the validator calls an error in a profile is what
the real parser rejects, crashes on or drops; a clean file loads completely in both."""

from __future__ import annotations

import pytest

import peers
from cdf.validate import validate_bytes

pytestmark = [pytest.mark.peer, pytest.mark.slow]

HEAD = ('<?xml version="1.0" encoding="UTF-8"?>\n<mavlinkcamera>\n<definition version="2">'
        "<model>{model}</model><vendor>Workswell</vendor></definition>\n<parameters>\n")
BASE = """<parameter name="CAM_MODE" type="uint32" default="0" control="0"><description>Mode</description>
<options><option name="Photo" value="0"/><option name="Video" value="1"/></options></parameter>
<parameter name="WW_PALETTE" type="uint32" default="2"><description>Palette</description>
<options><option name="Iron" value="0"/><option name="Rainbow" value="1"/><option name="Gray" value="2"/></options>
</parameter>
<parameter name="WW_EMISS" type="float" default="0.95" min="0.1" max="1.0" step="0.01">
<description>Emissivity</description></parameter>
"""
TAIL = "</parameters>\n</mavlinkcamera>\n"


def cdf(extra: str = "", *, model: str = "WIRIS Pro", base: str = BASE) -> bytes:
    return (HEAD.format(model=model) + base + extra + TAIL).encode()


GOOD = cdf()
# name -> (definition, parameter MAVSDK should lose if it loads the file at all)
BAD = {
    # reference §D: each of these crashes or breaks MAVSDK
    "empty-model": (cdf(model=""), None),
    "empty-description": (cdf('<parameter name="WW_X" type="uint8" default="0" min="0" max="3">'
                              "<description></description></parameter>"), "WW_X"),
    "empty-exclude": (cdf(base=BASE.replace('<option name="Iron" value="0"/>',
                                            '<option name="Iron" value="0"><exclusions><exclude></exclude>'
                                            "</exclusions></option>")), None),
    "non-numeric-option": (cdf('<parameter name="WW_X" type="uint32" default="0"><description>x</description>'
                               '<options><option name="a" value="0"/><option name="b" value="abc"/></options>'
                               "</parameter>"), "WW_X"),
    "uint32-over-int-max": (cdf('<parameter name="WW_X" type="uint32" default="0"><description>x</description>'
                                '<options><option name="a" value="0"/><option name="b" value="3000000000"/>'
                                "</options></parameter>"), "WW_X"),
    "default-not-an-option": (cdf(base=BASE.replace('default="2"', 'default="7"')), None),
    "wrong-case-type": (cdf('<parameter name="WW_X" type="Uint8" default="0" min="0" max="3">'
                            "<description>x</description></parameter>"), "WW_X"),
    "qgc-only-type": (cdf('<parameter name="WW_X" type="elapsedSeconds" default="0" min="0" max="9">'
                          "<description>x</description></parameter>"), "WW_X"),
    "readonly-writeonly": (cdf('<parameter name="WW_X" type="uint8" default="0" min="0" max="3" readonly="1" '
                               'writeonly="1"><description>x</description></parameter>'), "WW_X"),
    "no-default": (cdf('<parameter name="WW_X" type="uint8" min="0" max="3"><description>x</description>'
                       "</parameter>"), "WW_X"),
    "no-range": (cdf('<parameter name="WW_X" type="float" default="1"><description>x</description></parameter>'),
                 "WW_X"),
    "custom-type": (cdf('<parameter name="WW_X" type="custom" control="0"><description>x</description>'
                        "</parameter>"), "WW_X"),
    "range-to-unknown": (cdf(base=BASE.replace(
        '<option name="Rainbow" value="1"/>',
        '<option name="Rainbow" value="1"><parameterranges><parameterrange parameter="NOPE">'
        '<roption name="a" value="0"/></parameterrange></parameterranges></option>')), "WW_PALETTE"),
}


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    names = ["good", *BAD]
    datas = [GOOD, *(d for d, _ in BAD.values())]
    results = peers.mavsdk_load_definitions(datas, tmp_path_factory.mktemp("mavsdk-crafted"), workers=3)
    return dict(zip(names, results))


def test_clean_file_loads_completely_in_mavsdk_and_mavproxy(loaded):
    for profile in ("qgc", "mavsdk", "strict"):
        assert validate_bytes(GOOD, "good.xml", profile).findings == ()
    m = loaded["good"]
    assert m.accepted and m.dropped == ()
    assert m.settings == {"WW_PALETTE": ("0", "1", "2"), "WW_EMISS": m.settings["WW_EMISS"]}
    assert "CAM_MODE" not in m.settings  # control="0"
    px = peers.mavproxy_load_definition(GOOD)
    assert px.accepted and px.settings["WW_PALETTE"] == (0, 1, 2) and set(px.parameters) == {
        "CAM_MODE", "WW_PALETTE", "WW_EMISS"}


@pytest.mark.parametrize("case", sorted(BAD))
def test_mavsdk_profile_error_matches_mavsdk(loaded, case):
    data, lost = BAD[case]
    m = loaded[case]
    report = validate_bytes(data, f"{case}.xml", "mavsdk")
    unhappy = (not m.accepted) or bool(m.dropped)
    assert unhappy, (case, m.outcome, m.log[-800:])
    assert not report.valid, report.findings
    if m.accepted and lost is not None:
        assert lost in m.dropped, (case, m.dropped)


def test_harness_survives_crashes(loaded):
    # reference §D: empty texts and bad numbers crash MAVSDK; the harness records it and carries on
    crashed = [k for k, v in loaded.items() if v.crashed]
    assert crashed, {k: v.outcome for k, v in loaded.items()}
    assert loaded["good"].accepted


MAVPROXY_REJECTS = {
    "duplicate-name": cdf(base=BASE + BASE.split("\n", 2)[2]),
    "min-over-max": cdf('<parameter name="WW_X" type="int32" default="0" min="5" max="1">'
                        "<description>x</description></parameter>"),
    "dtd": cdf().replace(b"<mavlinkcamera>", b"<!DOCTYPE mavlinkcamera []>\n<mavlinkcamera>", 1),
    "string-type": cdf('<parameter name="WW_X" type="string" control="0"><description>x</description></parameter>'),
    "qgc-only-type": cdf('<parameter name="WW_X" type="elapsedSeconds" default="0" min="0" max="9">'
                         "<description>x</description></parameter>"),
    "value-out-of-range": cdf('<parameter name="WW_X" type="uint8" default="300" min="0" max="400">'
                              "<description>x</description></parameter>"),
}


@pytest.mark.parametrize("case", sorted(MAVPROXY_REJECTS))
def test_strict_errors_where_mavproxy_rejects(case):
    data = MAVPROXY_REJECTS[case]
    px = peers.mavproxy_load_definition(data)
    assert not px.accepted, case
    assert not validate_bytes(data, f"{case}.xml", "strict").valid


# The rows of RULES.md's disagreement table (rules.DISAGREEMENTS): MAVSDK loads each of these completely, the
# mavsdk profile keeps its error on purpose, and the row that explains it in bench/cdf_mutants.py matches it.
KEPT = {
    ("stoi-lenient", "digits-then-junk"): cdf(base=BASE.replace('name="Rainbow" value="1"',
                                                                'name="Rainbow" value="1abc"')),
    ("stoi-lenient", "hex-integer"): cdf('<parameter name="WW_X" type="int32" default="1" min="0x10" max="20">'
                                         "<description>x</description></parameter>"),
    ("stoi-lenient", "uint8-over-255"): cdf('<parameter name="WW_X" type="uint8" default="0"><description>x'
                                            '</description><options><option name="a" value="0"/>'
                                            '<option name="b" value="300"/></options></parameter>'),
    ("stof-lenient", "hex-float"): cdf(base=BASE.replace('max="1.0"', 'max="0x1"')),
    # the harness's blind spot: MAVSDK skips the custom parameter, but it has no name to ask MAVSDK for
    ("nameless-skipped", "custom"): cdf('<parameter name="" type="custom" control="0"><description>x'
                                        "</description></parameter>"),
}


@pytest.fixture(scope="module")
def kept(tmp_path_factory):
    results = peers.mavsdk_load_definitions(list(KEPT.values()), tmp_path_factory.mktemp("mavsdk-kept"), workers=2)
    return dict(zip(KEPT, results))


@pytest.mark.parametrize("case", sorted(KEPT))
def test_kept_disagreement_is_what_mavsdk_does_and_its_row_explains_it(kept, case):
    import re

    from cdf.validation.rules import DISAGREEMENTS

    key, _what = case
    m = kept[case]
    assert m.accepted and m.dropped == (), (case, m.outcome, m.dropped, m.log[-800:])
    report = validate_bytes(KEPT[case], "kept.xml", "mavsdk")
    assert not report.valid
    row = next(d for d in DISAGREEMENTS if d.key == key)
    assert tuple(sorted(report.rules("error"))) in row.errors, report.errors
    assert all(re.search(row.messages, f.message) for f in report.errors), report.errors
