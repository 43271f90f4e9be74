"""The hosting bundle: generated camera definitions, optional .xml.xz twins and manifest.json in one directory.

    from cdf.bundle import build_bundle
    result = build_bundle("build/cdf", all_models=True, base_url="http://127.0.0.1:8000/cdf", xz=True)

Published definitions are immutable. QGroundControl and MAVSDK cache a definition by vendor, model and
CAMERA_INFORMATION.cam_definition_version and never download it again for the same triple (reference
§3.5, §4.5), so new content under an old version would never reach a ground station that already has
it, and two different files would circulate under one name. The builder therefore refuses to write
different bytes under an existing file name or manifest version, and says to raise `definition_version`.

Every file is validated with the validator's `strict` profile before anything is written, and the
directory is changed atomically: files are built in a temporary directory, then renamed into place
(the manifest last), so an error leaves the directory exactly as it was.

The immutability check holds when builds run at the same time: each holds an exclusive lock (flock) on the
bundle directory's parent from reading what is published until its files are in place, so a second build
of the same version sees the first one's files and is refused (or finds them identical). The parent is
locked rather than the directory itself because a new bundle directory appears by one rename.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import lzma
import os
import re
import shutil
import tempfile
import urllib.parse
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Iterable, Iterator

from cdf.catalogue import Camera, Catalogue
from cdf.errors import CdfError
from cdf.paths import require_directory

MANIFEST = "manifest.json"
# CAMERA_INFORMATION.cam_definition_uri is char[140] and must be NUL-terminated (common.xml): 139 bytes of text.
URI_MAX = 139
URI_SCHEMES = ("http://", "https://", "mftp://")
# xz container with a CRC32 check: every xz decoder (xz-embedded in ground stations included) supports
# CRC32, while CRC64/SHA-256 are optional there. Preset 6 is liblzma's default; output is deterministic
# for a given liblzma, so a rebuild reproduces the same bytes.
XZ_CHECK = lzma.CHECK_CRC32
XZ_PRESET = 6


@dataclass(frozen=True)
class BundleEntry:
    """One manifest entry (spec/cli.md): the plain .xml file of one model and definition version."""

    id: str
    vendor: str
    model: str
    version: int
    file: str
    uri: str
    sha256: str
    bytes: int


@dataclass(frozen=True)
class BuildResult:
    directory: Path
    entries: tuple[BundleEntry, ...]            # built now
    manifest: tuple[BundleEntry, ...]           # everything manifest.json lists after the build
    written: tuple[str, ...]                    # file names created (not already present byte-identical)
    unchanged: tuple[str, ...]                  # file names already present with identical bytes
    skipped: tuple[tuple[str, str], ...]        # (model id, why) for --all models without a definition


def xz_bytes(data: bytes) -> bytes:
    """The deterministic .xml.xz twin of a definition (for MAVLink FTP; QGC does not inflate xz over HTTP)."""
    return lzma.compress(data, format=lzma.FORMAT_XZ, check=XZ_CHECK, preset=XZ_PRESET)


def definition_uri(base_url: str | None, file_name: str) -> str:
    """The URI a camera reports in CAMERA_INFORMATION.cam_definition_uri for `file_name` under `base_url`
    (the bare file name when no base URL is given)."""
    if not base_url:
        return file_name
    return base_url + file_name if base_url.endswith("/") else f"{base_url}/{file_name}"


def check_base_url(base_url: str) -> None:
    if not base_url.isascii() or any(c.isspace() for c in base_url):
        raise CdfError(f"base URL {base_url!r} must be ASCII without spaces",
                       hint="cam_definition_uri is a C string the camera sends as is")
    if not base_url.lower().startswith(URI_SCHEMES):
        raise CdfError(f"base URL {base_url!r} must start with http://, https:// or mftp://",
                       hint="QGroundControl knows only these (mavlinkftp:// is MAVSDK-only, reference §1.4)")
    if "?" in base_url or "#" in base_url:
        raise CdfError(f"base URL {base_url!r} must not carry a query or fragment",
                       hint="the file name is appended to it")
    if re.search(r"%(?![0-9A-Fa-f]{2})", base_url):
        raise CdfError(f"base URL {base_url!r} has a % not followed by two hex digits",
                       hint="write a literal % as %25")
    if base_url.lower().startswith(("http://", "https://")):
        try:
            parts = urllib.parse.urlsplit(base_url)
            parts.port  # noqa: B018 (raises ValueError for a port that is not 0-65535)
        except ValueError as err:
            raise CdfError(f"base URL {base_url!r} is malformed: {err}",
                           hint="write it as http://HOST[:PORT]/PATH, an IPv6 host in brackets") from None
        if not parts.hostname:
            raise CdfError(f"base URL {base_url!r} names no host", hint="write it as http://HOST[:PORT]/PATH")


def select_cameras(cat: Catalogue, models: Iterable[str], all_models: bool
                   ) -> tuple[list[Camera], list[tuple[str, str]]]:
    """The cameras to build and the (id, reason) of models skipped under --all."""
    names = list(dict.fromkeys(models))
    if not names and not all_models:
        raise CdfError("no model named", hint="name models (see `wiris cdf models`) or pass --all")
    chosen: list[Camera] = []
    skipped: list[tuple[str, str]] = []
    for name in names:
        cam = cat.get(name)
        if not cam.has_cdf:
            raise CdfError(f"{cam.id} ({cam.vendor} {cam.model}) has no camera definition",
                           where=f"cdf/tables/{cam.table}",
                           hint="it does not speak the MAVLink camera protocol (RedEdge: serial API, classic "
                                "PARAM_*); leave it out, or use --all, which skips it with a note")
        chosen.append(cam)
    if all_models:
        for cam in cat.cameras:
            if not cam.has_cdf:
                skipped.append((cam.id, f"no camera definition ({cam.protocol})"))
            elif cam not in chosen:
                chosen.append(cam)
    return chosen, skipped


def _read_manifest(directory: Path) -> list[BundleEntry]:
    path = directory / MANIFEST
    if not path.exists():
        return []
    hint = "move the directory's manifest.json away or build into an empty directory"
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
        rows = raw["models"]
        return [BundleEntry(id=str(r["id"]), vendor=str(r["vendor"]), model=str(r["model"]),
                            version=int(r["version"]), file=str(r["file"]), uri=str(r["uri"]),
                            sha256=str(r["sha256"]), bytes=int(r["bytes"])) for r in rows]
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as err:
        raise CdfError(f"cannot read the existing manifest: {type(err).__name__}: {err}", where=str(path),
                       hint=hint) from None


def manifest_bytes(entries: Iterable[BundleEntry]) -> bytes:
    """manifest.json: entries sorted by model id and version, fixed key order, two-space indent, LF."""
    rows = [asdict(e) for e in sorted(entries, key=lambda e: (e.id, e.version, e.file))]
    return (json.dumps({"models": rows}, indent=2, ensure_ascii=False) + "\n").encode("utf-8")


def _strict_problems(data: bytes, name: str, cam: Camera, uri: str | None) -> list[str]:
    from cdf.validation import CameraInfo, validate_bytes

    info = CameraInfo(vendor_name=cam.vendor, model_name=cam.model, cam_definition_version=cam.definition_version,
                      cam_definition_uri=uri)
    report = validate_bytes(data, name, "strict", camera_info=info)
    return [f.format(name) for f in report.errors]


def build_bundle(directory: str | Path, models: Iterable[str] = (), *, all_models: bool = False,
                 base_url: str | None = None, xz: bool = False, cat: Catalogue | None = None) -> BuildResult:
    """Generate, check and write the hosting bundle into `directory` (created if missing).

    Raises CdfError, leaving `directory` untouched, when: a named model is unknown or has no definition;
    a URI exceeds 139 characters; a file fails the strict validation; or the directory already holds a
    different file under a name being written, or a manifest entry of the same model and version with a
    different sha256 (published versions are immutable: raise `definition_version` in the table).
    """
    from cdf.generate import definition_file_name, definition_xml, load_locales

    if cat is None:
        from cdf.catalogue import catalogue

        cat = catalogue()
    directory = Path(directory)
    require_directory(directory, CdfError, missing_ok=True, hint="choose another -o directory, or move that file away",
                      access_hint="choose another -o directory, one you may create and write to")
    if base_url is not None:
        check_base_url(base_url)
    cameras, skipped = select_cameras(cat, models, all_models)
    locales = load_locales()

    outputs: dict[str, bytes] = {}
    entries: list[BundleEntry] = []
    for cam in cameras:
        file_name = definition_file_name(cam)
        uri = definition_uri(base_url, file_name)
        uris = [uri] + ([uri + ".xz"] if xz else [])
        for u in uris:
            if len(u.encode("utf-8")) > URI_MAX:
                raise CdfError(f"{cam.id}: URI is {len(u.encode('utf-8'))} characters, more than {URI_MAX}: {u}",
                               where=f"cdf/tables/{cam.table}",
                               hint="CAMERA_INFORMATION.cam_definition_uri is char[140] with a NUL; "
                                    "use a shorter --base-url")
        data = definition_xml(cam, locales)
        problems = _strict_problems(data, file_name, cam, uri if base_url else None)
        files = {file_name: data}
        if xz:
            packed = xz_bytes(data)
            if lzma.decompress(packed) != data:
                raise CdfError(f"{cam.id}: the xz twin does not inflate to the definition", where=file_name + ".xz",
                               hint="a bug in wiris-tools or liblzma: please report it; build without --xz meanwhile")
            problems += _strict_problems(packed, file_name + ".xz", cam, None)
            files[file_name + ".xz"] = packed
        if problems:
            raise CdfError(f"{cam.id}: the generated definition fails the strict validation:\n    "
                           + "\n    ".join(problems), where=f"cdf/tables/{cam.table}",
                           hint="fix the catalogue table; nothing was written")
        for name, content in files.items():
            if name in outputs and outputs[name] != content:
                raise CdfError(f"{cam.id}: file name {name} is produced by two models", hint="rename a model")
        outputs.update(files)
        entries.append(BundleEntry(id=cam.id, vendor=cam.vendor, model=cam.model, version=cam.definition_version,
                                   file=file_name, uri=uri, sha256=hashlib.sha256(data).hexdigest(),
                                   bytes=len(data)))

    with _build_lock(directory):
        return _publish(directory, cat, entries, outputs, skipped)


@contextlib.contextmanager
def _build_lock(directory: Path) -> Iterator[None]:
    """Hold the exclusive lock on the bundle directory's parent (created if missing) for the block: one build
    at a time checks and changes what is published there."""
    fd = None
    try:
        parent = directory.resolve().parent    # one lock for every spelling of the path, symlinks included
        parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(parent, os.O_RDONLY | os.O_DIRECTORY)
        fcntl.flock(fd, fcntl.LOCK_EX)         # released when fd closes, also when the process dies
    except OSError as err:
        if fd is not None:
            os.close(fd)
        raise CdfError(f"cannot write the bundle: {err.strerror or err}", where=str(directory),
                       hint="nothing was changed; the directory's parent must exist or be creatable, "
                            "readable and writable, on a file system that can lock") from None
    try:
        yield
    finally:
        os.close(fd)


def _publish(directory: Path, cat: Catalogue, entries: list[BundleEntry], outputs: dict[str, bytes],
             skipped: list[tuple[str, str]]) -> BuildResult:
    """Check the built files against what `directory` publishes and write them (under _build_lock)."""
    # Immutability: nothing published may change under the same name or version.
    existing = _read_manifest(directory) if directory.exists() else []
    built = {(e.id, e.version): e for e in entries}
    for old in existing:
        new = built.get((old.id, old.version))
        if new is not None and new.sha256 != old.sha256:
            raise CdfError(f"{old.id}: definition version {old.version} is already published with different "
                           f"content (sha256 {old.sha256[:12]}…, now {new.sha256[:12]}…)",
                           where=str(directory / MANIFEST),
                           hint=f"published versions are immutable: raise definition_version for {old.id} in "
                                f"cdf/tables/{cat.get(old.id).table if old.id in cat.ids else '<its table>'} and rebuild")
    written, unchanged = [], []
    for name, content in outputs.items():
        target = directory / name
        if target.is_symlink() or (target.exists() and not target.is_file()):
            raise CdfError("not a regular file; refusing to replace it", where=str(target),
                           hint="move it away (symlinks and directories are never replaced), or choose another -o")
        if target.exists():
            if target.read_bytes() != content:
                owner = next((e for e in entries if name.startswith(e.file)), None)
                model = owner.id if owner else name
                table = cat.get(owner.id).table if owner else "<its table>"
                raise CdfError(f"{model}: {name} already exists with different content", where=str(target),
                               hint=f"published versions are immutable: raise definition_version for {model} "
                                    f"in cdf/tables/{table} and rebuild")
            unchanged.append(name)
        else:
            written.append(name)

    # The manifest keeps earlier versions (and other models) whose files are still hosted here.
    merged = {(e.id, e.version): e for e in existing if (directory / e.file).is_file()}
    merged.update(built)
    manifest = tuple(sorted(merged.values(), key=lambda e: (e.id, e.version, e.file)))
    try:
        _write_atomically(directory, {n: outputs[n] for n in written}, manifest_bytes(manifest))
    except OSError as err:
        raise CdfError(f"cannot write the bundle: {err.strerror or err}", where=str(directory),
                       hint="nothing was changed; the directory's parent must exist or be creatable, "
                            "and be writable") from None
    return BuildResult(directory=directory, entries=tuple(entries), manifest=manifest, written=tuple(written),
                       unchanged=tuple(unchanged), skipped=tuple(skipped))


def _write_atomically(directory: Path, files: dict[str, bytes], manifest: bytes) -> None:
    """Write into a temporary directory, then rename into place: a new bundle directory appears whole; in
    an existing one each file appears whole, the manifest last."""
    parent = directory.parent if not directory.exists() else directory
    parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".wiris-build-", dir=parent))
    try:
        for name, content in {**files, MANIFEST: manifest}.items():
            path = tmp / name
            with open(path, "wb") as fh:
                fh.write(content)
                fh.flush()
                os.fsync(fh.fileno())
            os.chmod(path, 0o644)
        if not directory.exists():
            os.chmod(tmp, 0o755)
            os.rename(tmp, directory)
            return
        moved: list[Path] = []
        try:
            for name in files:   # only names that did not exist: nothing published is replaced
                os.replace(tmp / name, directory / name)
                moved.append(directory / name)
            manifest_path = directory / MANIFEST
            if not (manifest_path.is_file() and manifest_path.read_bytes() == manifest):
                os.replace(tmp / MANIFEST, manifest_path)
        except BaseException:
            for path in moved:   # roll back: the directory is as it was
                path.unlink(missing_ok=True)
            raise
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["BundleEntry", "BuildResult", "MANIFEST", "URI_MAX", "build_bundle", "definition_uri",
           "manifest_bytes", "xz_bytes"]
