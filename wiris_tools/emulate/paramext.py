"""PARAM_EXT values on the wire: the typed value, byte-wise, little-endian, in the 128-byte param_value.

The camera protocol sends a PARAM_EXT value as the bytes of the C union holding it (common.xml PARAM_EXT_*;
devguide parameter_ext.md "Parameter Encoding"), tagged with MAV_PARAM_EXT_TYPE. QGC sends `bool` as UINT8
(QGCCameraIO.cc). pymavlink hands received char[128] fields over with trailing NULs stripped (and a str view
cut at the first NUL), so a binary value must be read from `_param_value_raw` and padded back.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

VALUE_BYTES = 128  # PARAM_EXT_*.param_value is char[128]


@dataclass(frozen=True)
class WireType:
    cdf: str            # the camera definition's type name
    ext_type: int       # MAV_PARAM_EXT_TYPE
    fmt: str            # struct format, little-endian
    integer: bool


_TYPES = (
    WireType("uint8", mavlink2.MAV_PARAM_EXT_TYPE_UINT8, "<B", True),
    WireType("int8", mavlink2.MAV_PARAM_EXT_TYPE_INT8, "<b", True),
    WireType("uint16", mavlink2.MAV_PARAM_EXT_TYPE_UINT16, "<H", True),
    WireType("int16", mavlink2.MAV_PARAM_EXT_TYPE_INT16, "<h", True),
    WireType("uint32", mavlink2.MAV_PARAM_EXT_TYPE_UINT32, "<I", True),
    WireType("int32", mavlink2.MAV_PARAM_EXT_TYPE_INT32, "<i", True),
    WireType("uint64", mavlink2.MAV_PARAM_EXT_TYPE_UINT64, "<Q", True),
    WireType("int64", mavlink2.MAV_PARAM_EXT_TYPE_INT64, "<q", True),
    WireType("float", mavlink2.MAV_PARAM_EXT_TYPE_REAL32, "<f", False),
    WireType("double", mavlink2.MAV_PARAM_EXT_TYPE_REAL64, "<d", False),
)
BY_CDF = {t.cdf: t for t in _TYPES} | {"bool": WireType("bool", mavlink2.MAV_PARAM_EXT_TYPE_UINT8, "<B", True)}
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


def param_id(msg) -> str:
    """param_id as text: char[16], NUL-terminated unless exactly 16 characters long."""
    raw = getattr(msg, "_param_id_raw", None)
    if raw is None:
        return str(msg.param_id)
    return bytes(raw).split(b"\0", 1)[0].decode("ascii", errors="replace")
