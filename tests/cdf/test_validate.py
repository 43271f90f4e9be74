"""CDF validator: each rule fires on a crafted file (with line and parameter), profiles, JSON, docs, CLI."""

from __future__ import annotations

import json
import lzma
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from cdf.errors import CdfError
from cdf.validate import PROFILES, RULES, CameraInfo, validate_bytes
from cdf.validation.rules import RANK, render_markdown
from wiris_tools.cli import cli
import corpus

REPO = Path(__file__).resolve().parents[2]
CORPUS = corpus.CDF

HEAD = '<?xml version="1.0" encoding="UTF-8"?>\n'


def doc(params: str, *, definition: str | None = None, extra: str = "", head: str = HEAD) -> bytes:
    definition = definition or '<definition version="3"><model>WIRIS Pro</model><vendor>Workswell</vendor></definition>'
    return (f"{head}<mavlinkcamera>\n{definition}\n<parameters>\n{params}\n</parameters>\n{extra}"
            "</mavlinkcamera>\n").encode()


GOOD_PARAMS = """<parameter name="CAM_MODE" type="uint32" default="0" control="0">
  <description>Camera mode</description>
  <options><option name="Photo" value="0"/><option name="Video" value="1"/></options>
</parameter>
<parameter name="WW_PALETTE" type="uint32" default="1">
  <description>Palette</description>
  <updates><update>WW_LAYOUT</update></updates>
  <options>
    <option name="Iron" value="0"><exclusions><exclude>WW_EMISS</exclude></exclusions></option>
    <option name="Rainbow" value="1">
      <parameterranges><parameterrange parameter="WW_LAYOUT" condition="CAM_MODE=0">
        <roption name="Thermal" value="0"/></parameterrange></parameterranges>
    </option>
  </options>
</parameter>
<parameter name="WW_LAYOUT" type="uint8" default="0">
  <description>Layout</description>
  <options><option name="Thermal" value="0"/><option name="Visible" value="1"/></options>
</parameter>
<parameter name="WW_EMISS" type="float" default="0.95" min="0.1" max="1.0" step="0.01">
  <description>Emissivity</description>
</parameter>
<parameter name="WW_RECORD" type="bool" default="0"><description>Record</description></parameter>"""

GOOD = doc(GOOD_PARAMS, extra='<localization><locale name="de_DE"><strings original="Palette" '
                              'translated="Farbpalette"/></locale></localization>\n')


def p(xml: str) -> bytes:
    """A good file plus one more parameter."""
    return doc(GOOD_PARAMS + "\n" + xml)


def findings(data: bytes, profile: str = "strict"):
    return validate_bytes(data, "t.xml", profile).findings


def rules_of(data: bytes, profile: str = "strict") -> set[str]:
    return {f.rule for f in findings(data, profile)}


def test_good_file_is_clean_in_every_profile():
    for profile in PROFILES:
        report = validate_bytes(GOOD, "good.xml", profile)
        assert report.valid and report.findings == (), report.findings
        assert report.parameters == 5


