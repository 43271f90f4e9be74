"""A folder of the flight's images (JPEG EXIF: GPS position, time) matched to the log's captures by sequence
number (the number in the file name, IMG_00012.jpg, is the camera's image index: the WIRIS names them so) or,
for names without one, by time (EXIF DateTimeOriginal, read as UTC, within TIME_MATCH_S of a capture).
Pillow reads the EXIF: it is already a dependency and reads the GPS IFD."""

from __future__ import annotations

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
class ImageFile:
    path: str
    seq: int | None                  # the number in the file name
    time_s: float | None             # EXIF DateTimeOriginal as UTC seconds; None without one
    lat: float | None
    lon: float | None


@dataclass(frozen=True)
class ImageMatch:
    images: int
    matched: int
    without_log_entry: tuple[str, ...]       # images no capture of the log accounts for
    captured_without_image: tuple[int, ...]  # captures (image index) whose image is not in the folder
    by: str                                  # "sequence" | "time"

    def to_json(self) -> dict:
        return {"images": self.images, "matched": self.matched, "by": self.by,
                "without_log_entry": list(self.without_log_entry),
                "captured_without_image": list(self.captured_without_image)}


def _degrees(dms, ref: str) -> float:
    d, m, s = (float(v) for v in dms)
    v = d + m / 60 + s / 3600
    return -v if ref in ("S", "W") else v


def read_image(path: Path) -> ImageFile:
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as im:
            exif = im.getexif()
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
    return ImageFile(str(path), int(digits[-1]) if digits else None, t, lat, lon)


def read_folder(folder: str | Path) -> list[ImageFile]:
    d = Path(folder)
    if not d.is_dir():
        raise LinkError("no such folder of images", where=str(d), hint="give the folder the camera's images are in")
    return [read_image(p) for p in sorted(d.iterdir()) if p.suffix.lower() in IMAGE_SUFFIXES]


def match_images(images: Sequence[ImageFile], captures: Sequence[Shot]) -> ImageMatch:
    """Images against the log's captures, by sequence when every image has a number and the captures theirs."""
    if images and all(i.seq is not None for i in images) and all(c.seq is not None for c in captures):
        have = {i.seq for i in images}
        logged = {c.seq for c in captures}
        return ImageMatch(len(images), len(have & logged),
                          tuple(Path(i.path).name for i in images if i.seq not in logged),
                          tuple(sorted(s for s in logged if s not in have)), "sequence")
    times = sorted((c.pose.time_s, c.seq if c.seq is not None else k) for k, c in enumerate(captures))
    used: set[int] = set()
    lone = []
    for im in images:
        best = None
        if im.time_s is not None:
            best = min((k for k, (t, _) in enumerate(times) if k not in used and abs(t - im.time_s) <= TIME_MATCH_S),
                       key=lambda k: abs(times[k][0] - im.time_s), default=None)
        if best is None:
            lone.append(Path(im.path).name)
        else:
            used.add(best)
    return ImageMatch(len(images), len(used), tuple(lone),
                      tuple(s for k, (_, s) in enumerate(times) if k not in used), "time")
