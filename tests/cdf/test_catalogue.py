"""The catalogue tables load, hold the manual's facts, and refuse broken tables."""

import math
import shutil

import pytest
import yaml
from click.testing import CliRunner

from cdf.catalogue import TABLES_DIR, catalogue, load_catalogue
from cdf.errors import CdfError

WORKSWELL = ["wiris-pro", "wiris-pro-sc", "wiris-security", "wiris-agro", "gis-320", "wiris-enterprise"]


def test_every_family_of_the_manual_and_rededge_is_there():
    ids = set(catalogue().ids)
    assert set(WORKSWELL) | {"rededge-mx", "rededge-m"} <= ids


@pytest.mark.parametrize("cam_id", WORKSWELL)
def test_chapter_7_enumerators_are_complete(cam_id):
    cam = catalogue().get(cam_id)
    expected = {  # manual chapter 7.2: enumerator -> values
        "storage": {0, 1, 2}, "main_camera": {0, 1}, "layout": {0, 1, 2, 3}, "visible_mode": {0, 1, 2, 3},
        "stream_id": {0, 1, 2}, "video_id": {1, 2, 4}, "capture_flags": {1, 2, 4, 8},
        "isotherm_mode": {0, 1, 2, 3, 4}, "range_mode": {0, 1, 2}, "sights": {2, 4, 8, 16, 32},
        "menu_action": {1, 2, 3, 4}, "isotherm_color": {0, 1, 2},
    }
    for eid, values in expected.items():
        assert {o.value for o in cam.enum(eid).options} == values, eid


def test_model_differences_follow_the_manual():
    pro, sec = catalogue().get("wiris-pro"), catalogue().get("wiris-security")
    # §6.3.2.13: USER_1 means range/emissivity on the Pro and range stabilisation/rejection on the Security
    assert pro.setting("emissivity").command.cmd == "MAV_CMD_USER_1" and pro.setting("emissivity").command.param == 5
    assert sec.setting("emissivity") is None
    assert sec.setting("hot_rejection_pct").command.param == 2
    # §6.3.2.14: alarm limits in °C on radiometric cameras, % on the non-radiometric Security
    assert pro.setting("alarm_above").unit == "°C" and sec.setting("alarm_above").unit == "%"
    # CWSI sights only on the Agro
    assert all("cwsi" not in o.key for o in pro.setting("sights").options)
    assert any("cwsi" in o.key for o in catalogue().get("wiris-agro").setting("sights").options)
    # §6.2: camera protocol listed for Pro, Pro SC, Security, GIS; not Agro or Enterprise
    assert [c for c in WORKSWELL if catalogue().get(c).camera_protocol] == ["wiris-pro", "wiris-pro-sc",
                                                                            "wiris-security", "gis-320"]


def test_offsets_and_keep_rules_of_set_camera_mode():
    layout = catalogue().get("wiris-pro").setting("layout")
    assert layout.command.cmd == "MAV_CMD_SET_CAMERA_MODE" and layout.command.param == 5
    assert layout.command.encode(3) == 4.0            # "Layout increased by 1"
    assert layout.command.decode(0.0) is None          # 0 keeps
    assert layout.command.decode(math.nan) is None     # NaN keeps
    assert layout.command.decode(1.0) == 0
    emissivity = catalogue().get("wiris-pro").setting("emissivity")
    assert emissivity.command.decode(0.0) == 0.0       # only NaN keeps here


def test_flag_settings_check_and_refuse_exclusive_combinations():
    pro = catalogue().get("wiris-pro")
    assert pro.setting("capture").check(["radiometric_jpeg", "visible_jpeg"]) == 0x09
    with pytest.raises(CdfError, match="cannot be combined"):
        pro.setting("video").check(["thermal_sequence", "thermal_encoded"])   # §7.2.6
    with pytest.raises(CdfError, match="not a choice") as err:
        pro.setting("range_mode").check("manuel")
    assert "manual" in err.value.hint


def test_every_cdf_setting_is_generatable():
    for cam in catalogue().cameras:
        for s in cam.cdf_settings:
            assert len(s.param) <= 16
            assert s.type != "uint16" or not cam.has_cdf   # MAVSDK mishandles uint16 (reference §D)
            assert s.options or (s.min is not None and s.max is not None)


def test_optics_are_sourced_or_marked(tmp_path):
    for cam in catalogue().cameras:
        for imager in cam.imagers:
            if imager.known:
                assert imager.sources or imager.assumed, (cam.id, imager.id)
            else:
                assert imager.note, (cam.id, imager.id)


