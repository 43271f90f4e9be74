"""PARAM_EXT values on the wire: the typed value, byte-wise, little-endian, in the 128-byte param_value.

The camera protocol sends a PARAM_EXT value as the bytes of the C union holding it (common.xml PARAM_EXT_*;
devguide parameter_ext.md "Parameter Encoding"), tagged with MAV_PARAM_EXT_TYPE. QGC sends `bool` as UINT8
(QGCCameraIO.cc). pymavlink hands received char[128] fields over with trailing NULs stripped (and a str view
cut at the first NUL), so a binary value must be read from `_param_value_raw` and padded back.

Classic PARAM_SET/PARAM_VALUE carry a 4-byte float. A RedEdge reads those bytes "as a union ... interpreted
as the MAV_PARAM_TYPE listed" for the parameter (serial API PARAM_SET/PARAM_VALUE), i.e. byte-wise as well:
an integer parameter's value is the integer's bytes, which as a float are a tiny number (2 -> 2.8e-45).
encode_classic/decode_classic convert between the typed value and that float.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from cdf import paramtypes

VALUE_BYTES = 128  # PARAM_EXT_*.param_value is char[128]


@dataclass(frozen=True)
class WireType:
    cdf: str            # the camera definition's type name
    ext_type: int       # MAV_PARAM_EXT_TYPE
    fmt: str            # struct format, little-endian
    integer: bool


# Each wire type's MAV_PARAM_EXT_TYPE and struct format (little-endian). Which definition type travels as which
# wire type (bool as uint8), and whether it is an integer, come from the one type table, cdf/paramtypes.py.
_WIRE = {
    "uint8": (mavlink2.MAV_PARAM_EXT_TYPE_UINT8, "<B"), "int8": (mavlink2.MAV_PARAM_EXT_TYPE_INT8, "<b"),
    "uint16": (mavlink2.MAV_PARAM_EXT_TYPE_UINT16, "<H"), "int16": (mavlink2.MAV_PARAM_EXT_TYPE_INT16, "<h"),
    "uint32": (mavlink2.MAV_PARAM_EXT_TYPE_UINT32, "<I"), "int32": (mavlink2.MAV_PARAM_EXT_TYPE_INT32, "<i"),
    "uint64": (mavlink2.MAV_PARAM_EXT_TYPE_UINT64, "<Q"), "int64": (mavlink2.MAV_PARAM_EXT_TYPE_INT64, "<q"),
    "float": (mavlink2.MAV_PARAM_EXT_TYPE_REAL32, "<f"), "double": (mavlink2.MAV_PARAM_EXT_TYPE_REAL64, "<d"),
}
_TYPES = tuple(WireType(name, *_WIRE[name], paramtypes.BY_NAME[name].range is not None) for name in _WIRE)
BY_CDF = {t.name: WireType(t.name, *_WIRE[t.wire], t.range is not None) for t in paramtypes.TYPES if t.wire in _WIRE}
BY_EXT = {t.ext_type: t for t in _TYPES}


class WireValueError(ValueError):
    """A value that cannot be carried by the declared type."""


def wire_type(cdf_type: str) -> WireType:
    try:
        return BY_CDF[cdf_type.lower()]
    except KeyError:
        raise WireValueError(f"type {cdf_type!r} has no PARAM_EXT number encoding") from None


def encode(value: float | int, cdf_type: str) -> bytes:
    """The 128-byte param_value for `value` of a definition type (WireValueError if it does not fit)."""
    wt = wire_type(cdf_type)
    if wt.integer:
        if isinstance(value, float) and (not math.isfinite(value) or value != int(value)):
            raise WireValueError(f"{value!r} is not a whole number for {cdf_type}")
        value = int(value)
    else:
        value = float(value)
    try:
        raw = struct.pack(wt.fmt, value)
    except (struct.error, OverflowError):
        raise WireValueError(f"{value!r} does not fit {cdf_type}") from None
    return raw.ljust(VALUE_BYTES, b"\0")


def raw_value(msg) -> bytes:
    """The full 128 bytes of a received PARAM_EXT_SET/VALUE/ACK's param_value."""
    raw = getattr(msg, "_param_value_raw", None)
    if raw is None:
        raw = msg.param_value.encode("latin-1") if isinstance(msg.param_value, str) else bytes(msg.param_value)
    return bytes(raw[:VALUE_BYTES]).ljust(VALUE_BYTES, b"\0")


def decode(raw: bytes, cdf_type: str) -> float | int:
    wt = wire_type(cdf_type)
    size = struct.calcsize(wt.fmt)
    return struct.unpack(wt.fmt, bytes(raw[:size]).ljust(size, b"\0"))[0]


def decode_ext(raw: bytes, ext_type: int) -> float | int | None:
    """Decode by the MAV_PARAM_EXT_TYPE a message carries (None for CUSTOM or an unknown number)."""
    wt = BY_EXT.get(ext_type)
    if wt is None:
        return None
    return decode(raw, wt.cdf)


# definition type -> MAV_PARAM_TYPE of a classic parameter (4 bytes at most: the value is a float's bytes)
CLASSIC_TYPES = {"uint8": mavlink2.MAV_PARAM_TYPE_UINT8, "int8": mavlink2.MAV_PARAM_TYPE_INT8,
                 "uint16": mavlink2.MAV_PARAM_TYPE_UINT16, "int16": mavlink2.MAV_PARAM_TYPE_INT16,
                 "uint32": mavlink2.MAV_PARAM_TYPE_UINT32, "int32": mavlink2.MAV_PARAM_TYPE_INT32,
                 "float": mavlink2.MAV_PARAM_TYPE_REAL32}
_CLASSIC_BY_NUMBER = {number: cdf for cdf, number in CLASSIC_TYPES.items()}


def classic_type(cdf_type: str) -> int:
    """The MAV_PARAM_TYPE of a classic parameter of this definition type (WireValueError if 4 bytes cannot
    carry it)."""
    try:
        return CLASSIC_TYPES[cdf_type.lower()]
    except KeyError:
        raise WireValueError(f"type {cdf_type!r} does not fit a classic parameter's 4 bytes") from None


def encode_classic(value: float | int, cdf_type: str) -> float:
    """The float whose 4 bytes are `value` as `cdf_type` (WireValueError if it does not fit, or if its bytes
    are a signalling NaN pattern, which this Python's float conversion would not carry unchanged)."""
    classic_type(cdf_type)
    raw = encode(value, cdf_type)[:4]
    carried = struct.unpack("<f", raw)[0]
    if struct.pack("<f", carried) != raw:
        raise WireValueError(f"{value!r} as {cdf_type} cannot be carried in a float's bytes")
    return carried


def decode_classic(param_value: float, param_type: int) -> float | int | None:
    """The typed value a classic PARAM_VALUE carries (None for a type wider than 4 bytes or unknown)."""
    cdf = _CLASSIC_BY_NUMBER.get(param_type)
    if cdf is None:
        return None
    try:
        raw = struct.pack("<f", param_value)
    except (struct.error, OverflowError):
        return None
    return decode(raw, cdf)


def param_id(msg) -> str:
    """param_id as text: char[16], NUL-terminated unless exactly 16 characters long."""
    raw = getattr(msg, "_param_id_raw", None)
    if raw is None:
        return str(msg.param_id)
    return bytes(raw).split(b"\0", 1)[0].decode("ascii", errors="replace")
