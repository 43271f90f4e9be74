"""Every generated definition in the real parsers: MAVSDK 4.1.0's camera plugin (fresh HOME per run) and
MAVProxy's CameraDefinition. Each must accept the file, drop nothing, and show every setting with every
option.

Both parsers hide excluded parameters given the current values (the emulated camera answers the file's
defaults), so hidden parameters are checked in *visibility variants*: the same definition with the
defaults of the hiding parameters moved to options that hide nothing new, chosen greedily until every
parameter has been visible once. The published file itself is always loaded too.
"""

from __future__ import annotations

import copy

import pytest
from lxml import etree

import peers
from cdf.catalogue import catalogue
from cdf.generate import definition_xml

MODELS = [c.id for c in catalogue().cameras if c.has_cdf]

pytestmark = [pytest.mark.peer]


def _root(data: bytes):
    return etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False))


def _hiders(root) -> dict[str, dict[str, set[str]]]:
    """parameter -> option value -> names it hides."""
    out = {}
    for p in root.iter("parameter"):
        table = {o.get("value"): {e.text for e in o.iterfind("exclusions/exclude")} for o in p.iterfind("options/option")}
        if any(table.values()):
            out[p.get("name")] = table
    return out


def _hidden(root, values: dict[str, str]) -> set[str]:
    return set().union(*(_hiders(root)[n][v] for n, v in values.items()))


def visibility_variants(data: bytes) -> list[tuple[bytes, set[str]]]:
    """(definition bytes, parameters visible in it): the file itself, then variants with other defaults."""
    root = _root(data)
    names = [p.get("name") for p in root.iter("parameter")]
    hiders = _hiders(root)
    defaults = {n: root.find(f".//parameter[@name='{n}']").get("default") for n in hiders}
    out = [(data, set(names) - _hidden(root, defaults))]
    uncovered = set(names) - out[0][1]
    while uncovered:
        choice = {n: min(table, key=lambda v: (len(table[v] & uncovered), len(table[v]), v))
                  for n, table in hiders.items()}
        visible = set(names) - _hidden(root, choice)
        assert visible & uncovered, f"no default combination shows {sorted(uncovered)}"
        variant = copy.deepcopy(root)
        for n, v in choice.items():
            variant.find(f".//parameter[@name='{n}']").set("default", v)
        out.append((etree.tostring(variant, xml_declaration=True, encoding="UTF-8"), visible))
        uncovered -= visible
    return out


def expected_options(root) -> dict[str, tuple]:
    """What a parser should list per parameter: the option values, or (min, max, step) for a range."""
    out = {}
    for p in root.iter("parameter"):
        opts = tuple(o.get("value") for o in p.iterfind("options/option"))
        out[p.get("name")] = opts if opts else tuple(float(p.get(k)) for k in ("min", "max", "step"))
    return out


def _same(listed: tuple, expected: tuple) -> bool:
    if expected and isinstance(expected[0], float):
        return len(listed) == 3 and all(abs(float(a) - b) < 1e-6 for a, b in zip(listed, expected))
    return tuple(listed) == expected


@pytest.mark.slow
def test_mavsdk_accepts_every_definition_and_lists_every_setting_with_all_options(tmp_path):
    jobs = []
    for cam_id in MODELS:
        data = definition_xml(catalogue().get(cam_id))
        for variant, visible in visibility_variants(data):
            jobs.append((cam_id, variant, visible))
    # one worker for all files; HOME and TMPDIR are this test's scratch dir, model names unique per file
    results = peers.mavsdk_load_definitions([j[1] for j in jobs], tmp_path)
    shown: dict[str, set[str]] = {m: set() for m in MODELS}
    for (cam_id, variant, visible), r in zip(jobs, results):
        assert r.accepted, (cam_id, r.outcome, r.log[-1500:])
        assert not r.crashed
        assert r.dropped == (), (cam_id, r.dropped)
        expected = expected_options(_root(variant))
        assert set(r.settings) == visible, (cam_id, sorted(set(r.settings) ^ visible))
        for name, listed in r.settings.items():
            assert _same(listed, expected[name]), (cam_id, name, listed, expected[name])
        shown[cam_id] |= set(r.settings)
    for cam_id in MODELS:
        assert shown[cam_id] == {s.param for s in catalogue().get(cam_id).cdf_settings}


@pytest.mark.parametrize("cam_id", MODELS)
def test_mavproxy_accepts_every_definition_and_shows_every_setting_with_all_options(cam_id):
    data = definition_xml(catalogue().get(cam_id))
    shown = set()
    for variant, visible in visibility_variants(data):
        r = peers.mavproxy_load_definition(variant)
        assert r.accepted, r.error
        assert set(r.parameters) == {s.param for s in catalogue().get(cam_id).cdf_settings}
        assert set(r.settings) == visible
        expected = expected_options(_root(variant))
        for name, listed in r.settings.items():
            if isinstance(expected[name][0], str):   # MAVProxy lists typed option values
                assert [str(v) for v in listed] == list(expected[name]), name
        shown |= set(r.settings)
    assert shown == {s.param for s in catalogue().get(cam_id).cdf_settings}


def test_variants_cover_every_hidden_parameter():
    data = definition_xml(catalogue().get("wiris-pro"))
    variants = visibility_variants(data)
    assert len(variants) >= 2
    published_visible = variants[0][1]
    assert "RANGE_MAX_C" not in published_visible   # automatic range hides the manual limits
    assert set().union(*(v for _, v in variants)) == {s.param for s in catalogue().get("wiris-pro").cdf_settings}


@pytest.mark.parametrize("locale_name", ["de_DE", "cs_CZ"])
def test_mavproxy_shows_the_translations(locale_name):
    """MAVProxy maps descriptions and option names through the locale's strings (exact match): every one
    of them must arrive translated, with parameter names and values untouched."""
    from MAVProxy.modules.mavproxy_camera.definition import CameraDefinition

    from cdf.generate import load_locales

    table = dict(next(loc for loc in load_locales() if loc.name == locale_name).strings)
    for cam_id in MODELS:
        cam = catalogue().get(cam_id)
        cd = CameraDefinition(definition_xml(cam), locale_name=locale_name)
        assert list(cd.parameters) == [s.param for s in cam.cdf_settings]
        for s in cam.cdf_settings:
            p = cd.parameters[s.param]
            assert p.description == table[s.label] + (f" ({s.unit})" if s.unit else "")
            if s.options:
                labels = [label for label, _value in p.options]
                values = [int(value) for _label, value in p.options]
                assert values == [o.value for o in s.options]
                assert labels == [" + ".join(table[s.enum.by_key(k).name] for k in o.key.split("+")) if s.flags
                                  else table[o.name] for o in s.options]