# (rule, bad document, parameter the finding names, profiles where it is an error)
CASES = [
    ("CDF101", b'<?xml version="1.0" encoding="UTF-8"?><camera><definition version="1"><model>a</model>'
               b'<vendor>b</vendor></definition><parameters><parameter name="A" type="uint8" default="0" min="0" '
               b'max="1"><description>d</description></parameter></parameters></camera>', None, {"mavsdk", "strict"}),
    ("CDF102", doc("", definition="<x><definition version='1'><model>a</model><vendor>b</vendor></definition></x>"),
     None, {"mavsdk", "strict"}),
    ("CDF103", HEAD.encode() + b'<mavlinkcamera><parameters/></mavlinkcamera>', None, {"qgc", "mavsdk", "strict"}),
    ("CDF104", doc(GOOD_PARAMS, definition='<definition version="1"><model>a</model></definition>'), None,
     {"qgc", "mavsdk", "strict"}),
    ("CDF105", doc(GOOD_PARAMS, definition='<definition version="1"><model></model><vendor>b</vendor></definition>'),
     None, {"mavsdk", "strict"}),
    ("CDF105", p('<parameter name="X" type="uint8" default="0" min="0" max="1"><description/></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF106", doc(GOOD_PARAMS, definition='<definition><model>a</model><vendor>b</vendor></definition>'), None,
     {"qgc", "strict"}),
    ("CDF107", doc(GOOD_PARAMS, definition='<definition version="70000"><model>a</model><vendor>b</vendor></definition>'),
     None, set()),
    ("CDF108", doc(""), None, {"qgc", "strict"}),
    ("CDF109", p('<parameter name="X" default="0"><description>d</description></parameter>'), "X",
     {"qgc", "mavsdk", "strict"}),
    ("CDF110", p('<parameter name="X" type="uint33" default="0"><description>d</description></parameter>'), "X",
     {"qgc", "mavsdk", "strict"}),
    ("CDF111", p('<parameter name="X" type="UINT8" default="0" min="0" max="3"><description>d</description></parameter>'),
     "X", {"mavsdk", "strict"}),
    ("CDF112", p('<parameter name="X" type="string" control="0"><description>d</description></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF113", p('<parameter name="X" type="custom" control="0"><description>d</description></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF114", p('<parameter name="X" type="uint8" default="0" min="0" max="3"></parameter>'), "X",
     {"qgc", "mavsdk", "strict"}),
    ("CDF115", p('<parameter name="X" type="uint16" default="0" min="0" max="3"><description>d</description></parameter>'),
     "X", set()),
    ("CDF116", p('<parameter name="WW_A_VERY_LONG_NAME" type="uint8" default="0" min="0" max="3">'
                 '<description>d</description></parameter>'), "WW_A_VERY_LONG_NAME", {"qgc", "mavsdk", "strict"}),
    ("CDF134", p('<parameter name="WW_É" type="uint8" default="0" min="0" max="3">'
                 '<description>d</description></parameter>'), "WW_É", {"qgc", "strict"}),
    ("CDF117", p('<parameter name="WW_LAYOUT" type="uint8" default="0" min="0" max="3"><description>d</description>'
                 '</parameter>'), "WW_LAYOUT", {"qgc", "strict"}),
    ("CDF118", p('<parameter name="video-size" type="uint8" default="0" min="0" max="3"><description>d</description>'
                 '</parameter>'), "video-size", set()),
    ("CDF119", p('<parameter name="X" type="uint8" min="0" max="3"><description>d</description></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF120", p('<parameter name="X" type="uint8" default="300" min="0" max="3"><description>d</description>'
                 '</parameter>'), "X", {"mavsdk", "strict"}),
    ("CDF120", p('<parameter name="X" type="uint32" default="0"><description>d</description><options>'
                 '<option name="a" value="zero"/><option name="b" value="0"/></options></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF121", p('<parameter name="X" type="uint32" default="0"><description>d</description><options>'
                 '<option name="a" value="0"/><option name="b" value="3000000000"/></options></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF122", p('<parameter name="X" type="uint8" default="0"><description>d</description>'
                 '<option name="a" value="0"/></parameter>'), "X", {"mavsdk", "strict"}),
    ("CDF123", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"/><option value="1"/></options></parameter>'), "X",
     {"qgc", "mavsdk", "strict"}),
    ("CDF124", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"/><option name="b" value="1"/><option name="c" value="1"/></options>'
                 '</parameter>'), "X", {"strict"}),
    ("CDF125", p('<parameter name="X" type="uint8" default="5"><description>d</description><options>'
                 '<option name="a" value="0"/></options></parameter>'), "X", {"mavsdk", "strict"}),
    ("CDF126", p('<parameter name="X" type="bool" default="0"><description>d</description><options>'
                 '<option name="off" value="0"><exclusions><exclude>WW_LAYOUT</exclude></exclusions></option>'
                 '<option name="on" value="1"/></options></parameter>'), "X", set()),
    ("CDF127", p('<parameter name="X" type="float" default="1.5"><description>d</description></parameter>'), "X",
     {"mavsdk", "strict"}),
    ("CDF128", p('<parameter name="X" type="int32" default="0" min="5" max="1"><description>d</description>'
                 '</parameter>'), "X", {"strict"}),
    ("CDF129", p('<parameter name="X" type="int32" default="9" min="0" max="4"><description>d</description>'
                 '</parameter>'), "X", set()),
    ("CDF130", p('<parameter name="X" type="uint8" default="0" min="0" max="3" control="false">'
                 '<description>d</description></parameter>'), "X", set()),
    ("CDF131", p('<parameter name="X" type="uint8" default="0" min="0" max="3" readonly="1" writeonly="1">'
                 '<description>d</description></parameter>'), "X", {"mavsdk", "strict"}),
    ("CDF132", p('<parameter name="X" type="custom"><description>d</description></parameter>'), "X", set()),
    ("CDF133", p('<parameter name="X" type="elapsedSeconds" default="0" min="0" max="9"><description>d</description>'
                 '</parameter>'), "X", {"mavsdk", "strict"}),
    ("CDF200", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"><exclusions><exclusions><exclude>WW_LAYOUT</exclude></exclusions>'
                 '</exclusions></option></options></parameter>'), "X", {"strict"}),
    ("CDF201", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"><exclusions><exclude>NOPE</exclude></exclusions></option></options>'
                 '</parameter>'), "X", set()),
    ("CDF202", p('<parameter name="X" type="uint8" default="0" min="0" max="3"><description>d</description>'
                 '<updates><update>NOPE</update></updates></parameter>'), "X", {"qgc", "strict"}),
    ("CDF203", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"><parameterranges><parameterrange parameter="NOPE">'
                 '<roption name="r" value="0"/></parameterrange></parameterranges></option></options></parameter>'),
     "X", {"qgc", "mavsdk", "strict"}),
    ("CDF204", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"><parameterranges><parameterrange parameter="WW_LAYOUT">'
                 '<roption name="r" value="7"/></parameterrange></parameterranges></option></options></parameter>'),
     "X", set()),
    ("CDF205", p('<parameter name="X" type="uint8" default="0"><description>d</description><options>'
                 '<option name="a" value="0"><parameterranges><parameterrange parameter="WW_LAYOUT" '
                 'condition="CAM_MODE = 1"><roption name="r" value="0"/></parameterrange></parameterranges></option>'
                 '</options></parameter>'), "X", set()),
    ("CDF206", p('<parameter name="X" type="uint8" default="1"><description>d</description><options>'
                 '<option name="a" value="01"><exclusions><exclude>WW_LAYOUT</exclude></exclusions></option>'
                 '</options></parameter>'), "X", set()),
    ("CDF207", p('<parameter name="X" type="float" default="1" min="0" max="2" decimalplaces="2">'
                 '<description>d</description></parameter>'), "X", set()),
    ("CDF208", doc(GOOD_PARAMS.replace('control="0"', 'control="1"', 1)), "CAM_MODE", set()),
    ("CDF209", p('<parameter name="CAM_ISO" type="custom" control="0"><description>d</description></parameter>'),
     "CAM_ISO", set()),
    ("CDF210", doc(GOOD_PARAMS, extra='<localization><locale name="de"><strings original="Palette" '
                                      'translated="P"/></locale></localization>'), None, set()),
    ("CDF211", doc(GOOD_PARAMS, extra="<videostreams><stream/></videostreams>"), None, set()),
    ("CDF213", p('<parameter name="X" type="uint8" default="0" readonly="1"><description>d</description><options>'
                 '<option name="a" value="0"/></options></parameter>'), "X", set()),
    ("CDF214", doc(GOOD_PARAMS, definition='<definition version="1"><model>a/b</model><vendor>v</vendor></definition>'),
     None, set()),
    ("CDF007", doc(GOOD_PARAMS, head='<?xml version="1.0" encoding="ISO-8859-1"?>\n'), None, set()),
    ("CDF008", doc(GOOD_PARAMS, head='<?xml version="1.0" encoding="UTF-16"?>\n').decode().encode("utf-16"), None,
     {"mavsdk", "strict"}),
    ("CDF009", doc(GOOD_PARAMS, head='<?xml version="1.0" encoding="UTF-16"?>\n'), None, {"qgc", "strict"}),
]


