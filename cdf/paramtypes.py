"""The parameter types of camera definition files: one table for the validator, the catalogue and the generator.

camera_def.md §Parameter Types lists bool ("internally treated as a uint8"), the eight integer types,
float, double and custom; `string` is a QGC extension the validator warns about. How MAVSDK reads a
value decides the largest one it accepts: `ParamValue::set_from_xml` uses std::stoi for bool and the
8-, 16- and 32-bit types (uint32 included), std::stoll for the 64-bit ones and stof/stod for floats
(../shared/reference/camera-definition-files.md §4.2). The PARAM_EXT wire codec of the emulators
(wiris_tools/paramext.py) derives its types from this table and adds their struct formats.
"""

from __future__ import annotations

from typing import NamedTuple

from cdf.float32 import FLOAT32_MAX  # noqa: F401 (one of the type table's limits, re-exported)

STOI_MAX = 2**31 - 1  # std::stoi returns an int
STOLL_MAX = 2**63 - 1  # std::stoll returns a long long


class ParamType(NamedTuple):
    name: str
    range: tuple[int, int] | None  # the integers the type holds; None for floats and text
    mavsdk_reads_with: str | None  # MAVSDK's std:: conversion of the XML text; None: not a number
    wire: str  # the type whose PARAM_EXT_TYPE carries it (bool travels as UINT8, string as CUSTOM)


TYPES: tuple[ParamType, ...] = (
    ParamType("bool", (0, 1), "stoi", "uint8"),
    ParamType("uint8", (0, 255), "stoi", "uint8"),
    ParamType("int8", (-128, 127), "stoi", "int8"),
    ParamType("uint16", (0, 65535), "stoi", "uint16"),
    ParamType("int16", (-32768, 32767), "stoi", "int16"),
    ParamType("uint32", (0, 2**32 - 1), "stoi", "uint32"),
    ParamType("int32", (-2**31, 2**31 - 1), "stoi", "int32"),
    ParamType("uint64", (0, 2**64 - 1), "stoll", "uint64"),
    ParamType("int64", (-2**63, 2**63 - 1), "stoll", "int64"),
    ParamType("float", None, "stof", "float"),
    ParamType("double", None, "stod", "double"),
    ParamType("custom", None, None, "custom"),
    ParamType("string", None, None, "custom"),
)
BY_NAME: dict[str, ParamType] = {t.name: t for t in TYPES}

INT_RANGES: dict[str, tuple[int, int]] = {t.name: t.range for t in TYPES if t.range is not None}
FLOAT_TYPES = tuple(t.name for t in TYPES if t.mavsdk_reads_with in ("stof", "stod"))
NUMERIC_TYPES = tuple(INT_RANGES) + FLOAT_TYPES
KNOWN_TYPES = tuple(BY_NAME)
STOI_TYPES = tuple(t.name for t in TYPES if t.mavsdk_reads_with == "stoi")
_READ_MAX = {"stoi": STOI_MAX, "stoll": STOLL_MAX}


def mavsdk_range(name: str) -> tuple[int, int]:
    """The integers of an integer type that MAVSDK also reads: its range cut at what std::stoi or std::stoll
    returns (a uint32 above 2**31-1 throws out_of_range and crashes the process)."""
    t = BY_NAME[name]
    lo, hi = t.range
    return lo, min(hi, _READ_MAX[t.mavsdk_reads_with])


def wire_name(name: str) -> str:
    """The type a PARAM_EXT value of this type travels as; an unknown name stands for itself."""
    t = BY_NAME.get(name)
    return t.wire if t is not None else name
