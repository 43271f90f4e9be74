"""Generated camera definitions: content from the catalogue, formats both parsers accept, localisation that
survives QGroundControl's whole-file string replacement, strict validity, and refusals of unsafe input."""

from __future__ import annotations

import dataclasses
import re

import pytest
from lxml import etree

from cdf.catalogue import INTEGER_RANGES, Option, catalogue
from cdf.errors import CdfError
from cdf.generate import (Locale, definition_file_name, definition_view, definition_xml, definition_xmls,
                          load_locales)

MODELS = [c.id for c in catalogue().cameras if c.has_cdf]
INT = re.compile(r"-?(0|[1-9][0-9]*)")


def parse(data: bytes):
    return etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False))


def params(root) -> dict:
    return {p.get("name"): p for p in root.find("parameters").findall("parameter")}


def structure(root) -> dict:
    """Everything of a definition except descriptions and option names (what localisation must not touch)."""
    d = root.find("definition")
    out = {"version": d.get("version"), "model": d.findtext("model"), "vendor": d.findtext("vendor"), "params": []}
    for p in root.find("parameters").findall("parameter"):
        opts = p.find("options")
        out["params"].append((
            tuple(sorted((k, v) for k, v in p.attrib.items())),
            tuple(u.text for u in p.iterfind("updates/update")),
            tuple((o.get("value"), tuple(e.text for e in o.iterfind("exclusions/exclude")))
                  for o in (opts if opts is not None else ())),
        ))
    return out


def texts(root) -> list[tuple[str, str, list[str]]]:
    return [(p.get("name"), p.findtext("description"), [o.get("name") for o in p.iterfind("options/option")])
            for p in root.find("parameters").findall("parameter")]


def qgc_localize(data: bytes, system_locale: str) -> bytes:
    """QGroundControl's localisation (VehicleCameraControl.cc _handleLocalization/_replaceLocaleStrings,
    reference §3.4): pick the locale whose lower-cased, '-'->'_' name equals the system locale, else the
    first that starts with its first three characters; then, string after string, replace `"original"`
    and `>original<` in the raw bytes of the whole file. Nothing happens for en_US."""
    loc = system_locale.lower().replace("-", "_")
    if loc == "en_us":
        return data
    root = parse(data)
    locales = list(root.iterfind("localization/locale"))
    chosen = next((e for e in locales if e.get("name", "").lower().replace("-", "_") == loc), None)
    if chosen is None:
        chosen = next((e for e in locales if e.get("name", "").lower().replace("-", "_").startswith(loc[:3])), None)
    if chosen is None:
        return data
    for s in chosen.iterfind("strings"):
        o, t = s.get("original").encode(), s.get("translated").encode()
        data = data.replace(b'"' + o + b'"', b'"' + t + b'"').replace(b">" + o + b"<", b">" + t + b"<")
    return data


# --------------------------------------------------------------------------------------------- content

@pytest.mark.parametrize("cam_id", MODELS)
def test_rebuild_is_byte_identical(cam_id):
    cam = catalogue().get(cam_id)
    assert definition_xml(cam) == definition_xml(cam)
    assert definition_xmls()[cam_id] == definition_xml(cam)


@pytest.mark.parametrize("cam_id", MODELS)
def test_every_setting_and_option_of_the_catalogue_is_in_the_file(cam_id):
    cam = catalogue().get(cam_id)
    root = parse(definition_xml(cam))
    assert root.tag == "mavlinkcamera"
    d = root.find("definition")
    assert (d.get("version"), d.findtext("model"), d.findtext("vendor")) == (
        str(cam.definition_version), cam.model, cam.vendor)
    ps = params(root)
    assert list(ps) == [s.param for s in cam.cdf_settings]
    assert "CAM_MODE" not in ps   # the lead's decision: the camera takes MAV_CMD_SET_CAMERA_MODE
    for s in cam.cdf_settings:
        p = ps[s.param]
        assert p.get("type") == s.type
        assert p.findtext("description") == (f"{s.label} ({s.unit})" if s.unit else s.label)
        options = p.findall("options/option")
        if s.options:
            assert [(int(o.get("value")), o.get("name")) for o in options] == [(o.value, o.name) for o in s.options]
            assert int(p.get("default")) == s.default
            assert p.get("min") is None and p.get("max") is None
        else:
            assert options == []
            assert float(p.get("min")) == s.min and float(p.get("max")) == s.max
            assert float(p.get("step")) == s.step and float(p.get("default")) == s.default
        assert p.get("unit") == s.unit
        if s.decimals is not None and not s.is_integer:
            assert p.get("decimalPlaces") == str(s.decimals)
        assert p.get("decimalplaces") is None


