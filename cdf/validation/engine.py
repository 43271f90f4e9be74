"""validate_bytes / validate_source: load safely, run the XSD and the semantic rules, apply a profile."""

from __future__ import annotations

from pathlib import Path

from cdf.errors import CdfError
from cdf.validation import schema, semantic
from cdf.validation.report import Finding, Report
from cdf.validation.rules import PROFILES, RULES_BY_ID
from cdf.validation.schema import Hit, schema_hits
from cdf.validation.semantic import CameraInfo, check_camera, check_document, prove_tree, walk_tree
from cdf.validation.vocabulary import _has
from cdf.xmlsafe import HTTP_TIMEOUT_S, TOO_DEEP, inflate, parse_xml, read_source, too_deep


def _hits(data: bytes, name: str, camera_info: CameraInfo | None) -> tuple[list[Hit], int]:
    loaded = inflate(data, name)
    hits = [Hit(p.rule, p.line, None, p.message) for p in loaded.problems]
    if loaded.data is None:
        return hits, 0
    data = loaded.data
    # Whitespace-only text between elements is read by no rule once libxml2's proof settles the document
    # and no CDATA section can move text (below), so the tree is first built without it: a third fewer
    # nodes, parsed and proved faster. A document the proof leaves to the walk (which reads every text)
    # or that xmlschema must judge is parsed again as written. (Dropped are only blanks libxml2 calls
    # ignorable: never text next to other text, never an element's only content; inside a text element
    # that happens only beside a child node, which the proof rules out, or beside a CDATA section.)
    lean = _lean(data)
    root, problems = parse_xml(data, name, check_depth=False, keep_blank_text=not lean)  # depth tested below
    hits += [Hit(p.rule, p.line, None, p.message) for p in problems]
    if root is None:
        return hits, 0
    # the vocabulary rule and the XSD fast path's structure test
    scan = prove_tree(root, data)
    if scan is None:
        if lean:
            root, lean = parse_xml(data, name, check_depth=False)[0], False
        if too_deep(root):  # before anything recursive (xmlschema) sees the tree
            return hits + [Hit(TOO_DEEP.rule, TOO_DEEP.line, None, TOO_DEEP.message)], 0
        scan = walk_tree(root)
    attributes: list[tuple] = []  # each parameter's typed attributes, read once for both
    hits += check_document(root, data, scan, attributes)
    hits += schema_hits(root, scan.xsd_structure_ok, attributes,
                        as_written=(lambda: parse_xml(data, name, check_depth=False)[0]) if lean else None)
    if camera_info is not None:
        hits += check_camera(root, camera_info)
    params = next(root.iterchildren("parameters"), None)  # as check_document finds them
    if params is None:
        params = next(root.iter("parameters"), None)
    count = sum(1 for _ in params.iterchildren("parameter")) if params is not None else 0
    return hits, count


def _lean(data: bytes) -> bool:
    """Whether _hits may build the tree without blank text first: no CDATA section, whose text libxml2
    delivers after it has judged the blanks before it (`<description>  <![CDATA[x]]>` reads "x")."""
    return not _has(data, b"<![CDATA[", b"[")


def clear_caches() -> None:
    """Forget the values memoised across files: what a fresh process starts with (the bench starts every
    run cold)."""
    semantic._PARSED.clear()
    semantic._attribute_rules.cache_clear()
    semantic._condition_parts.cache_clear()
    schema._lexical_ok.cache_clear()
    schema._attributes_conform.cache_clear()


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
