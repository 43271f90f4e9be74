"""Typed values of CDF parameters: the lexical forms every parser reads the same way."""

from __future__ import annotations

import re
import struct

INT_RANGES: dict[str, tuple[int, int]] = {
    "bool": (0, 1), "uint8": (0, 255), "int8": (-128, 127), "uint16": (0, 65535), "int16": (-32768, 32767),
    "uint32": (0, 2**32 - 1), "int32": (-2**31, 2**31 - 1), "uint64": (0, 2**64 - 1), "int64": (-2**63, 2**63 - 1),
}
FLOAT_TYPES = ("float", "double")
NUMERIC_TYPES = tuple(INT_RANGES) + FLOAT_TYPES
# MAV_PARAM_EXT_TYPE has no string; QGC maps string and custom to CUSTOM (reference §1.3, §1.5).
KNOWN_TYPES = NUMERIC_TYPES + ("custom", "string")
# std::stoi (int, 32-bit) is what MAVSDK's ParamValue::set_from_xml uses for these types (reference §4.2).
STOI_TYPES = ("bool", "uint8", "int8", "uint16", "int16", "uint32", "int32")
STOI_MAX = 2**31 - 1
from cdf.float32 import FLOAT32_MAX  # noqa: E402

_INT = re.compile(r"-?[0-9]+")
_FLOAT = re.compile(r"[-+]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]+)?")


def parse_typed(text: str | None, ptype: str) -> tuple[int | float | None, str | None]:
    """(value, None) or (None, why not). Floats come back rounded to the wire precision."""
    if text is None:
        return None, "missing"
    s = text.strip()
    if ptype in INT_RANGES:
        if not _INT.fullmatch(s):
            return None, f"{text!r} is not a plain decimal integer" + (
                " (MAVSDK's std::stoi throws on it and crashes the process)" if not re.match(r"\s*[-+]?[0-9]", text)
                else " (MAVSDK's std::stoi silently truncates it)")
        v = int(s)
        lo, hi = INT_RANGES[ptype]
        if not lo <= v <= hi:
            return None, f"{v} is outside the {ptype} range {lo}..{hi}"
        return v, None
    if ptype in FLOAT_TYPES:
        if not _FLOAT.fullmatch(s):
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


def canonical_int(text: str) -> bool:
    """QGC compares option text with rawValueString(): only canonical decimal integers match reliably."""
    s = text.strip()
    return bool(_INT.fullmatch(s)) and s == str(int(s)) and s == text