def test_settings_left_out_of_the_definition_stay_out():
    cam = catalogue().get("wiris-pro")
    assert cam.setting("aperture") is not None and not cam.setting("aperture").in_cdf
    assert "CAM_APERTURE" not in params(parse(definition_xml(cam)))


@pytest.mark.parametrize("cam_id", MODELS)
def test_values_are_what_both_parsers_read_the_same_way(cam_id):
    root = parse(definition_xml(catalogue().get(cam_id)))
    for name, p in params(root).items():
        assert len(name) <= 16 and name.isascii()
        ptype = p.get("type")
        assert ptype not in ("uint16", "bool", "string", "custom")
        values = [p.get(k) for k in ("default", "min", "max", "step") if p.get(k) is not None]
        values += [o.get("value") for o in p.iterfind("options/option")]
        for v in values:
            if ptype in INTEGER_RANGES:
                assert INT.fullmatch(v), (name, v)   # canonical decimal: no '+', '.', exponent, leading zero
                lo, hi = INTEGER_RANGES[ptype]
                assert lo <= int(v) <= hi
            else:
                assert re.fullmatch(r"-?[0-9]+(\.[0-9]+)?", v), (name, v)   # no exponent
        opts = [o.get("value") for o in p.iterfind("options/option")]
        if opts:
            assert opts.count(p.get("default")) == 1 and len(set(opts)) == len(opts)
        else:
            assert float(p.get("min")) <= float(p.get("default")) <= float(p.get("max"))


def test_floats_are_written_as_qgc_renders_them():
    ps = params(parse(definition_xml(catalogue().get("wiris-pro"))))
    # decimalPlaces 1 -> QGC shows 60.0; the XML says the same (rule 25)
    assert ps["RANGE_MAX_C"].get("default") == "60.0"
    assert ps["EMISSIVITY"].get("default") == "0.95" and ps["EMISSIVITY"].get("step") == "0.01"


def test_exclusions_follow_the_catalogue_hides():
    cam = catalogue().get("wiris-pro")
    ps = params(parse(definition_xml(cam)))
    rm = ps["RANGE_MODE"]
    excl = {o.get("name"): [e.text for e in o.iterfind("exclusions/exclude")] for o in rm.iterfind("options/option")}
    # automatic range: the manual limits and the span are hidden; manual: the span; span: the manual limits
    assert excl["Automatic"] == ["RANGE_MAX_C", "RANGE_MIN_C", "SPAN_HALF_C", "SPAN_CENTER_C"]
    assert excl["Manual"] == ["SPAN_HALF_C", "SPAN_CENTER_C"]
    assert excl["Span"] == ["RANGE_MAX_C", "RANGE_MIN_C"]
    assert [u.text for u in rm.iterfind("updates/update")] == list(cam.setting("range_mode").updates)
    for s in cam.cdf_settings:
        hides = dict(s.hides)
        for o in ps[s.param].iterfind("options/option"):
            assert [e.text for e in o.iterfind("exclusions/exclude")] == list(hides.get(int(o.get("value")), ()))
    # exclusions only on integer-typed parameters (QGC compares option text with the rendered value)
    for p in ps.values():
        if p.find("options/option/exclusions") is not None:
            assert p.get("type") in INTEGER_RANGES


def test_flag_sets_offer_every_allowed_combination():
    cam = catalogue().get("wiris-pro")
    ps = params(parse(definition_xml(cam)))
    video = {int(o.get("value")): o.get("name") for o in ps["VIDEO_ID"].iterfind("options/option")}
    # thermal sequence (1) and thermal encoded (2) cannot be combined (§7.2.6)
    assert 3 not in video and 7 not in video
    assert video[5] == "Thermal sequence + Visible encoded"
    capture = [int(o.get("value")) for o in ps["CAPTURE_FMT"].iterfind("options/option")]
    assert capture == list(range(1, 16))


