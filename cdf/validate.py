"""Public entry points of CDF validation (see cdf.validation for the parts)."""

from cdf.validation import (PROFILES, RULES, CameraInfo, Finding, Report, Rule, uri_problems, validate_bytes,
                            validate_source)

__all__ = ["CameraInfo", "Finding", "PROFILES", "RULES", "Report", "Rule", "uri_problems", "validate_bytes",
           "validate_source"]