@pytest.mark.parametrize("rule_id,data,param,error_in", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_rule_fires_with_location_and_profile_severity(rule_id, data, param, error_in):
    for profile in PROFILES:
        report = validate_bytes(data, "t.xml", profile)
        mine = [f for f in report.findings if f.rule == rule_id]
        sev = next(r for r in RULES if r.id == rule_id).severity(profile)
        if sev is None:
            assert not mine
            continue
        assert mine, (profile, report.findings)
        assert all(f.severity == sev for f in mine)
        if rule_id not in ("CDF007", "CDF103"):
            assert all(isinstance(f.line, int) and f.line > 0 for f in mine), mine
        if param is not None:
            assert any(f.parameter == param for f in mine), mine
        assert (sev == "error") == (profile in error_in), (profile, sev)
        if profile in error_in:
            assert not report.valid


def test_every_rule_that_a_file_can_break_has_a_case():
    covered = {c[0] for c in CASES}
    # loading rules: tests/cdf/test_hostile.py; CDF100 generic; CDF212 needs 65536 parameters;
    # CDF3xx: test_camera_info_rules below; CDF001: CLI tests.
    untested = {r.id for r in RULES} - covered - {"CDF001", "CDF002", "CDF003", "CDF004", "CDF005", "CDF006",
                                                  "CDF100", "CDF212", "CDF300", "CDF301", "CDF302", "CDF303",
                                                  "CDF304"}
    assert untested == set()


def test_huge_sibling_lists_are_refused_before_the_schema_runs():
    # 65536 parameters (CDF212) cannot get past the node cap of CDF006: xmlschema needs ~35 s for them
    report = validate_bytes(doc("<parameter/>" * 65536), "many.xml", "qgc")
    assert [f.rule for f in report.errors] == ["CDF006"]


def test_strict_is_at_least_as_severe_as_both_other_profiles():
    for r in RULES:
        assert RANK[r.strict] >= max(RANK[r.qgc], RANK[r.mavsdk]), r.id


def test_rule_ids_unique_and_well_formed():
    ids = [r.id for r in RULES]
    assert len(ids) == len(set(ids))
    assert all(len(i) == 6 and i.startswith("CDF") and i[3:].isdigit() for i in ids)
    assert len({r.name for r in RULES}) == len(RULES)


def test_rules_md_matches_the_table():
    md = (REPO / "cdf" / "schema" / "RULES.md").read_text()
    assert md == render_markdown(), "regenerate: python -m cdf.validation.rules > cdf/schema/RULES.md"


def test_json_has_exactly_the_contract_fields():
    data = p('<parameter name="X" type="uint8" default="5"><description>d</description><options>'
             '<option name="a" value="0"/></options></parameter>')
    out = validate_bytes(data, "x.xml", "mavsdk").to_json()
    assert set(out) == {"file", "valid", "profile", "parameters", "findings"}
    assert out["valid"] is False and out["profile"] == "mavsdk" and out["parameters"] == 6
    for f in out["findings"]:
        assert set(f) == {"rule", "severity", "line", "parameter", "message"}
        assert f["severity"] in ("error", "warning", "info")
    json.dumps(out)


def test_valid_is_false_exactly_with_an_error():
    for data in (GOOD, doc(""), p('<parameter name="X" type="uint16" default="0" min="0" max="1">'
                                  "<description>d</description></parameter>")):
        for profile in PROFILES:
            r = validate_bytes(data, "f.xml", profile)
            assert r.valid == (not any(f.severity == "error" for f in r.findings))


def test_unknown_profile_is_a_cdf_error():
    with pytest.raises(CdfError):
        validate_bytes(GOOD, "g.xml", "px4")


def test_xz_detected_by_magic_not_name():
    r = validate_bytes(lzma.compress(GOOD, format=lzma.FORMAT_XZ), "looks-plain.xml")
    assert r.valid and r.parameters == 5


def test_camera_info_rules():
    info = CameraInfo(vendor_name="Workswell", model_name="WIRIS Enterprise", cam_definition_version=4,
                      cam_definition_uri="http://10.0.0.1/" + "x" * 130 + ".xml.xz",
                      param_types={"WW_LAYOUT": "uint32", "WW_PALETTE": "uint32", "WW_RECORD": "uint8"},
                      answered=frozenset({"CAM_MODE", "WW_PALETTE", "WW_LAYOUT"}))
    r = validate_bytes(GOOD, "g.xml", camera_info=info)
    by_rule = {}
    for f in r.findings:
        by_rule.setdefault(f.rule, []).append(f)
    assert "CDF300" in by_rule and "CDF301" in by_rule
    assert len(by_rule["CDF302"]) == 2  # too long, xz over http
    assert [f.parameter for f in by_rule["CDF303"]] == ["WW_LAYOUT"]  # bool travels as uint8: fine
    assert {f.parameter for f in by_rule["CDF304"]} == {"WW_EMISS", "WW_RECORD"}
    assert not r.valid  # wire type mismatch is an error
    ok = CameraInfo(vendor_name="Workswell", model_name="WIRIS Pro", cam_definition_version=3,
                    cam_definition_uri="http://10.0.0.1/wiris_pro_v3.xml")
    assert validate_bytes(GOOD, "g.xml", camera_info=ok).findings == ()


def test_devguide_example_fails_mavsdk_on_its_cam_vidfmt_default():
    data = (CORPUS / "devguide" / "camera_definition_example.xml").read_bytes()
    errs = validate_bytes(data, "ex.xml", "mavsdk").errors
    assert [(f.rule, f.parameter) for f in errs] == [("CDF125", "CAM_VIDFMT")]
    assert validate_bytes(data, "ex.xml", "qgc").valid


# ---- CLI ---------------------------------------------------------------------------------------------------

def test_cli_text_output_and_exit_codes(tmp_path):
    good, bad = tmp_path / "good.xml", tmp_path / "bad.xml"
    good.write_bytes(GOOD)
    bad.write_bytes(p('<parameter name="X" type="uint8" default="5"><description>d</description><options>'
                      '<option name="a" value="0"/></options></parameter>'))
    runner = CliRunner()
    r = runner.invoke(cli, ["cdf", "validate", str(good)])
    assert r.exit_code == 0, r.output
    assert f"{good}: valid (strict)" in r.output
    r = runner.invoke(cli, ["cdf", "validate", str(good), str(bad)])
    assert r.exit_code == 1
    line = next(x for x in r.output.splitlines() if " CDF125 " in x)
    assert line.startswith(f"{bad}:") and ": ERROR CDF125 [X] default" in line
    assert f"{bad}: INVALID (strict)" in r.output
    r = runner.invoke(cli, ["cdf", "validate", "--profile", "qgc", str(bad)])
    assert r.exit_code == 0 and "WARNING CDF125 [X]" in r.output


def test_cli_json_one_object_per_file(tmp_path):
    good = tmp_path / "good.xml"
    good.write_bytes(GOOD)
    missing = tmp_path / "missing.xml"
    r = CliRunner().invoke(cli, ["cdf", "validate", "--json", "--profile", "mavsdk", str(good), str(missing)])
    assert r.exit_code == 1
    objs = [json.loads(x) for x in r.output.splitlines()]
    assert [o["file"] for o in objs] == [str(good), str(missing)]
    assert objs[0]["valid"] is True and objs[0]["profile"] == "mavsdk" and objs[0]["parameters"] == 5
    assert objs[1]["valid"] is False and objs[1]["findings"][0]["rule"] == "CDF001"
    assert all(set(o) == {"file", "valid", "profile", "parameters", "findings"} for o in objs)


def test_cli_says_what_to_do_about_a_source_it_cannot_read(tmp_path):
    r = CliRunner().invoke(cli, ["cdf", "validate", str(tmp_path)])
    assert r.exit_code == 1
    line = next(x for x in r.output.splitlines() if " CDF001 " in x)
    assert line.startswith(f"{tmp_path}: ERROR CDF001 is a directory") and "(hint: name the .xml" in line
    r = CliRunner().invoke(cli, ["cdf", "validate", "--json", str(tmp_path)])
    assert "(hint: " in json.loads(r.output)["findings"][0]["message"]


def test_cli_usage_errors_exit_2():
    runner = CliRunner()
    assert runner.invoke(cli, ["cdf", "validate"]).exit_code == 2
    assert runner.invoke(cli, ["cdf", "validate", "--profile", "px4", "x.xml"]).exit_code == 2


def test_cli_help_stays_light():
    code = ("import sys\nfrom click.testing import CliRunner\nfrom wiris_tools.cli import cli\n"
            "r = CliRunner().invoke(cli, ['cdf', 'validate', '--help'])\nassert r.exit_code == 0\n"
            "print(','.join(m for m in ('lxml', 'xmlschema') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO)
    assert out.stdout.strip() == ""


def test_misplaced_element_points_at_the_element_itself():
    data = doc('<parameter name="X" type="uint8" default="0">\n<description>d</description>\n<options>\n'
               '<option name="a" value="0">\n<exclusions>\n<exclusions><exclude>X</exclude></exclusions>\n'
               "</exclusions>\n</option>\n</options>\n</parameter>")
    (f,) = [f for f in findings(data) if f.rule == "CDF200"]
    assert f.line == 10 and f.parameter == "X" and f.severity == "error"


def test_every_reference_rule_is_implemented_by_some_rule():
    # ../shared/reference/camera-definition-files.md §C lists 35 rules; each maps to at least one rule id
    import re

    cited = set()
    for r in RULES:
        cited |= {int(n) for n in re.findall(r"§C(\d+)", r.ref)}
    assert cited >= set(range(1, 36)), sorted(set(range(1, 36)) - cited)


def test_stray_text_is_info_with_its_line():
    data = doc(GOOD_PARAMS.replace("<options><option name=\"Photo\"", "<options>oops\n<option name=\"Photo\"", 1))
    (f,) = [f for f in findings(data) if f.rule == "CDF211"]
    assert f.severity == "info" and f.line == 7 and f.parameter == "CAM_MODE" and "oops" in f.message


def test_unknown_attribute_is_reported_once_at_its_first_occurrence():
    data = doc('<parameter name="X" type="uint8" default="0">\n<description>d</description>\n<options>\n'
               '<option name="a" value="0" colour="red"/>\n<option name="b" value="1" colour="blue"/>\n'
               "</options>\n</parameter>")
    (f,) = [f for f in findings(data) if f.rule == "CDF211"]
    assert f.line == 8 and f.parameter == "X" and "option@colour" in f.message


def test_unknown_attribute_on_options_with_children_is_reported_at_the_first():
    data = doc('<parameter name="X" type="uint8" default="0">\n<description>d</description>\n<options>\n'
               '<option name="a" value="0" colour="red">\n<exclusions><exclude>Y</exclude></exclusions>\n</option>\n'
               '<option name="b" value="1" colour="blue">\n<exclusions><exclude>Y</exclude></exclusions>\n</option>\n'
               '<option name="c" value="2" colour="green"/>\n</options>\n</parameter>\n'
               '<parameter name="Y" type="uint8" default="0"><description>e</description>\n'
               '<options><option name="a" value="0"/></options></parameter>')
    (f,) = [f for f in findings(data) if f.rule == "CDF211"]
    assert f.line == 8 and f.parameter == "X" and "option@colour" in f.message


def test_the_xsd_states_the_parameter_types_of_the_one_type_table():
    # mavlinkcamera.xsd spells the types out for xmlschema; cdf/paramtypes.py is what the code reads
    from lxml import etree

    from cdf.paramtypes import INT_RANGES, KNOWN_TYPES, NUMERIC_TYPES
    from cdf.validation.schema import XSD_PATH

    xs = {"xs": "http://www.w3.org/2001/XMLSchema"}
    xsd = etree.parse(str(XSD_PATH))
    names = xsd.xpath("//xs:simpleType[@name='paramTypeName']//xs:enumeration/@value", namespaces=xs)
    assert tuple(names) == KNOWN_TYPES
    alternatives = xsd.xpath("//xs:alternative/@test", namespaces=xs)
    assert sorted(t.split("'")[1] for t in alternatives) == sorted(NUMERIC_TYPES)
    for ptype, (lo, hi) in INT_RANGES.items():
        if ptype == "bool":
            continue  # lex_bool is the pattern [01]
        lex = xsd.xpath(f"//xs:simpleType[@name='lex_{ptype}']/xs:restriction", namespaces=xs)[0]
        assert (int(lex.find("xs:minInclusive", xs).get("value")),
                int(lex.find("xs:maxInclusive", xs).get("value"))) == (lo, hi), ptype