def test_manual_sections_are_in_comments_and_no_entities_anywhere():
    data = definition_xml(catalogue().get("wiris-pro"))
    text = data.decode("utf-8")
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>\n')
    assert "<!DOCTYPE" not in text and "&" not in text
    assert "<!-- RANGE_MODE: plan setting range_mode; manual §6.3.2.13, §7.2.9; sent as MAV_CMD_USER_1 param 1 -->" in text
    assert "CAM_MODE" in text.split("-->")[0]   # the header says why there is none


def test_file_name_is_vendor_model_version():
    assert definition_file_name(catalogue().get("wiris-pro")) == "workswell_wiris-pro_v1.xml"
    assert definition_file_name(catalogue().get("gis-320")) == "workswell_gis-320_v1.xml"


# ------------------------------------------------------------------------------------------- validity

@pytest.mark.parametrize("cam_id", MODELS)
def test_strict_profile_finds_nothing(cam_id):
    validation = pytest.importorskip("cdf.validation")
    cam = catalogue().get(cam_id)
    info = validation.CameraInfo(vendor_name=cam.vendor, model_name=cam.model,
                                 cam_definition_version=cam.definition_version)
    report = validation.validate_bytes(definition_xml(cam), f"{cam_id}.xml", "strict", camera_info=info)
    assert report.valid, [f.format(cam_id) for f in report.findings]
    assert report.findings == (), [f.format(cam_id) for f in report.findings]
    assert report.parameters == len(cam.cdf_settings)


# -------------------------------------------------------------------------------------------- locales

def test_locale_tables_cover_every_string_the_definitions_use():
    names = [loc.name for loc in load_locales()]
    assert {"cs_CZ", "de_DE"} <= set(names)
    for cam_id in MODELS:
        view = definition_view(catalogue().get(cam_id))
        assert view.missing_translations == (), (cam_id, view.missing_translations)


@pytest.mark.parametrize("cam_id", MODELS)
@pytest.mark.parametrize("system_locale", ["cs_CZ", "de_DE", "de_AT", "cs-cz"])
def test_qgc_string_replacement_only_translates_labels(cam_id, system_locale):
    cam = catalogue().get(cam_id)
    data = definition_xml(cam)
    before = parse(data)
    translated = qgc_localize(data, system_locale)
    assert translated != data
    after = parse(translated)   # still well-formed
    # no parameter name, type, value, range, unit, exclusion, update, model, vendor or version changed
    assert structure(after) == structure(before)
    # and every description and option name is the locale table's translation
    table = {loc.name: dict(loc.strings) for loc in load_locales()}["cs_CZ" if system_locale.lower().startswith("cs") else "de_DE"]
    for s, (name, desc, opts) in zip(cam.cdf_settings, texts(after)):
        assert name == s.param
        assert desc == table[s.label] + (f" ({s.unit})" if s.unit else "")
        expected = []
        for o in s.options:
            parts = [s.enum.by_key(k).name for k in o.key.split("+")] if s.flags else [o.name]
            expected.append(" + ".join(table[p] for p in parts))
        assert opts == expected


def test_qgc_english_or_unknown_locale_leaves_the_file_alone():
    data = definition_xml(catalogue().get("wiris-pro"))
    assert qgc_localize(data, "en_US") == data
    assert qgc_localize(data, "fr_FR") == data


def test_localization_block_is_well_formed():
    root = parse(definition_xml(catalogue().get("wiris-security")))
    locs = root.findall("localization/locale")
    assert [loc.get("name") for loc in locs] == sorted(loc.get("name") for loc in locs)
    assert len(root.findall("localization")) == 1
    for loc in locs:
        assert re.fullmatch(r"[a-z]{2}_[A-Z]{2}", loc.get("name"))
        originals = [s.get("original") for s in loc.iterfind("strings")]
        assert len(originals) == len(set(originals))
        for s in loc.iterfind("strings"):
            assert s.get("original") != s.get("translated")


