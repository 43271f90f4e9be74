"""The catalogue tables load, hold the manual's facts, and refuse broken tables."""

import math
import shutil

import pytest
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
