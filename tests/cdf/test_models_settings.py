"""`wiris cdf models --settings MODEL`: every setting of a catalogue camera with its plan name, PARAM_EXT name,
values and unit; an unknown model is a clear error."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from cdf.catalogue import catalogue
from wiris_tools.cli import cli


@pytest.mark.parametrize("model", catalogue().ids)
def test_every_setting_is_listed_with_both_names_and_its_values(model):
    cam = catalogue().get(model)
    r = CliRunner().invoke(cli, ["cdf", "models", "--settings", model])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()[1:]
    assert len(lines) == len(cam.settings)
    for s, line in zip(cam.settings, lines):
        assert line.split()[:2] == [s.key, s.param]
        if s.unit:
            assert f"[{s.unit}]" in line
        for o in (s.enum.options if s.flags else s.options):
            assert o.key in line


def test_json_gives_options_with_name_label_and_value():
    r = CliRunner().invoke(cli, ["cdf", "models", "--settings", "wiris-pro", "--json"])
    doc = json.loads(r.output)
    mode = next(s for s in doc["settings"] if s["plan_name"] == "range_mode")
    assert mode["param"] == "RANGE_MODE"
    assert {"name": "manual", "label": "Manual", "value": 1} in mode["options"]
    emissivity = next(s for s in doc["settings"] if s["plan_name"] == "emissivity")
    assert (emissivity["min"], emissivity["max"]) == (0.5, 1.0)


def test_an_unknown_model_is_an_error_with_did_you_mean():
    r = CliRunner().invoke(cli, ["cdf", "models", "--settings", "wiris-por"])
    assert r.exit_code == 1 and "did you mean 'wiris-pro'?" in r.output and "Traceback" not in r.output
