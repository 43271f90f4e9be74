"""A folder of geotagged JPEGs (written here with Pillow's EXIF writer) matched to the tlog's captures: by the
number in the file name, and by EXIF time when the names carry none."""

from __future__ import annotations

import json
from datetime import datetime, timezone

import pytest
from click.testing import CliRunner
from PIL import Image

import sitl_plans
from audit_logs import write_tlog
from missions.compile import compile_plan
from wiris_tools.audit.images import match_images, read_folder
from wiris_tools.audit.logs import read_log
from wiris_tools.cli import cli


def _dms(v: float) -> tuple[float, float, float]:
    d = int(abs(v))
    m = int((abs(v) - d) * 60)
    return (float(d), float(m), round(((abs(v) - d) * 60 - m) * 60, 4))


def write_jpeg(path, lat: float, lon: float, t: float) -> None:
    img = Image.new("RGB", (64, 48), (200, 80, 40))
    exif = img.getexif()
    gps = exif.get_ifd(0x8825)
    gps.update({1: "N" if lat >= 0 else "S", 2: _dms(lat), 3: "E" if lon >= 0 else "W", 4: _dms(lon)})
    exif.get_ifd(0x8769)[0x9003] = datetime.fromtimestamp(round(t), timezone.utc).strftime("%Y:%m:%d %H:%M:%S")
    img.save(path, exif=exif)


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    d = tmp_path_factory.mktemp("f")
    path = sitl_plans.write_plan(d, "survey")
    compiled = compile_plan(path)
    write_tlog(d / "f.tlog", compiled)
    return path, d / "f.tlog", read_log(d / "f.tlog")


def test_images_matched_by_sequence_find_the_missing_and_the_foreign(flight, tmp_path):
    path, tlog, log = flight
    for c in log.captures:
        if c.seq not in (3, 10):
            write_jpeg(tmp_path / f"IMG_{c.seq:05d}.jpg", c.pose.lat, c.pose.lon, c.pose.time_s)
    write_jpeg(tmp_path / "IMG_00999.jpg", 50.08, 14.42, log.captures[0].pose.time_s)
    images = read_folder(tmp_path)
    assert images[0].lat == pytest.approx(log.captures[0].pose.lat, abs=1e-6)
    m = match_images(images, log.captures)
    assert m.by == "sequence"
    assert m.captured_without_image == (3, 10)
    assert m.without_log_entry == ("IMG_00999.jpg",)
    res = CliRunner().invoke(cli, ["mission", "audit", str(path), str(tlog), "--images", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.output)["images"]["captured_without_image"] == [3, 10]


def test_images_without_numbers_are_matched_by_time(flight, tmp_path):
    _, _, log = flight
    for k, c in enumerate(log.captures[:10]):
        write_jpeg(tmp_path / f"thermal-{chr(97 + k)}.jpg", c.pose.lat, c.pose.lon, c.pose.time_s)
    m = match_images(read_folder(tmp_path), log.captures)
    assert m.by == "time" and m.matched == 10 and m.without_log_entry == ()
    assert len(m.captured_without_image) == len(log.captures) - 10
