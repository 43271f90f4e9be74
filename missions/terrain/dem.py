"""Digital elevation models: read GeoTIFFs (any projected or geographic CRS) and SRTM .hgt tiles with rasterio,
and sample ground heights above mean sea level (EGM96) bilinearly at WGS84 positions.

    dem = load_dem(["n50e014.hgt", "lidar.tif"], base_dir, vertical="auto", where="plan.yaml:3:8")
    dem.ground_amsl(lats, lons)          # metres above the EGM96 geoid; NaN where no file has a height
    dem.ground_at(lats, lons, "the survey area", where)   # the same, a PlanError naming the first gap

Several files are one mosaic: at each position the first file (in the plan's order) with a height there gives
it, so a fine local model listed first wins over a coarse tile under it.

Vertical datum. Mission altitudes in MAV_FRAME_GLOBAL are above mean sea level as the autopilot's GNSS gives it
(receivers report MSL through the EGM96 geoid or a model close to it), so every height is brought to EGM96:
- the file's CRS says (a compound CRS with a vertical part, or a 3D geographic CRS): EGM96 heights (EPSG:5773)
  are used as they are, EGM2008 (EPSG:3855) too (the two geoids differ by less than a metre over most land, a
  few metres in high mountains), ellipsoidal heights have the EGM96 undulation subtracted (`geoid.py`);
- an SRTM .hgt tile is EGM96 by NASA's definition of the product;
- a file that does not say is taken as above mean sea level (SRTM, ASTER GDEM and most national models are),
  and the report says it was assumed; `terrain.vertical: ellipsoid` in the plan overrides it (e.g. a
  photogrammetry DSM straight from GNSS heights).
Vertical units other than metres are converted when the CRS names them.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from missions.errors import PlanError

VERTICAL_CHOICES = ("auto", "egm96", "ellipsoid")
# Pixels read per file: an SRTM1 tile (3601 x 3601) is 13 M; this is a 1 m model of 10 km x 10 km. Larger
# files are better clipped to the survey (gdal_translate -projwin) than held in memory whole.
MAX_PIXELS = 100_000_000
# Metres per degree of latitude (WGS84 mean), for a geographic DEM's resolution in metres.
M_PER_DEG = 111_320.0
_EGM96_EPSG, _EGM2008_EPSG = 5773, 3855
_CLIP_HINT = "clip or resample it to the survey's surroundings (gdal_translate -projwin ... or -tr ...)"


@dataclass(frozen=True)
class DemInfo:
    """One DEM file as the report describes it."""

    path: str
    crs: str                     # e.g. "EPSG:32633 (WGS 84 / UTM zone 33N)"
    vertical: str                # "EGM96 geoid", "EGM2008 geoid", "WGS84 ellipsoid (converted to EGM96)"
    vertical_source: str         # "the file's CRS", "SRTM .hgt (EGM96 by definition)", "assumed", "the plan"
    resolution_m: float          # the coarser pixel side, metres
    size_px: tuple[int, int]     # width, height

    def to_json(self) -> dict[str, Any]:
        return {"path": self.path, "crs": self.crs, "vertical": self.vertical,
                "vertical_source": self.vertical_source, "resolution_m": round(self.resolution_m, 3),
                "size_px": list(self.size_px)}


@dataclass(frozen=True)
class _Raster:
    """One file's heights (float32, NaN = nodata) and how a WGS84 position finds its pixel."""

    info: DemInfo
    heights: np.ndarray
    inverse: tuple[float, float, float, float, float, float]   # CRS x/y -> column/row (affine a, b, c, d, e, f)
    to_crs: Any                                                 # pyproj Transformer, lon/lat -> CRS x/y
    ellipsoidal: bool
    unit_m: float

    def sample(self, lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
        """Bilinear heights above EGM96 (NaN outside the file or next to a nodata pixel)."""
        x, y = self.to_crs.transform(lon, lat)
        a, b, c, d, e, f = self.inverse
        col = a * x + b * y + c - 0.5           # pixel centres sit at half-integers of the geotransform
        row = d * x + e * y + f - 0.5
        h, w = self.heights.shape
        inside = np.isfinite(col) & np.isfinite(row) & (col >= -0.5) & (col <= w - 0.5) & (row >= -0.5) \
            & (row <= h - 0.5)
        col = np.clip(np.where(inside, col, 0.0), 0.0, w - 1.0)
        row = np.clip(np.where(inside, row, 0.0), 0.0, h - 1.0)
        c0 = np.minimum(np.floor(col).astype(int), max(w - 2, 0))
        r0 = np.minimum(np.floor(row).astype(int), max(h - 2, 0))
        c1, r1 = np.minimum(c0 + 1, w - 1), np.minimum(r0 + 1, h - 1)
        fc, fr = col - c0, row - r0
        z = self.heights
        top = z[r0, c0] * (1 - fc) + z[r0, c1] * fc
        bottom = z[r1, c0] * (1 - fc) + z[r1, c1] * fc
        out = (top * (1 - fr) + bottom * fr) * self.unit_m
        out = np.where(inside, out, np.nan)
        if self.ellipsoidal:
            from missions.terrain.geoid import undulation_m
            out = out - undulation_m(lat, lon)
        return out


class Dem:
    """A mosaic of DEM files (first file with a height wins), read once; immutable after loading."""

    def __init__(self, rasters: Sequence[_Raster]) -> None:
        self._rasters = tuple(rasters)

    @property
    def files(self) -> tuple[DemInfo, ...]:
        return tuple(r.info for r in self._rasters)

    @property
    def resolution_m(self) -> float:
        """The finest file's pixel: the step at which paths are sampled against the ground."""
        return min(r.info.resolution_m for r in self._rasters)

    def ground_amsl(self, lat: Any, lon: Any) -> np.ndarray:
        lat = np.atleast_1d(np.asarray(lat, dtype=float))
        lon = np.atleast_1d(np.asarray(lon, dtype=float))
        out = np.full(lat.shape, np.nan)
        for r in self._rasters:
            gap = np.isnan(out)
            if not gap.any():
                break
            out[gap] = r.sample(lat[gap], lon[gap])
        return out

    def ground_at(self, lat: Any, lon: Any, what: str, where: str | None) -> np.ndarray:
        """`ground_amsl`, or a PlanError naming the first position no file has a height for."""
        z = self.ground_amsl(lat, lon)
        bad = np.flatnonzero(~np.isfinite(z))
        if len(bad):
            la, lo = np.atleast_1d(lat)[bad[0]], np.atleast_1d(lon)[bad[0]]
            raise PlanError(f"no ground height in the DEM under {what} at {la:.6f}, {lo:.6f} "
                            f"({len(bad)} of {len(z)} sampled points): outside "
                            f"{'its file' if len(self._rasters) == 1 else 'all its files'} or on a nodata hole",
                            where=where,
                            hint="give a DEM that covers the whole flight (a list of files is mosaicked) and has "
                                 "its holes filled (gdal_fillnodata.py)")
        return z


# ------------------------------------------------------------------------------------------------ loading

def load_dem(paths: Sequence[str], base_dir: str | Path, vertical: str = "auto", where: str | None = None) -> Dem:
    """Read every file of `paths` (relative to `base_dir`); PlanError for a file that cannot serve."""
    if vertical not in VERTICAL_CHOICES:
        raise PlanError(f"terrain.vertical {vertical!r} is not one of {', '.join(VERTICAL_CHOICES)}", where=where,
                        hint="auto: as the file says; egm96: heights above mean sea level; ellipsoid: above WGS84")
    return Dem([_read(_resolve(p, base_dir), vertical, where) for p in paths])


def _resolve(p: str, base_dir: str | Path) -> Path:
    path = Path(p)
    return path if path.is_absolute() else Path(base_dir) / path


def _rasterio(where: str | None) -> Any:
    """rasterio (GDAL), loaded only for a plan with a DEM; an optional dependency (the `terrain` extra)."""
    try:
        import rasterio
        import rasterio.errors
    except ImportError:
        raise PlanError("reading a DEM needs rasterio, which is not installed", where=where,
                        hint="pip install 'wiris-tools[terrain]' (or pip install rasterio) in the tools' "
                             "environment") from None
    return rasterio


def _read(path: Path, vertical: str, where: str | None) -> _Raster:
    rasterio = _rasterio(where)

    if not path.is_file():
        raise PlanError(f"DEM file {str(path)!r} {'is not a file' if path.exists() else 'not found'}", where=where,
                        hint="paths in a plan are relative to the plan file; give a GeoTIFF (.tif) or SRTM .hgt")
    try:
        with rasterio.open(path) as ds:
            return _raster(ds, path, vertical, where)
    except rasterio.errors.RasterioError as e:     # not a raster, truncated, an unknown format: GDAL says which
        raise PlanError(f"DEM file {path.name} cannot be read as a raster: {_first_line(e)}", where=where,
                        hint="give a GeoTIFF (.tif) or an SRTM tile named like N50E014.hgt") from None


def _first_line(e: Exception) -> str:
    return (str(e).strip().splitlines() or [type(e).__name__])[0][:200]


def _raster(ds: Any, path: Path, vertical: str, where: str | None) -> _Raster:
    if ds.crs is None:
        raise PlanError(f"DEM file {path.name} has no coordinate reference system", where=where,
                        hint="assign the one it was made in, e.g. gdal_edit.py -a_srs EPSG:32633 FILE")
    if ds.width * ds.height > MAX_PIXELS:
        raise PlanError(f"DEM file {path.name} has {ds.width} x {ds.height} pixels, more than the "
                        f"{MAX_PIXELS:,} one file may have", where=where, hint=_CLIP_HINT)
    crs = _pyproj_crs(ds, path, where)
    horizontal, ellipsoidal_crs, vertical_crs = _split_crs(crs)
    to_crs = _transformer(horizontal, path, where)
    heights = _heights(ds, path, where)
    info, ellipsoidal, unit = _vertical(path, ds.driver, horizontal, ellipsoidal_crs, vertical_crs, vertical)
    t = ~ds.transform
    res = _resolution_m(ds, horizontal)
    return _Raster(DemInfo(str(path), info[0], info[1], info[2], res, (ds.width, ds.height)), heights,
                   (t.a, t.b, t.c, t.d, t.e, t.f), to_crs, ellipsoidal, unit)


def _pyproj_crs(ds: Any, path: Path, where: str | None) -> Any:
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        return CRS.from_wkt(ds.crs.to_wkt())
    except CRSError as e:
        raise PlanError(f"DEM file {path.name}'s coordinate reference system is not understood: {_first_line(e)}",
                        where=where, hint="reproject it to a standard CRS (gdalwarp -t_srs EPSG:4326)") from None


def _split_crs(crs: Any) -> tuple[Any, bool, Any]:
    """(horizontal CRS, whether its heights are ellipsoidal (a 3D geographic CRS), the vertical CRS or None)."""
    if crs.is_compound:
        subs = crs.sub_crs_list
        return subs[0], False, subs[1] if len(subs) > 1 else None
    if crs.is_geographic and len(crs.axis_info) == 3:
        return crs.geodetic_crs if crs.geodetic_crs is not None else crs, True, None
    return crs, False, None


def _transformer(horizontal: Any, path: Path, where: str | None) -> Any:
    from pyproj import CRS, Transformer
    from pyproj.exceptions import CRSError, ProjError

    try:
        t = Transformer.from_crs(CRS.from_epsg(4326), horizontal, always_xy=True)
    except (ProjError, CRSError) as e:           # e.g. a CRS of another body, or one PROJ has no way to
        raise PlanError(f"DEM file {path.name}'s CRS ({horizontal.name}) cannot be transformed from WGS84: "
                        f"{_first_line(e)}", where=where,
                        hint="reproject it to EPSG:4326 or a UTM zone with gdalwarp -t_srs") from None
    return t


def _heights(ds: Any, path: Path, where: str | None) -> np.ndarray:
    band = ds.read(1, masked=True).astype(np.float32)
    heights = band.filled(np.nan)
    heights[~np.isfinite(heights)] = np.nan
    # the SRTM void value, also when a file does not declare it as its nodata
    heights[heights <= -32767] = np.nan
    if not np.isfinite(heights).any():
        raise PlanError(f"DEM file {path.name} holds no heights (every pixel is nodata)", where=where,
                        hint="check the file: its nodata value may be set to the value of every pixel")
    return heights


def _vertical(path: Path, driver: str, horizontal: Any, ellipsoidal_crs: bool, vertical_crs: Any,
              choice: str) -> tuple[tuple[str, str, str], bool, float]:
    """((CRS text, vertical datum text, where it came from), heights are ellipsoidal, metres per height unit)."""
    crs_text = _crs_text(horizontal)
    unit = 1.0
    if vertical_crs is not None:
        axis = vertical_crs.axis_info[0] if vertical_crs.axis_info else None
        unit = float(axis.unit_conversion_factor) if axis is not None and axis.unit_conversion_factor else 1.0
        crs_text += f" + {vertical_crs.name}"
    if choice == "ellipsoid":
        return (crs_text, "WGS84 ellipsoid (converted to EGM96)", "the plan"), True, unit
    if choice == "egm96":
        return (crs_text, "EGM96 geoid", "the plan"), False, unit
    if ellipsoidal_crs:
        return (crs_text, "WGS84 ellipsoid (converted to EGM96)", "the file's CRS"), True, unit
    if vertical_crs is not None:
        epsg = vertical_crs.to_epsg()
        if epsg == _EGM2008_EPSG:
            return (crs_text, "EGM2008 geoid (taken as EGM96: within ~1 m over most land)", "the file's CRS"), \
                False, unit
        name = "EGM96 geoid" if epsg == _EGM96_EPSG else vertical_crs.name
        return (crs_text, name, "the file's CRS"), False, unit
    if driver == "SRTMHGT" or path.suffix.lower() == ".hgt":
        return (crs_text, "EGM96 geoid", "SRTM .hgt (EGM96 by definition)"), False, unit
    return (crs_text, "mean sea level (EGM96 assumed)", "assumed: the file does not say"), False, unit


def _crs_text(crs: Any) -> str:
    epsg = crs.to_epsg()
    return f"EPSG:{epsg} ({crs.name})" if epsg else crs.name


def _resolution_m(ds: Any, horizontal: Any) -> float:
    rx, ry = abs(ds.res[0]), abs(ds.res[1])
    if horizontal.is_geographic:
        b = ds.bounds
        lat = math.radians(max(-85.0, min(85.0, 0.5 * (b.top + b.bottom))))
        return max(rx * M_PER_DEG * math.cos(lat), ry * M_PER_DEG)
    axis = horizontal.axis_info[0] if horizontal.axis_info else None
    unit = float(axis.unit_conversion_factor) if axis is not None and axis.unit_conversion_factor else 1.0
    return max(rx, ry) * unit


class PlaneGround:
    """The DEM resampled on a regular grid of a metric plane (a LocalProjection), for many look-ups near each
    other (the report's footprint rays): one coordinate transformation for the grid instead of one per ray.
    Heights between grid nodes are bilinear; NaN where the DEM has none."""

    MAX_NODES = 4_000_000

    def __init__(self, dem: Dem, projection: Any, box: tuple[float, float, float, float], step_m: float) -> None:
        x0, y0, x1, y1 = box
        step = max(step_m, math.sqrt(max((x1 - x0) * (y1 - y0), 1.0) / self.MAX_NODES))
        nx, ny = int(math.ceil((x1 - x0) / step)) + 2, int(math.ceil((y1 - y0) / step)) + 2
        self.x0, self.y0, self.step = x0 - step / 2, y0 - step / 2, step
        xs, ys = self.x0 + step * np.arange(nx), self.y0 + step * np.arange(ny)
        X, Y = np.meshgrid(xs, ys)
        lat, lon = projection.to_latlon(X.ravel(), Y.ravel())
        self.z = dem.ground_amsl(lat, lon).reshape(ny, nx)

    def at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        ny, nx = self.z.shape
        c = (np.asarray(x, dtype=float) - self.x0) / self.step
        r = (np.asarray(y, dtype=float) - self.y0) / self.step
        inside = (c >= 0) & (c <= nx - 1) & (r >= 0) & (r <= ny - 1)
        c, r = np.clip(c, 0, nx - 1.000001), np.clip(r, 0, ny - 1.000001)
        c0, r0 = np.floor(c).astype(int), np.floor(r).astype(int)
        fc, fr = c - c0, r - r0
        z = self.z
        v = (z[r0, c0] * (1 - fc) + z[r0, c0 + 1] * fc) * (1 - fr) + (z[r0 + 1, c0] * (1 - fc) + z[r0 + 1, c0 + 1] * fc) * fr
        return np.where(inside, v, np.nan)