def test_broken_table_is_refused_with_its_name(tmp_path):
    for f in TABLES_DIR.glob("*.yaml"):
        shutil.copy(f, tmp_path)
    p = tmp_path / "wiris-pro.yaml"
    p.write_text(p.read_text().replace("overrides:\n", "overrides:\n  nosuch: {unit: x}\n"))
    with pytest.raises(CdfError, match="nosuch") as err:
        load_catalogue(tmp_path)
    assert "wiris-pro.yaml" in str(err.value)
    assert err.value.hint and "overrides" in err.value.hint


def _text(change):
    """A break written on the table's text."""
    def apply(path):
        path.write_text(change(path.read_text(encoding="utf-8")), encoding="utf-8")
    return apply


def _data(change):
    """A break made on the table's data (change mutates it), written back as YAML."""
    def apply(path):
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        change(data)
        path.write_text(yaml.safe_dump(data, allow_unicode=True, sort_keys=False), encoding="utf-8")
    return apply


def _setting(data, key):
    return next(s for s in data["settings"] if s["key"] == key)


def _override(key, **values):
    return _data(lambda d: d["overrides"].update({key: values}))


RE, PRO = "rededge.yaml", "wiris-pro.yaml"   # RE stands alone; PRO extends workswell.yaml

# (table, break, message, where: "{dir}" is the tables directory, words the hint must hold)
BROKEN_TABLES = {
    "not-a-mapping": (RE, _text(lambda t: "- a list\n- not a mapping\n"), "must be a mapping", "{dir}/" + RE,
                      "models:"),
    "empty-file": (RE, _text(lambda t: ""), "must be a mapping", "{dir}/" + RE, "models:"),
    "yaml-syntax": (RE, _text(lambda t: t.replace("vendor: MicaSense", "vendor: [MicaSense")),
                    "cannot parse catalogue table", "{dir}/" + RE, "line and column"),
    "duplicate-enumerator-value": (RE, _data(lambda d: d["enums"]["raw_format"]["options"][1].update(value=0)),
                                   "enumerator raw_format: duplicate value or key", RE, "enums: raw_format"),
    "duplicate-enumerator-key": (RE, _data(lambda d: d["enums"]["raw_format"]["options"][1].update(key="tiff")),
                                 "enumerator raw_format: duplicate value or key", RE, "`key:`"),
    "unknown-enumerator": (RE, _data(lambda d: _setting(d, "raw_format").update(enum="raw_formats")),
                           "unknown enumerator 'raw_formats'", RE, "did you mean 'raw_format'"),
    "enumerator-without-flags": (PRO, _override("capture", flags="layout"), "'layout' is not a flag enumerator",
                                 PRO, "flags: true"),
    "no-flag-enumerator": (RE, _data(lambda d: (_setting(d, "raw_format").pop("enum"),
                                                _setting(d, "raw_format").update(flags="raw_format"))),
                           "'raw_format' is not a flag enumerator", RE, "flags: true"),
    "no-options-no-range": (RE, _data(lambda d: (_setting(d, "wifi").pop("min"), _setting(d, "wifi").pop("max"))),
                            "setting wifi: needs options or min and max", RE, "`min:` and `max:`"),
    "default-outside-range": (RE, _data(lambda d: _setting(d, "wifi").update(default=2)),
                              "setting wifi: default 2 outside 0..1", RE, "between 0 and 1"),
    "default-not-an-option": (RE, _data(lambda d: _setting(d, "raw_format").update(default=5)),
                              "setting raw_format: default 5 is not among its options", RE, "0, 1"),
    "default-left-out": (PRO, _override("sights", without=["cwsi_values", "temperatures"]),
                         "setting sights: default 2 is not among its options", PRO, "`without:`"),
    "param-too-long": (RE, _data(lambda d: _setting(d, "wifi").update(param="A_VERY_LONG_NAME_X")),
                       "PARAM_EXT name 'A_VERY_LONG_NAME_X' must be 1–16", RE, "at most 16"),
    "param-not-ascii": (RE, _data(lambda d: _setting(d, "wifi").update(param="WIFI_É")),
                        "PARAM_EXT name 'WIFI_É' must be 1–16 ASCII", RE, "ASCII letters"),
    "unknown-type": (RE, _data(lambda d: _setting(d, "wifi").update(type="bool")),
                     "type 'bool' is not a definition type", RE, "uint32"),
    "value-does-not-fit": (RE, _data(lambda d: _setting(d, "wifi").update(type="uint8", max=300)),
                           "setting wifi: a value does not fit uint8", RE, "0..255"),
    "unknown-group": (PRO, _data(lambda d: d.update(groups=["visible", "dispaly"])),
                      "unknown setting group 'dispaly'", PRO, "did you mean 'display'"),
    "group-without-extends": (RE, _data(lambda d: d.update(groups=["visible"])),
                              "unknown setting group 'visible'", RE, "extends:"),
    "unknown-override": (PRO, _override("emisivity", default=0.9), "overrides name unknown settings: emisivity",
                         PRO, "did you mean 'emissivity'"),
    "duplicate-param": (RE, _data(lambda d: d["settings"].append(dict(_setting(d, "wifi"), key="wifi_2"))),
                        "duplicate PARAM_EXT name: wifi", RE, "`param:`"),
    "duplicate-key": (RE, _data(lambda d: d["settings"].append(dict(_setting(d, "wifi"), param="WIFI_2"))),
                      "duplicate setting key: wifi", RE, "`key:`"),
    "hides-a-setting-key": (PRO, _override("layout", hides={0: ["blend_opacity"]}),
                            "setting layout: hides unknown blend_opacity", PRO, "'BLEND_OPACITY'"),
    "unknown-command": (PRO, _override("layout", command={"cmd": "MAV_CMD_SET_CAMERA_MOD", "param": 5}),
                        "command MAV_CMD_SET_CAMERA_MOD is not in the commands table", PRO,
                        "did you mean 'MAV_CMD_SET_CAMERA_MODE'"),
    "no-commands-table": (RE, _data(lambda d: _setting(d, "wifi").update(command={"cmd": "MAV_CMD_USER_1"})),
                          "command MAV_CMD_USER_1 is not in the commands table", RE, "`commands:`"),
    "unknown-when-setting": (RE, _data(lambda d: _setting(d, "iso")["command"].update(when={"DIGICAM_MODE": 2})),
                             "setting iso: 'when' names unknown setting DIGICAM_MODE", RE, "'exposure_mode'"),
    "camera-id-twice-in-a-table": (RE, _data(lambda d: d["models"].append(dict(d["models"][0]))),
                                   "camera id used twice: rededge-mx", "{dir}", RE),
    "camera-id-twice-in-two-tables": (RE, _data(lambda d: d["models"][0].update(id="wiris-pro")),
                                      "camera id used twice: wiris-pro", "{dir}", PRO),
    # these crashed as internal errors (FileNotFoundError, UnicodeDecodeError, KeyError, OverflowError)
    "extends-unknown-table": (PRO, _text(lambda t: t.replace("extends: workswell", "extends: workswel", 1)),
                              "no such catalogue table", "{dir}/workswel.yaml", "`extends:`"),
    "not-utf8": (RE, lambda p: p.write_bytes(p.read_bytes() + b"# \xff\n"), "cannot read catalogue table",
                 "{dir}/" + RE, "UTF-8"),
    "enumerator-without-options": (RE, _data(lambda d: d["enums"]["raw_format"].pop("options")),
                                   "missing key 'options'", RE, "enums need options:"),
    "setting-without-key": (RE, _data(lambda d: _setting(d, "wifi").pop("key")), "missing key 'key'", RE,
                            "settings need key:"),
    "integer-setting-max-inf": (RE, _data(lambda d: _setting(d, "wifi").update(type="uint8", max=float("inf"))),
                                "OverflowError", RE, "compare the entry"),
}