def _with_setting(cam, key, **changes):
    settings = tuple(dataclasses.replace(s, **changes) if s.key == key else s for s in cam.settings)
    return dataclasses.replace(cam, settings=settings)


def test_an_option_name_equal_to_a_parameter_name_is_refused():
    cam = catalogue().get("wiris-pro")
    s = cam.setting("main_camera")
    bad = _with_setting(cam, "main_camera", options=(Option(0, "thermal", "LAYOUT"), s.options[1]))
    de = Locale("de_DE", (("LAYOUT", "Anordnung"),) + tuple(load_locales()[1].strings))
    with pytest.raises(CdfError, match="LAYOUT"):
        definition_xml(bad, [de])


def test_a_translation_that_is_another_original_is_refused():
    cam = catalogue().get("wiris-pro")
    # "Manual" -> "Automatic" would be turned into the translation of "Automatic" by the next string
    strings = tuple((o, "Automatic" if o == "Manual" else t) for o, t in load_locales()[1].strings)
    with pytest.raises(CdfError, match="one after another"):
        definition_xml(cam, [Locale("de_DE", strings)])


def test_text_that_needs_an_entity_is_refused():
    cam = catalogue().get("wiris-pro")
    with pytest.raises(CdfError, match="entity"):
        definition_xml(_with_setting(cam, "zoom", label="Zoom & focus"))


def test_missing_translations_stay_english_and_are_reported():
    cam = catalogue().get("wiris-pro")
    partial = Locale("de_DE", tuple((o, t) for o, t in load_locales()[1].strings if o != "Emissivity"))
    view = definition_view(cam, [partial])
    assert ("de_DE", "Emissivity") in view.missing_translations
    root = parse(qgc_localize(definition_xml(cam, [partial]), "de_DE"))
    assert params(root)["EMISSIVITY"].findtext("description") == "Emissivity"


# ------------------------------------------------------------------------------------------- refusals

def test_a_model_without_definition_is_refused_with_a_hint():
    with pytest.raises(CdfError) as err:
        definition_xml(catalogue().get("rededge-mx"))
    assert "no camera definition" in str(err.value) and err.value.hint


@pytest.mark.parametrize("change, match", [
    ({"type": "uint16"}, "uint16"),
    ({"param": "CAM_MODE"}, "CAM_MODE"),
    ({"param": "A_VERY_LONG_NAME_X"}, "1-16"),
    ({"label": ""}, "empty"),
])
def test_unsafe_settings_are_refused(change, match):
    cam = catalogue().get("wiris-pro")
    with pytest.raises(CdfError, match=match) as err:
        definition_xml(_with_setting(cam, "layout", **change))
    assert err.value.hint


# Table values the catalogue loader lets through but the generator refuses (or, the last, never sees).
@pytest.mark.parametrize("key, change, match, hint", [
    ("layout", {"label": "HDMI\tlayout"}, "control character", "one line"),
    ("layout", {"default": True}, "True is not a whole number for uint32", "not true or false"),
    ("layout", {"hides": ((7, ("BLEND_OPACITY",)),)}, r"hides names option values \[7\]", "0, 1, 2, 3"),
    ("capture", {"options": (Option(1, "a", "A"), Option(1, "b", "B"))}, "two options have the same value",
     "own bit"),
    ("blend_opacity", {"step": 0.5}, "0.5 is not a whole number for uint32", "`step:`"),
    ("zoom", {"step": 0}, "step 0 must be positive", "`step:`"),
    ("zoom", {"max": float("inf")}, "inf is not a finite number", ".inf"),
    ("zoom", {"default": 20.0}, "default 20.0 outside", "bug in wiris-tools"),
])
def test_unsafe_values_are_refused_with_a_hint(key, change, match, hint):
    cam = catalogue().get("wiris-pro")
    with pytest.raises(CdfError, match=match) as err:
        definition_xml(_with_setting(cam, key, **change))
    assert err.value.where == f"cdf/tables/wiris-pro.yaml: setting {key}"
    assert hint in err.value.hint, err.value.hint


