"""Typed values of CDF parameters: the lexical forms every parser reads the same way."""

from __future__ import annotations

import re
import struct

from cdf.paramtypes import FLOAT32_MAX, FLOAT_TYPES, INT_RANGES, KNOWN_TYPES, NUMERIC_TYPES, STOI_MAX, STOI_TYPES

__all__ = ["FLOAT32_MAX", "FLOAT_TYPES", "INT_RANGES", "KNOWN_TYPES", "NUMERIC_TYPES", "STOI_MAX", "STOI_TYPES",
           "canonical_int", "lexically_valid", "parse_typed"]

INTEGER = re.compile(r"-?[0-9]+")
DECIMAL = re.compile(r"[-+]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]+)?")


def parse_typed(text: str | None, ptype: str) -> tuple[int | float | None, str | None]:
    """(value, None) or (None, why not). Floats come back rounded to the wire precision."""
    if text is None:
        return None, "missing"
    s = text.strip()
    if ptype in INT_RANGES:
        if not INTEGER.fullmatch(s):
            return None, f"{text!r} is not a plain decimal integer" + (
                " (MAVSDK's std::stoi throws on it and crashes the process)" if not re.match(r"\s*[-+]?[0-9]", text)
                else " (MAVSDK's std::stoi silently truncates it)")
        v = int(s)
        lo, hi = INT_RANGES[ptype]
        if not lo <= v <= hi:
            return None, f"{v} is outside the {ptype} range {lo}..{hi}"
        return v, None
    if ptype in FLOAT_TYPES:
        if not DECIMAL.fullmatch(s):
            return None, f"{text!r} is not a finite decimal number"
        v = float(s)
        if ptype == "float":
            if abs(v) > FLOAT32_MAX:
                return None, f"{text} does not fit a 32-bit float"
            v = struct.unpack("<f", struct.pack("<f", v))[0]
        elif v in (float("inf"), float("-inf")):
            return None, f"{text} does not fit a 64-bit double"
        return v, None
    return None, f"type {ptype!r} has no numeric values"


def lexically_valid(text: str, ptype: str) -> bool:
    """Whether mavlinkcamera.xsd's type for this parameter type accepts the text as written (no blanks
    trimmed; floats by their lexical form only, whatever their magnitude); other types are xs:string."""
    if ptype in INT_RANGES:
        lo, hi = INT_RANGES[ptype]
        return INTEGER.fullmatch(text) is not None and lo <= int(text) <= hi
    if ptype in FLOAT_TYPES:
        return DECIMAL.fullmatch(text) is not None
    return True


def canonical_int(text: str) -> bool:
    """QGC compares option text with rawValueString(): only canonical decimal integers match reliably."""
    s = text.strip()
    return bool(INTEGER.fullmatch(s)) and s == str(int(s)) and s == text
