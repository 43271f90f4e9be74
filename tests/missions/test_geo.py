"""The local projection: metric, wrap-aware, refuses the poles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from pyproj import Geod

from missions.errors import PlanError
from missions.geometry.geo import LocalProjection, unwrap_lons

GEOD = Geod(ellps="WGS84")

PLACES = [
    (50.1, 14.5),        # central Europe
    (-33.9, 151.2),      # southern hemisphere (Sydney)
    (0.0, 0.0),          # equator / prime meridian
    (51.48, -0.0005),    # Greenwich: longitudes of both signs
    (-16.5, 179.9995),   # Fiji: across the 180° meridian
    (75.0, 20.0),        # Svalbard
    (-75.0, -60.0),      # Antarctic peninsula
]


@pytest.mark.parametrize("lat0,lon0", PLACES)
def test_distances_match_the_ellipsoid(lat0: float, lon0: float) -> None:
    # points up to ~3 km away in all directions, including across 0°/180° where the place is on it
    az = np.arange(0, 360, 30.0)
    dist = np.full(az.shape, 3000.0)
    lons, lats, _ = GEOD.fwd(np.full(az.shape, lon0), np.full(az.shape, lat0), az, dist)
    proj = LocalProjection.centred_on(np.append(lats, lat0), np.append(lons, lon0))
    x, y = proj.to_xy(lats, lons)
    cx, cy = proj.point_to_xy(lat0, lon0)
    # every pair of points: planar distance == geodesic distance to 1e-5
    for i in range(len(az)):
        for j in range(i + 1, len(az)):
            _, _, g = GEOD.inv(lons[i], lats[i], lons[j], lats[j])
            p = math.hypot(x[i] - x[j], y[i] - y[j])
            assert abs(p - g) <= 1e-5 * g + 1e-3
    # the azimuth from the centre is preserved: north is +y
    for a, xi, yi in zip(az, x, y):
        got = math.degrees(math.atan2(xi - cx, yi - cy)) % 360
        assert min(abs(got - a), 360 - abs(got - a)) < 0.05


@pytest.mark.parametrize("lat0,lon0", PLACES)
def test_round_trip(lat0: float, lon0: float) -> None:
    proj = LocalProjection(lat0, lon0)
    xs = np.array([-2000.0, 0.0, 1500.0, 2500.0])
    ys = np.array([1000.0, 0.0, -2500.0, 300.0])
    lat, lon = proj.to_latlon(xs, ys)
    assert np.all((lon >= -180) & (lon < 180))
    x2, y2 = proj.to_xy(lat, lon)
    assert np.allclose(x2, xs, atol=1e-6) and np.allclose(y2, ys, atol=1e-6)


def test_antimeridian_area_is_centred_on_the_meridian_not_the_far_side() -> None:
    proj = LocalProjection.centred_on([-16.5, -16.5, -16.49], [179.998, -179.998, 179.999])
    assert abs(abs(proj.lon0) - 180.0) < 0.01
    x, _ = proj.to_xy([-16.5, -16.5], [179.998, -179.998])
    assert 400 < x[1] - x[0] < 450          # 0.004° of longitude at 16.5° S ≈ 427 m, not 40 000 km


@given(st.floats(-179.9, 179.9), st.floats(-0.05, 0.05))
@settings(max_examples=50, deadline=None)
def test_unwrap_keeps_points_within_180_of_the_reference(lon: float, delta: float) -> None:
    other = ((lon + delta + 180) % 360) - 180
    u = unwrap_lons([lon, other])
    assert abs(u[1] - u[0] - delta) < 1e-9


@pytest.mark.parametrize("lat", [85.5, -89.0, 90.0])
def test_polar_areas_are_refused(lat: float) -> None:
    with pytest.raises(PlanError, match="pole") as e:
        LocalProjection.centred_on([lat, lat - 0.01], [0.0, 0.01])
    assert "±85" in (e.value.hint or "")


def test_non_finite_centre_is_refused() -> None:
    with pytest.raises(PlanError) as e:
        LocalProjection(float("nan"), 0.0)
    assert "NaN" in (e.value.hint or "")


def test_no_points_to_centre_on_is_refused() -> None:
    with pytest.raises(PlanError, match="no coordinates") as e:
        LocalProjection.centred_on([], [])
    assert "report" in (e.value.hint or "")
