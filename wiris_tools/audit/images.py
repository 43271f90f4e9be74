"""A folder of the flight's images (JPEG EXIF: GPS position, time; XMP: the camera's gimbal angles) matched to
the log's captures by sequence number (the number in the file name, IMG_00012.jpg, is the camera's image
index: the WIRIS names them so) or, for names without one, by time (EXIF DateTimeOriginal, read as UTC, within
TIME_MATCH_S of a capture). Pillow reads the EXIF and hands over the XMP packet; defusedxml parses it.

Gimbal angles, where an image's XMP carries them, tell where that photo's camera looked, which the
autopilot's attitude does not (a gimbal moves on its own): the audit uses them over the log's for that photo.
Two conventions are read, the ones photogrammetry tools read:
- DJI's `drone-dji:GimbalPitchDegree`, `GimbalRollDegree`, `GimbalYawDegree` (http://www.dji.com/drone-dji/1.0/):
  pitch -90 looks straight down, yaw is the heading clockwise from north, both against the earth;
- Pix4D's camera namespace `Camera:Pitch`, `Roll`, `Yaw` (http://pix4d.com/camera/1.0/): pitch 0 looks
  straight down.
Which of them (if any) a WIRIS writes is not in the documents the project has (the MAVLink interface manual
says nothing of its image metadata): an image with neither is matched, and its photo keeps the log's attitude.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Sequence

from wiris_tools.audit.logs import Shot
from wiris_tools.errors import LinkError

IMAGE_SUFFIXES = (".jpg", ".jpeg")
TIME_MATCH_S = 2.0
_GPS_IFD = 0x8825
_EXIF_IFD = 0x8769
_DATETIME_ORIGINAL = 0x9003


@dataclass(frozen=True)
class CameraAngles:
    """Where the camera looked, from the image's XMP: heading clockwise from north, tilt from straight down
    (positive: ahead of the heading) and roll (positive: to the right), degrees."""

    heading_deg: float
    tilt_deg: float
    roll_deg: float
    source: str                      # "drone-dji" | "pix4d-camera"


@dataclass(frozen=True)
class ImageFile:
    path: str
    seq: int | None                  # the number in the file name
    time_s: float | None             # EXIF DateTimeOriginal as UTC seconds; None without one
    lat: float | None
    lon: float | None
    angles: CameraAngles | None = None


@dataclass(frozen=True)
class ImageMatch:
    images: int
    matched: int
    without_log_entry: tuple[str, ...]       # images no capture of the log accounts for
    captured_without_image: tuple[int, ...]  # captures (image index) whose image is not in the folder
    by: str                                  # "sequence" | "time"
    pairs: tuple[tuple[int, int], ...] = ()  # (capture's place in the log's list, image's place in the folder's)

    def to_json(self) -> dict:
        return {"images": self.images, "matched": self.matched, "by": self.by,
                "without_log_entry": list(self.without_log_entry),
                "captured_without_image": list(self.captured_without_image)}


def _degrees(dms, ref: str) -> float:
    d, m, s = (float(v) for v in dms)
    v = d + m / 60 + s / 3600
    return -v if ref in ("S", "W") else v


_DJI = "{http://www.dji.com/drone-dji/1.0/}"
_PIX4D = "{http://pix4d.com/camera/1.0/}"


def _xmp_values(xmp: bytes | str | None) -> dict[str, str]:
    """Every property of the XMP packet, as attributes or as elements, by its namespaced name."""
    if not xmp:
        return {}
    from defusedxml import ElementTree
    text = xmp.decode("utf-8", "replace") if isinstance(xmp, bytes) else xmp
    try:
        root = ElementTree.fromstring(text.strip().strip("\x00"))
    except Exception:   # a damaged packet (ParseError) or one defusedxml refuses (entities): no angles from it
        return {}
    out: dict[str, str] = {}
    for el in root.iter():
        out.update({k: v for k, v in el.attrib.items()})
        if el.text and el.text.strip() and len(el) == 0:
            out[el.tag] = el.text.strip()
    return out


def _angles(xmp: dict[str, str]) -> CameraAngles | None:
    def num(key: str) -> float | None:
        try:
            return float(xmp[key])
        except (KeyError, ValueError):
            return None
    for ns, source, nadir in ((_DJI, "drone-dji", -90.0), (_PIX4D, "pix4d-camera", 0.0)):
        names = ("GimbalPitchDegree", "GimbalRollDegree", "GimbalYawDegree") if ns == _DJI else ("Pitch", "Roll", "Yaw")
        pitch, roll, yaw = (num(ns + n) for n in names)
        if pitch is not None and yaw is not None:
            return CameraAngles(yaw % 360.0, pitch - nadir, roll or 0.0, source)
    return None


def read_image(path: Path) -> ImageFile:
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as im:
            exif = im.getexif()
            xmp = im.info.get("xmp")
    except (UnidentifiedImageError, OSError) as err:
        raise LinkError(f"not a readable image: {err}", where=str(path),
                        hint="the folder should hold the flight's JPEGs only") from None
    gps = exif.get_ifd(_GPS_IFD)
    lat = lon = None
    if 2 in gps and 4 in gps:
        lat, lon = _degrees(gps[2], gps.get(1, "N")), _degrees(gps[4], gps.get(3, "E"))
    stamp = exif.get_ifd(_EXIF_IFD).get(_DATETIME_ORIGINAL) or exif.get(0x0132)
    t = None
    if isinstance(stamp, str):
        try:
            t = datetime.strptime(stamp.strip(), "%Y:%m:%d %H:%M:%S").replace(tzinfo=timezone.utc).timestamp()
        except ValueError:
            t = None
    digits = re.findall(r"\d+", path.stem)
    return ImageFile(str(path), int(digits[-1]) if digits else None, t, lat, lon, _angles(_xmp_values(xmp)))


def read_folder(folder: str | Path) -> list[ImageFile]:
    d = Path(folder)
    if not d.is_dir():
        raise LinkError("no such folder of images", where=str(d), hint="give the folder the camera's images are in")
    return [read_image(p) for p in sorted(d.iterdir()) if p.suffix.lower() in IMAGE_SUFFIXES]


def match_images(images: Sequence[ImageFile], captures: Sequence[Shot]) -> ImageMatch:
    """Images against the log's captures, by sequence when every image has a number and the captures theirs,
    each once (several logs of one flight may each count from 0); else by time."""
    seqs = [c.seq for c in captures]
    if images and all(i.seq is not None for i in images) and None not in seqs and len(set(seqs)) == len(seqs):
        have = {i.seq for i in images}
        logged = {c.seq for c in captures}
        image_of = {i.seq: k for k, i in enumerate(images)}
        return ImageMatch(len(images), len(have & logged),
                          tuple(Path(i.path).name for i in images if i.seq not in logged),
                          tuple(sorted(s for s in logged if s not in have)), "sequence",
                          tuple((c, image_of[cap.seq]) for c, cap in enumerate(captures) if cap.seq in image_of))
    times = sorted((c.pose.time_s, c.seq if c.seq is not None else k, k) for k, c in enumerate(captures))
    used: dict[int, int] = {}            # place in `times` -> image's place in the folder
    lone = []
    for n, im in enumerate(images):
        best = None
        if im.time_s is not None:
            best = min((k for k, (t, _, _) in enumerate(times) if k not in used and abs(t - im.time_s) <= TIME_MATCH_S),
                       key=lambda k: abs(times[k][0] - im.time_s), default=None)
        if best is None:
            lone.append(Path(im.path).name)
        else:
            used[best] = n
    return ImageMatch(len(images), len(used), tuple(lone),
                      tuple(s for k, (_, s, _) in enumerate(times) if k not in used), "time",
                      tuple(sorted((times[k][2], n) for k, n in used.items())))


def oriented_by_images(captures: Sequence[Shot], images: Sequence[ImageFile], match: ImageMatch) -> list[Shot]:
    """The captures, each whose image carries gimbal angles turned and tilted as the image says (the log's
    attitude is the airframe's; the image's is the camera's own)."""
    out = list(captures)
    for c, n in match.pairs:
        a = images[n].angles
        if a is not None:
            p = out[c].pose
            out[c] = dataclasses.replace(out[c], oriented=True,
                                         pose=dataclasses.replace(p, heading_deg=a.heading_deg, pitch_deg=a.tilt_deg,
                                                                  roll_deg=a.roll_deg))
    return out
