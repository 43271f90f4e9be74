"""Synthetic DEM GeoTIFFs written with rasterio, and plans that fly over them (tests and bench).

Heights are functions of (east, north) metres from CENTRE; `write_dem` grids them in UTM zone 33N or in
EPSG:4326 degrees, optionally with a vertical CRS, nodata holes or no CRS at all.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

CENTRE = (50.07, 14.73)          # lat, lon: UTM zone 33N
BASE_M = 300.0                   # ground height at the centre of every shape below

Shape = Callable[[np.ndarray, np.ndarray], np.ndarray]


def slope(pct: float = 30.0, azimuth_deg: float = 90.0) -> Shape:
    """A plane rising `pct` % towards `azimuth_deg` (90: uphill to the east)."""
    a = np.radians(azimuth_deg)
    return lambda e, n: BASE_M + pct / 100.0 * (e * np.sin(a) + n * np.cos(a))


def hill(height_m: float = 80.0, radius_m: float = 150.0) -> Shape:
    return lambda e, n: BASE_M + height_m * np.exp(-(e ** 2 + n ** 2) / (2 * radius_m ** 2))


def valley(depth_m: float = 60.0, width_m: float = 120.0) -> Shape:
    """A north-south valley floor at the centre."""
    return lambda e, n: BASE_M + depth_m * (1 - np.exp(-(e ** 2) / (2 * width_m ** 2)))


def cliff(height_m: float = 60.0, at_e_m: float = 0.0) -> Shape:
    """Flat ground with a step of `height_m` up at east offset `at_e_m` (spread over one pixel)."""
    return lambda e, n: BASE_M + np.where(e > at_e_m, height_m, 0.0)


def flat() -> Shape:
    return lambda e, n: np.full_like(e, BASE_M)


def _utm():
    from pyproj import Transformer
    return Transformer.from_crs("EPSG:4326", "EPSG:32633", always_xy=True)


def write_dem(path: Path, shape: Shape, crs: str = "utm", half_m: float = 800.0, res_m: float = 5.0,
              holes: list[tuple[float, float, float]] = (), vertical_epsg: int | None = None,
              offset_m: float = 0.0, with_crs: bool = True, nodata: float = -9999.0) -> Path:
    """Write a GeoTIFF of `shape` over +-half_m around CENTRE; `holes` (east, north, radius) are nodata;
    `offset_m` is added to every height (e.g. a geoid undulation for an ellipsoidal file)."""
    import rasterio
    from rasterio.crs import CRS
    from rasterio.transform import from_origin

    lat0, lon0 = CENTRE
    n_px = int(round(2 * half_m / res_m))
    if crs == "utm":
        e0, n0 = _utm().transform(lon0, lat0)
        transform = from_origin(e0 - half_m, n0 + half_m, res_m, res_m)
        cols = (np.arange(n_px) + 0.5) * res_m - half_m
        E, N = np.meshgrid(cols, -cols)
        horizontal = 32633
    else:
        dlat = res_m / 111_320.0
        dlon = res_m / (111_320.0 * np.cos(np.radians(lat0)))
        transform = from_origin(lon0 - n_px / 2 * dlon, lat0 + n_px / 2 * dlat, dlon, dlat)
        lons = lon0 + ((np.arange(n_px) + 0.5) - n_px / 2) * dlon
        lats = lat0 - ((np.arange(n_px) + 0.5) - n_px / 2) * dlat
        LON, LAT = np.meshgrid(lons, lats)
        tr = _utm()
        e0, n0 = tr.transform(lon0, lat0)
        Eu, Nu = tr.transform(LON, LAT)
        E, N = Eu - e0, Nu - n0
        horizontal = 4326
    Z = shape(E, N).astype(np.float32) + np.float32(offset_m)
    for he, hn, r in holes:
        Z[(E - he) ** 2 + (N - hn) ** 2 < r * r] = nodata
    if not with_crs:
        ref = None
    elif vertical_epsg is not None:
        ref = CRS.from_wkt(_compound_wkt(horizontal, vertical_epsg))
    else:
        ref = CRS.from_epsg(horizontal)
    with rasterio.open(path, "w", driver="GTiff", width=n_px, height=n_px, count=1, dtype="float32",
                       crs=ref, transform=transform, nodata=nodata) as ds:
        ds.write(Z, 1)
    return path


def _compound_wkt(horizontal: int, vertical: int) -> str:
    from pyproj import CRS
    if vertical == 4979:
        return CRS.from_epsg(4979).to_wkt()
    return CRS.from_user_input(f"EPSG:{horizontal}+{vertical}").to_wkt()


def offset(e_m: float, n_m: float) -> tuple[float, float]:
    """(lat, lon) of a point e_m east, n_m north of CENTRE."""
    from pyproj import Transformer
    tr = _utm()
    e0, n0 = tr.transform(CENTRE[1], CENTRE[0])
    lon, lat = Transformer.from_crs("EPSG:32633", "EPSG:4326", always_xy=True).transform(e0 + e_m, n0 + n_m)
    return lat, lon


def square(half_m: float, e_m: float = 0.0, n_m: float = 0.0) -> list[list[float]]:
    """An inline survey area: a square of side 2*half_m centred e_m/n_m from CENTRE."""
    return [list(offset(e_m + dx, n_m + dy)) for dx, dy in
            ((-half_m, -half_m), (half_m, -half_m), (half_m, half_m), (-half_m, half_m))]


def plan_text(dem: str | list[str] | None, area: list[list[float]], altitude_m: float = 60.0,
              front: float = 80, side: float = 70, terrain_extra: str = "", home_alt: float | None = None,
              firmware: str = "ardupilot", takeoff_m: float = 60.0, speed_mps: float = 5.0,
              home_offset: tuple[float, float] = (0.0, -250.0), angle: float = 0.0, vehicle_extra: str = "",
              home_latlon: tuple[float, float] | None = None) -> str:
    """A survey plan over `area` with a WIRIS Pro 13 mm; `dem` None: no terrain block; home `home_offset` metres
    from CENTRE, or at `home_latlon`."""
    hlat, hlon = home_latlon if home_latlon is not None else offset(*home_offset)
    alt = f", alt_amsl_m: {home_alt}" if home_alt is not None else ""
    dems = "" if dem is None else f"terrain: {{dem: {dem if isinstance(dem, str) else list(dem)}{terrain_extra}}}\n"
    return f"""version: 1
name: terrain-test
vehicle: {{firmware: {firmware}, frame: copter, speed_mps: {speed_mps}{vehicle_extra}}}
home: {{lat: {hlat}, lon: {hlon}{alt}}}
{dems}payloads:
  thermal: {{camera: wiris-pro, imager: thermal, lens_mm: 13, component_id: 100}}
mission:
  - takeoff: {{alt_m: {takeoff_m}}}
  - survey:
      area: {area}
      payloads: [thermal]
      altitude_m: {altitude_m}
      overlap: {{front: {front}, side: {side}}}
      angle_deg: {angle}
  - rtl: {{}}
"""
