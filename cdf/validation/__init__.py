"""Camera definition file validation: XSD (cdf/schema/mavlinkcamera.xsd) + semantic rules, three profiles.

    from cdf.validate import validate_bytes, validate_source
    report = validate_source("wiris.xml", profile="strict")     # or an http(s) URL, or .xml.xz
    report.valid, report.findings, report.to_json()

Rules and their severities per profile: cdf/validation/rules.py (documented in cdf/schema/RULES.md).
"""

from cdf.validation.engine import validate_bytes, validate_source
from cdf.validation.report import Finding, Report
from cdf.validation.rules import PROFILES, RULES, Rule
from cdf.validation.semantic import CameraInfo, uri_problems

__all__ = ["CameraInfo", "Finding", "PROFILES", "RULES", "Report", "Rule", "uri_problems", "validate_bytes",
           "validate_source"]