def test_a_default_outside_the_options_is_refused():
    cam = catalogue().get("wiris-pro")
    with pytest.raises(CdfError, match="exactly one of the options") as err:
        definition_xml(_with_setting(cam, "layout", default=9))
    assert err.value.hint


def test_a_range_without_max_is_refused():
    cam = catalogue().get("wiris-pro")
    with pytest.raises(CdfError, match="min and max") as err:
        definition_xml(_with_setting(cam, "zoom", max=None))
    assert err.value.hint


@pytest.mark.parametrize("version", [0, 65536, None])
def test_definition_version_must_fit_uint16_and_not_be_zero(version):
    cam = dataclasses.replace(catalogue().get("wiris-pro"), definition_version=version)
    with pytest.raises(CdfError, match="definition_version") as err:
        definition_xml(cam)
    assert err.value.hint
    if version is None:
        with pytest.raises(CdfError, match="wiris-pro has no definition_version") as err:
            definition_file_name(cam)
        assert err.value.where == "wiris-pro.yaml" and "`definition_version:`" in err.value.hint


@pytest.mark.parametrize("name, text, match, hint", [
    ("de_DE.yaml", 'strings:\n  "Zoom": [Zoom\n', "cannot parse locale table", "line and column"),
    ("de_DE.yaml", "- Zoom\n- Zoom\n", "needs a mapping `strings:", "`strings:`"),
    ("de_DE.yaml", "strings:\n  Off: Aus\n", "both sides must be text", "quote"),
    ("de_DE.yaml", 'strings:\n  "Zoom": "Zoom\\tfaktor"\n', "control character", "one line"),
    ("de.yaml", "strings: {}\n", "is not ll_CC.yaml", "rename"),
])
def test_broken_locale_tables_are_refused_with_a_hint(tmp_path, name, text, match, hint):
    (tmp_path / name).write_text(text, encoding="utf-8")
    with pytest.raises(CdfError, match=match) as err:
        load_locales(tmp_path)
    assert err.value.where == str(tmp_path / name)
    assert hint in err.value.hint, err.value.hint


def test_a_numeric_option_name_cannot_be_translated():
    cam = catalogue().get("wiris-pro")
    s = cam.setting("main_camera")
    bad = _with_setting(cam, "main_camera", options=(s.options[0], Option(1, "visible", "1.5")))
    de = Locale("de_DE", (("1.5", "1,5"),) + tuple(load_locales()[1].strings))
    with pytest.raises(CdfError, match="numeric text '1.5'") as err:
        definition_xml(bad, [de])
    assert "locale table" in err.value.hint


# --------------------------------------------------------------------------------------- the loader

def test_template_loader_is_strict_and_escapes_xml_only():
    import jinja2

    from templates import _autoescape, environment

    env = environment()
    assert env.undefined is jinja2.StrictUndefined
    assert _autoescape("camera_definition.xml.j2") and _autoescape("preview.html.j2")
    assert not _autoescape("bridge.lua.j2")
    with pytest.raises(jinja2.UndefinedError):
        env.from_string("{{ nope }}").render()
    assert env.get_template("camera_definition.xml.j2") is env.get_template("camera_definition.xml.j2")


def test_xml_comment_filter_keeps_comments_well_formed():
    from templates import xml_comment

    assert "--" not in str(xml_comment("a -- b --- c-"))
    assert not str(xml_comment("ends-")).endswith("-")
    parse(f"<a><!-- {xml_comment('x -- y -')} --></a>".encode())


def test_output_does_not_depend_on_hash_seed_or_process():
    """Byte-identical across processes with different hash seeds (sets and dicts must not leak order)."""
    import hashlib
    import os
    import subprocess
    import sys

    code = ("import hashlib; from cdf.generate import definition_xmls; "
            "print(hashlib.sha256(b''.join(definition_xmls().values())).hexdigest())")
    digests = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env=dict(os.environ, PYTHONHASHSEED=seed)).stdout.strip() for seed in ("1", "4242")}
    assert digests == {hashlib.sha256(b"".join(definition_xmls().values())).hexdigest()}
