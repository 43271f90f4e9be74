"""validate_bytes / validate_source: load safely, run the XSD and the semantic rules, apply a profile."""

from __future__ import annotations

from pathlib import Path

from cdf.errors import CdfError
from cdf.validation.report import Finding, Hit, Report
from cdf.validation.rules import PROFILES, RULES_BY_ID
from cdf.validation.schema import schema_hits
from cdf.validation.semantic import CameraInfo, check_camera, check_document
from cdf.xmlsafe import HTTP_TIMEOUT_S, inflate, parse_xml, read_source


def _hits(data: bytes, name: str, camera_info: CameraInfo | None) -> tuple[list[Hit], int]:
    """Every finding of one definition before the profile, and its number of <parameter> elements."""
    loaded = inflate(data, name)
    hits = [Hit(p.rule, p.line, None, p.message) for p in loaded.problems]
    if loaded.data is None:
        return hits, 0
    root, problems = parse_xml(loaded.data, name)
    hits += [Hit(p.rule, p.line, None, p.message) for p in problems]
    if root is None:
        return hits, 0
    hits += check_document(root, loaded.data)
    hits += schema_hits(root)
    if camera_info is not None:
        hits += check_camera(root, camera_info)
    return hits, _parameter_count(root)


def _parameter_count(root) -> int:
    """The <parameter> children of the <parameters> section that the rules read."""
    params = root.find("parameters")
    if params is None:
        params = next(root.iter("parameters"), None)
    return len(params.findall("parameter")) if params is not None else 0


def validate_bytes(data: bytes, name: str = "<bytes>", profile: str = "strict", *,
                   camera_info: CameraInfo | None = None) -> Report:
    """Validate one definition (plain XML or xz, detected by magic number) in one profile.

    Never raises for bad content: every problem is a finding. Raises CdfError for an unknown profile.
    `camera_info` enables the CDF3xx checks against what the camera reports.
    """
    if profile not in PROFILES:
        raise CdfError(f"unknown profile {profile!r}", hint=f"choose one of {', '.join(PROFILES)}")
    hits, count = _hits(bytes(data), name, camera_info)
    findings = []
    for h in hits:
        severity = RULES_BY_ID[h.rule].severity(profile)
        if severity is not None:
            findings.append(Finding(h.rule, severity, h.line, h.parameter, h.message))
    findings.sort(key=lambda f: (f.line is not None, f.line or 0, f.rule))
    return Report(name, profile, count, tuple(dict.fromkeys(findings)))


def validate_source(source: str | Path, profile: str = "strict", *, camera_info: CameraInfo | None = None,
                    timeout_s: float = HTTP_TIMEOUT_S) -> Report:
    """Validate a file path or an http(s) URL. Raises CdfError when the source cannot be read."""
    data = read_source(source, timeout_s=timeout_s)
    return validate_bytes(data, str(source), profile, camera_info=camera_info)