@pytest.mark.parametrize("case", BROKEN_TABLES)
def test_a_broken_table_says_where_and_what_to_do(tmp_path, case):
    table, breaks, message, where, hint_has = BROKEN_TABLES[case]
    for name in (RE, PRO, "workswell.yaml"):
        shutil.copy(TABLES_DIR / name, tmp_path)
    load_catalogue(tmp_path)   # the copies load
    breaks(tmp_path / table)
    with pytest.raises(CdfError) as err:
        load_catalogue(tmp_path)
    assert message in err.value.message
    assert err.value.where == where.format(dir=tmp_path)
    assert err.value.hint and hint_has in err.value.hint, err.value.hint
    assert str(err.value).endswith(f"\n  hint: {err.value.hint}")


def test_models_command_lists_the_catalogue():
    from wiris_tools.cli import cli

    result = CliRunner().invoke(cli, ["cdf", "models", "--json"])
    assert result.exit_code == 0
    import json

    rows = json.loads(result.output)["models"]
    pro = next(r for r in rows if r["id"] == "wiris-pro")
    assert pro["component_ids"] == [100, 101, 102, 103, 104, 105]
    assert pro["imagers"][0]["resolution_px"] == [640, 512]
    text = CliRunner().invoke(cli, ["cdf", "models"])
    assert text.exit_code == 0 and "wiris-security" in text.output
