"""A folder of geotagged JPEGs (written here with Pillow's EXIF writer) matched to the tlog's captures: by the
number in the file name, and by EXIF time when the names carry none."""

from __future__ import annotations

import json
import math
from datetime import datetime, timezone

import numpy as np

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


def write_jpeg(path, lat: float, lon: float, t: float, xmp: str | None = None) -> None:
    img = Image.new("RGB", (64, 48), (200, 80, 40))
    exif = img.getexif()
    gps = exif.get_ifd(0x8825)
    gps.update({1: "N" if lat >= 0 else "S", 2: _dms(lat), 3: "E" if lon >= 0 else "W", 4: _dms(lon)})
    exif.get_ifd(0x8769)[0x9003] = datetime.fromtimestamp(round(t), timezone.utc).strftime("%Y:%m:%d %H:%M:%S")
    img.save(path, exif=exif, **({"xmp": xmp.encode()} if xmp else {}))


def dji_xmp(pitch: float, roll: float, yaw: float) -> str:
    """An XMP packet as DJI writes one: the gimbal's angles as attributes of rdf:Description."""
    return ('<?xpacket begin="\ufeff" id="W5M0MpCehiHzreSzNTczkc9d"?>'
            '<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">'
            '<rdf:Description rdf:about="" xmlns:drone-dji="http://www.dji.com/drone-dji/1.0/" '
            f'drone-dji:GimbalRollDegree="{roll:+.2f}" drone-dji:GimbalYawDegree="{yaw:+.2f}" '
            f'drone-dji:GimbalPitchDegree="{pitch:+.2f}" drone-dji:FlightPitchDegree="+3.10"/>'
            '</rdf:RDF></x:xmpmeta><?xpacket end="w"?>')


def pix4d_xmp(pitch: float, roll: float, yaw: float) -> str:
    """Pix4D's camera namespace, the angles as elements (pitch 0: straight down)."""
    return ('<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">'
            '<rdf:Description rdf:about="" xmlns:Camera="http://pix4d.com/camera/1.0/">'
            f'<Camera:Pitch>{pitch}</Camera:Pitch><Camera:Roll>{roll}</Camera:Roll><Camera:Yaw>{yaw}</Camera:Yaw>'
            '</rdf:Description></rdf:RDF></x:xmpmeta>')


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



def _centres(path, tlog, images=None):
    from missions.compile import compile_plan as _compile
    from wiris_tools.audit.measure import audit_flight
    audit = audit_flight(_compile(path), read_log(tlog), str(path), images=images)
    return audit, audit.steps[0].footprints.centres


def _expected_shift(c, ahead_deg: float, right_deg: float, heading_deg: float) -> np.ndarray:
    h = math.radians(heading_deg)
    alt = c.pose.alt_rel_m
    return (alt * math.tan(math.radians(ahead_deg)) * np.array([math.sin(h), math.cos(h)])
            + alt * math.tan(math.radians(right_deg)) * np.array([math.cos(h), -math.sin(h)]))


def test_dji_gimbal_angles_in_the_images_place_their_footprints(flight, tmp_path):
    path, tlog, log = flight
    tilted = {5, 6, 7, 8, 9}                   # the gimbal looked 30 degrees ahead for these five
    turned = 9                                 # and for this one it also looked to the right of the airframe

    def yaw(k, c):
        y = (c.pose.heading_deg + (90.0 if k == turned else 0.0)) % 360.0
        return y - 360.0 if y > 180 else y                                   # DJI writes -180..180
    for k, c in enumerate(log.captures):
        pitch = -60.0 if k in tilted else -90.0
        write_jpeg(tmp_path / f"IMG_{c.seq:05d}.jpg", c.pose.lat, c.pose.lon, c.pose.time_s,
                   dji_xmp(pitch, 0.0, yaw(k, c)))
    images = read_folder(tmp_path)
    assert images[5].angles.source == "drone-dji" and images[5].angles.tilt_deg == pytest.approx(30.0)
    plain, base = _centres(path, tlog)
    audit, moved = _centres(path, tlog, images)
    assert audit.images.matched == len(log.captures)
    assert any(f"{len(log.captures)} photo(s) placed by their image's gimbal angles" in n for n in audit.notes)
    shift = moved - base
    for k in range(len(log.captures)):
        want = _expected_shift(log.captures[k], 30.0, 0.0, yaw(k, log.captures[k])) if k in tilted else 0
        assert shift[k] == pytest.approx(want, abs=0.05), k
    assert np.linalg.norm(shift[5]) > 20            # 40 m up, 30 degrees ahead: 23 m
    assert plain.steps[0].coverage == pytest.approx(audit.steps[0].coverage, abs=0.02)


def test_pix4d_camera_angles_and_images_without_angles(flight, tmp_path):
    path, tlog, log = flight
    for k, c in enumerate(log.captures):
        xmp = pix4d_xmp(0.0, 20.0, c.pose.heading_deg) if k == 3 else None      # rolled 20 degrees right
        write_jpeg(tmp_path / f"IMG_{c.seq:05d}.jpg", c.pose.lat, c.pose.lon, c.pose.time_s, xmp)
    images = read_folder(tmp_path)
    assert images[3].angles.source == "pix4d-camera" and images[0].angles is None
    _, base = _centres(path, tlog)
    audit, moved = _centres(path, tlog, images)
    shift = moved - base
    assert shift[3] == pytest.approx(_expected_shift(log.captures[3], 0.0, 20.0, log.captures[3].pose.heading_deg),
                                     abs=0.05)
    assert np.abs(np.delete(shift, 3, axis=0)).max() < 1e-6
    assert any("1 photo(s) placed by their image's gimbal angles" in n for n in audit.notes)


def test_a_damaged_xmp_packet_gives_no_angles(tmp_path):
    write_jpeg(tmp_path / "IMG_00001.jpg", 50.08, 14.42, 1_780_000_000.0, "<x:xmpmeta><rdf:RDF")
    (image,) = read_folder(tmp_path)
    assert image.angles is None and image.lat == pytest.approx(50.08, abs=1e-6)
