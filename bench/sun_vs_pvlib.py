"""The sun module against pvlib, the reference PV library, over one day at three places.

    python bench/sun_vs_pvlib.py        # needs pvlib installed beside the project (it is not a dependency)

Prints, per place: the largest difference in apparent solar elevation and azimuth (astral vs pvlib's SPA), the
largest difference of the module-plane transposition (ours vs pvlib's isotropic model fed the same DNI/DHI),
and the clear-sky horizontal irradiance at solar noon (our ASHRAE clear-day model vs pvlib's Ineichen), all
measured in this one run.
"""

from __future__ import annotations

import datetime as dt
import math

import pandas as pd
import pvlib

from missions.thermal.sun import Plane, SunPosition, clear_sky_poa_wm2, sun_day, sun_position

PLACES = {"Prague, June": (50.07, 14.73, "2026-06-14"), "Canberra, June": (-35.26, 149.04, "2026-06-14"),
          "Singapore, March": (1.30, 103.80, "2026-03-21")}
PLANE = Plane(25.0, 180.0)


def ashrae(when: dt.datetime, el: float) -> tuple[float, float]:
    n = when.timetuple().tm_yday
    a = 1160 + 75 * math.sin(math.radians(360 / 365 * (n - 275)))
    k = 0.174 + 0.035 * math.sin(math.radians(360 / 365 * (n - 100)))
    c = 0.095 + 0.04 * math.sin(math.radians(360 / 365 * (n - 100)))
    dni = a * math.exp(-k / math.sin(math.radians(el)))
    return dni, c * dni


def main() -> None:
    print(f"{'place':18} {'max d_elev':>10} {'max d_az':>9} {'max d_poa':>10} {'GHI noon ours':>13} {'Ineichen':>9}")
    for name, (lat, lon, day) in PLACES.items():
        times = pd.date_range(f"{day}T00:00Z", periods=24 * 12, freq="5min")
        sp = pvlib.solarposition.get_solarposition(times, lat, lon)
        d_el = d_az = d_poa = 0.0
        for t, row in zip(times.to_pydatetime(), sp.itertuples()):
            ours = sun_position(lat, lon, t)
            if row.apparent_elevation < 1.0:
                continue
            d_el = max(d_el, abs(ours.elevation_deg - row.apparent_elevation))
            d_az = max(d_az, abs((ours.azimuth_deg - row.azimuth + 180) % 360 - 180))
            dni, dhi = ashrae(t, ours.elevation_deg)
            ghi = dni * math.sin(math.radians(ours.elevation_deg)) + dhi
            ref = pvlib.irradiance.get_total_irradiance(PLANE.tilt_deg, PLANE.azimuth_deg, 90 - ours.elevation_deg,
                                                        ours.azimuth_deg, dni, ghi, dhi, albedo=0.2,
                                                        model="isotropic")["poa_global"]
            d_poa = max(d_poa, abs(clear_sky_poa_wm2(t, ours, PLANE) - float(ref)))
        noon = sun_day(lat, lon, dt.datetime.fromisoformat(f"{day}T12:00+00:00")).solar_noon
        at_noon = sun_position(lat, lon, noon)
        ours_ghi = clear_sky_poa_wm2(noon, at_noon, Plane(0.0, 180.0))
        ineichen = pvlib.location.Location(lat, lon).get_clearsky(pd.DatetimeIndex([noon]))["ghi"].iloc[0]
        print(f"{name:18} {d_el:9.3f}° {d_az:8.3f}° {d_poa:7.3f} W/m² {ours_ghi:9.0f} W/m² {ineichen:5.0f} W/m²")


if __name__ == "__main__":
    main()
