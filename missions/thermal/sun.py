"""The sun over a flight: position, the day's sunrise/sunset and solar noon, a clear-sky irradiance estimate on
a tilted module plane, and the angles between camera, module normal and the sun's specular reflection.

    sun = sun_position(lat, lon, when)                      # apparent elevation (refraction included), azimuth
    day = sun_day(lat, lon, when)                           # sunrise, sunset, solar noon (UTC datetimes)
    poa = clear_sky_poa_wm2(when, sun, Plane(25, 180))      # W/m² on the module plane, clear sky

Positions come from astral (NOAA's solar equations, maintained, pure Python, no dependencies): pvlib, the
reference library, pulls pandas, scipy and h5py in (357 MB measured in a fresh venv), more than the whole
run-time install budget. The clear-sky irradiance is the ASHRAE clear-day model as Masters gives it in
closed form ("Renewable and Efficient Electric Power Systems", 2004, §7.8: apparent extraterrestrial flux A,
optical depth k and sky diffuse factor C as sinusoids of the day of the year), transposed to the plane with
the isotropic sky (beam · cos(incidence) + C · beam · (1 + cos tilt)/2 + ground albedo · (beam · (sin β + C)) ·
(1 − cos tilt)/2). It is an estimate before the flight: irradiance must be measured on site.

Angles are degrees; azimuths clockwise from true north; a plane's azimuth is the direction its face looks
(180 = facing south). Vectors are east, north, up.
"""

from __future__ import annotations

from dataclasses import dataclass
import datetime as dt
import math

GROUND_ALBEDO = 0.2          # Masters' typical ground reflectance (grass, soil) for the reflected part


@dataclass(frozen=True)
class SunPosition:
    elevation_deg: float     # apparent: above the horizon, refraction included; negative at night
    azimuth_deg: float       # clockwise from true north


@dataclass(frozen=True)
class SunDay:
    """The day at a place: UTC datetimes; sunrise/sunset None where the sun does not rise or set that day."""

    solar_noon: dt.datetime
    sunrise: dt.datetime | None
    sunset: dt.datetime | None


@dataclass(frozen=True)
class Plane:
    """A module plane: tilt from horizontal and the azimuth its face looks to."""

    tilt_deg: float
    azimuth_deg: float

    def normal(self) -> tuple[float, float, float]:
        return _unit(90.0 - self.tilt_deg, self.azimuth_deg)


def _unit(elevation_deg: float, azimuth_deg: float) -> tuple[float, float, float]:
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e))


def _angle_deg(u: tuple[float, float, float], v: tuple[float, float, float]) -> float:
    dot = sum(a * b for a, b in zip(u, v))
    return math.degrees(math.acos(max(-1.0, min(1.0, dot))))


def _observer(lat: float, lon: float):
    from astral import Observer   # loads only for a plan that says when it flies

    return Observer(latitude=lat, longitude=lon)


def sun_position(lat: float, lon: float, when: dt.datetime) -> SunPosition:
    from astral import sun

    obs = _observer(lat, lon)
    return SunPosition(sun.elevation(obs, when), sun.azimuth(obs, when))


def _local_date(lon: float, when: dt.datetime) -> dt.date:
    """The calendar date at the place by mean solar time: the day whose solar noon is nearest `when`."""
    return (when.astimezone(dt.timezone.utc) + dt.timedelta(hours=lon / 15.0)).date()


def sun_day(lat: float, lon: float, when: dt.datetime) -> SunDay:
    from astral import sun

    obs, date = _observer(lat, lon), _local_date(lon, when)
    noon = sun.noon(obs, date)
    try:
        rise, down = sun.sunrise(obs, date), sun.sunset(obs, date)
    except ValueError:              # polar day or night: astral says the sun never reaches the horizon
        rise = down = None
    return SunDay(noon, rise, down)


def solar_time_h(lat: float, lon: float, when: dt.datetime) -> float:
    """Apparent solar time in hours (12.0 at solar noon): what PV practice's "10:00-15:00 solar time" means."""
    noon = sun_day(lat, lon, when).solar_noon
    return 12.0 + (when - noon).total_seconds() / 3600.0


def clear_sky_poa_wm2(when: dt.datetime, sun: SunPosition, plane: Plane, albedo: float = GROUND_ALBEDO) -> float:
    """Clear-sky irradiance on `plane` (W/m²), ASHRAE clear-day model (Masters 2004, §7.8); 0 at night."""
    if sun.elevation_deg <= 0.0:
        return 0.0
    n = when.astimezone(dt.timezone.utc).timetuple().tm_yday
    a_flux = 1160.0 + 75.0 * math.sin(math.radians(360.0 / 365.0 * (n - 275)))
    k = 0.174 + 0.035 * math.sin(math.radians(360.0 / 365.0 * (n - 100)))
    c = 0.095 + 0.04 * math.sin(math.radians(360.0 / 365.0 * (n - 100)))
    beta = math.radians(sun.elevation_deg)
    beam = a_flux * math.exp(-k / math.sin(beta))
    tilt = math.radians(plane.tilt_deg)
    cos_incidence = (math.cos(beta) * math.cos(math.radians(sun.azimuth_deg - plane.azimuth_deg)) * math.sin(tilt)
                     + math.sin(beta) * math.cos(tilt))
    direct = beam * max(cos_incidence, 0.0)
    diffuse = c * beam * (1.0 + math.cos(tilt)) / 2.0
    reflected = albedo * beam * (math.sin(beta) + c) * (1.0 - math.cos(tilt)) / 2.0
    return direct + diffuse + reflected


def camera_to_ground(plane: Plane, camera_pitch_deg: float) -> tuple[float, float, float]:
    """The camera's view direction: nadir tilted `camera_pitch_deg` towards the modules' face (the camera on
    the side the modules look to, looking back at them)."""
    p, g = math.radians(camera_pitch_deg), math.radians(plane.azimuth_deg)
    return (-math.sin(p) * math.sin(g), -math.sin(p) * math.cos(g), -math.cos(p))


def viewing_angle_deg(plane: Plane, camera_pitch_deg: float) -> float:
    """Angle between the module normal and the direction from the modules to the camera (0 = head-on)."""
    d = camera_to_ground(plane, camera_pitch_deg)
    return _angle_deg(plane.normal(), (-d[0], -d[1], -d[2]))


def glare_angle_deg(sun: SunPosition, plane: Plane, camera_pitch_deg: float) -> float | None:
    """Angle between the sun's specular reflection off the module glass and the direction to the camera (small:
    the camera looks into the reflected sun); None when the sun is behind the modules or below the horizon."""
    if sun.elevation_deg <= 0.0:
        return None
    s, n = _unit(sun.elevation_deg, sun.azimuth_deg), plane.normal()
    sn = sum(a * b for a, b in zip(s, n))
    if sn <= 0.0:
        return None
    reflected = tuple(2.0 * sn * b - a for a, b in zip(s, n))
    d = camera_to_ground(plane, camera_pitch_deg)
    return _angle_deg(reflected, (-d[0], -d[1], -d[2]))
