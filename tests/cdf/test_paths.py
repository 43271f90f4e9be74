"""cdf.paths.require_directory (the one directory guard of cdf build, mission compile and cdf serve) and
cdf.float32.FLOAT32_MAX: real files in tmp_path; a scan of the packages' source keeps them the only ones."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest

from cdf.errors import CdfError
from cdf.float32 import FLOAT32_MAX
from cdf.paths import require_directory
from missions.errors import PlanError
from wiris_tools.errors import LinkError

REPO = Path(__file__).resolve().parents[2]


def _sources():
    for package in ("cdf", "missions", "wiris_tools"):
        yield from sorted((REPO / package).rglob("*.py"))


def test_an_existing_directory_passes_both_ways(tmp_path):
    require_directory(tmp_path, LinkError, hint="h")
    require_directory(tmp_path, PlanError, hint="h", missing_ok=True, access_hint="a")
    require_directory(tmp_path / "to-be-made", CdfError, hint="h", missing_ok=True, access_hint="a")


@pytest.mark.parametrize("error_class", [CdfError, PlanError, LinkError])
def test_a_file_in_the_way_is_refused_in_the_callers_family(tmp_path, error_class):
    (tmp_path / "f").write_text("x")
    with pytest.raises(error_class) as err:
        require_directory(tmp_path / "f", error_class, hint="move it", missing_ok=True, access_hint="a")
    assert err.value.message == "the output path exists and is not a directory"
    assert err.value.where == str(tmp_path / "f") and err.value.hint == "move it"
    with pytest.raises(error_class) as err:
        require_directory(tmp_path / "f", error_class, hint="h")
    assert err.value.message == "not a directory"
    assert (tmp_path / "f").read_text() == "x"


def test_missing_or_unreadable_paths(tmp_path):
    with pytest.raises(LinkError) as err:
        require_directory(str(tmp_path / "missing"), LinkError, hint="build a bundle first")
    assert err.value.message == "not a directory" and err.value.where == str(tmp_path / "missing") and err.value.hint == "build a bundle first"
    too_long = tmp_path / ("d" * 300)
    with pytest.raises(LinkError) as err:
        require_directory(too_long, LinkError, hint="h")
    assert err.value.message == "not a directory"
    with pytest.raises(PlanError) as err:
        require_directory(too_long, PlanError, hint="h", missing_ok=True, access_hint="shorter names")
    assert err.value.message == "cannot use the output directory: File name too long"
    assert err.value.hint == "shorter names"


def test_float32_max_is_the_largest_finite_float32():
    assert struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0] == FLOAT32_MAX
    with pytest.raises(OverflowError):
        struct.pack("<f", FLOAT32_MAX * (1 + 2.0 ** -23))


def test_each_is_defined_once():
    definitions = [p.relative_to(REPO).as_posix() for p in _sources()
                   if re.search(r"^FLOAT32_MAX\s*=", p.read_text(encoding="utf-8"), re.M)]
    assert definitions == ["cdf/float32.py"]
    guards = [p.relative_to(REPO).as_posix() for p in _sources() if '"not a directory"' in p.read_text(encoding="utf-8")
              or "is not a directory\"" in p.read_text(encoding="utf-8")]
    assert guards == ["cdf/paths.py"]
