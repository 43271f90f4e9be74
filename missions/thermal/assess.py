"""The sun over each survey and corridor of a compiled mission, and the PV inspection profile's verdict.

    result = assess(plan, compiled)      # Assessment(steps, problems, warnings)

A step is timed by the re-flight of the emitted items (missions.measure.flight): it starts when the vehicle
reaches the step's first item, `when` after take-off (or at the step's own `when`), and lasts as long as it is
flown. The sun is sampled every SAMPLE_S over that window. Each profile violation is a located `Problem` with
what to change; a glare geometry and radiometric settings that differ from the profile's are warnings.
"""

from __future__ import annotations

from dataclasses import dataclass
import datetime as dt
from typing import Any, NamedTuple

from cdf.catalogue import catalogue
from missions.compiled import AreaInfo, Compiled, PayloadInfo, PlanWarning
from missions.errors import Problem
from missions.geometry import optics
from missions.plan.types import CorridorStep, Plan, SurveyStep, Target
from missions.thermal.pv import PvProfile
from missions.thermal.sun import (Plane, SunDay, SunPosition, clear_sky_poa_wm2, glare_angle_deg, solar_time_h,
                                  sun_day, sun_position, viewing_angle_deg)

SAMPLE_S = 300.0                 # the sun moves 1.25° in 5 minutes
MAX_SAMPLES = 1000               # 83 h of flight: more is not one flight
HORIZONTAL = Plane(0.0, 180.0)


@dataclass(frozen=True)
class StepSun:
    """The sun over one survey or corridor, as the report gives it."""

    step: int
    site: tuple[float, float]             # lat, lon the sun is computed for (the area's centre)
    start: dt.datetime
    end: dt.datetime
    sun_start: SunPosition
    sun_end: SunPosition
    min_elevation_deg: float
    solar_time_start_h: float
    solar_time_end_h: float
    sunrise: dt.datetime | None
    sunset: dt.datetime | None
    plane: str                            # "target" (the plan's module plane) or "horizontal"
    clear_sky_min_wm2: float              # lowest clear-sky estimate on that plane over the step
    viewing_angle_deg: float | None       # camera against module normal (a target only)
    glare_min_deg: float | None           # closest approach of the sun's reflection to the camera's view
    profile: str | None
    wind_mps: float | None

    def to_json(self) -> dict[str, Any]:
        def iso(t: dt.datetime | None) -> str | None:
            return None if t is None else t.astimezone(self.start.tzinfo).isoformat(timespec="minutes")

        def pos(p: SunPosition) -> dict[str, float]:
            return {"elevation_deg": round(p.elevation_deg, 2), "azimuth_deg": round(p.azimuth_deg, 2)}

        return {"step": self.step, "start": iso(self.start), "end": iso(self.end), "sun_start": pos(self.sun_start),
                "sun_end": pos(self.sun_end), "min_elevation_deg": round(self.min_elevation_deg, 2),
                "solar_time_start_h": round(self.solar_time_start_h, 3),
                "solar_time_end_h": round(self.solar_time_end_h, 3), "sunrise": iso(self.sunrise),
                "sunset": iso(self.sunset), "clear_sky_plane": self.plane,
                "clear_sky_min_wm2": round(self.clear_sky_min_wm2, 1),
                "viewing_angle_deg": None if self.viewing_angle_deg is None else round(self.viewing_angle_deg, 1),
                "glare_min_deg": None if self.glare_min_deg is None else round(self.glare_min_deg, 1),
                "profile": self.profile, "wind_mps": self.wind_mps,
                "note": "clear-sky estimate (ASHRAE clear-day model): irradiance must be measured on site"}


class Assessment(NamedTuple):
    steps: tuple[StepSun, ...]
    problems: tuple[Problem, ...]
    warnings: tuple[PlanWarning, ...]


class _Window(NamedTuple):
    start: dt.datetime
    end: dt.datetime


def assess(plan: Plan, compiled: Compiled) -> Assessment:
    """The sun over every timed step, and what the PV profile finds wrong (nothing to time: nothing to say)."""
    lined = {s.index: s for s in plan.mission if isinstance(s, (SurveyStep, CorridorStep))}
    profiled = [s for s in lined.values() if isinstance(s, SurveyStep) and s.profile is not None]
    timed = plan.timing.when is not None or any(s.timing.when is not None for s in lined.values())
    problems: list[Problem] = []
    warnings: list[PlanWarning] = []
    for step in profiled:
        problems += _gsd_problems(plan, compiled, step)
        warnings += _settings_warnings(plan, step)
        if not timed:
            warnings.append(PlanWarning("pv_when_missing", f"survey at {plan.step_where(step)}: the pv-inspection "
                                        "profile cannot check the sun, the hour or the irradiance without `when`"))
    if not timed:
        return Assessment((), tuple(problems), tuple(warnings))
    windows = _step_windows(plan, compiled, lined)
    rows: list[StepSun] = []
    for area in compiled.areas:
        step, window = lined.get(area.step), windows.get(area.step)
        if step is None or window is None:
            continue
        row = _step_sun(plan, step, area, window)
        rows.append(row)
        warnings += _sun_warnings(plan, step, row)
        if isinstance(step, SurveyStep) and step.profile is not None:
            problems += _profile_problems(plan, step, row)
    return Assessment(tuple(rows), tuple(problems), tuple(warnings))


# -------------------------------------------------------------------------------------------- timing

def _step_windows(plan: Plan, compiled: Compiled, lined: dict[int, Any]) -> dict[int, _Window]:
    from missions.measure.flight import simulate   # the re-flight: only for a plan that says when it flies

    sim = simulate(compiled)
    out: dict[int, _Window] = {}
    for area in compiled.areas:
        if area.items is None or area.step not in lined:
            continue
        first, end = area.items
        times = [t for v, t in zip(sim.vertices, sim.vertex_times_s) if first <= v.item < end]
        if not times:
            continue
        own = lined[area.step].timing.when
        start = own if own is not None else plan.timing.when + dt.timedelta(seconds=min(times))
        if start is None:
            continue
        out[area.step] = _Window(start, start + dt.timedelta(seconds=max(times) - min(times)))
    return out


def _samples(window: _Window) -> list[dt.datetime]:
    span = (window.end - window.start).total_seconds()
    n = min(MAX_SAMPLES, int(span // SAMPLE_S))
    return [window.start + dt.timedelta(seconds=k * SAMPLE_S) for k in range(n + 1)] + [window.end]


def _target_plane(step: Any) -> Plane | None:
    target: Target | None = getattr(step, "target", None)
    return None if target is None else Plane(target.tilt_deg, target.azimuth_deg)


def _step_sun(plan: Plan, step: Any, area: AreaInfo, window: _Window) -> StepSun:
    lat, lon = area.area.projection.lat0, area.area.projection.lon0
    times = _samples(window)
    suns = [sun_position(lat, lon, t) for t in times]
    target = _target_plane(step)
    plane = target or HORIZONTAL
    pitch = getattr(step, "camera_pitch_deg", 0.0)
    glare = [g for g in (glare_angle_deg(s, target, pitch) for s in suns) if g is not None] if target else []
    day: SunDay = sun_day(lat, lon, window.start)
    profile: PvProfile | None = getattr(step, "profile", None)
    return StepSun(
        step=step.index, site=(lat, lon), start=window.start, end=window.end, sun_start=suns[0], sun_end=suns[-1],
        min_elevation_deg=min(s.elevation_deg for s in suns),
        solar_time_start_h=solar_time_h(lat, lon, window.start), solar_time_end_h=solar_time_h(lat, lon, window.end),
        sunrise=day.sunrise, sunset=day.sunset, plane="target" if target else "horizontal",
        clear_sky_min_wm2=min(clear_sky_poa_wm2(t, s, plane) for t, s in zip(times, suns)),
        viewing_angle_deg=viewing_angle_deg(target, pitch) if target else None,
        glare_min_deg=min(glare) if glare else None,
        profile=None if profile is None else f"pv-inspection ({profile.level} level)",
        wind_mps=step.timing.wind_mps if step.timing.wind_mps is not None else plan.timing.wind_mps)


# ------------------------------------------------------------------------------------------- findings

def _when_where(plan: Plan, step: Any) -> str:
    return plan.step_where(step, "when") if step.timing.when is not None else plan.where("when")


def _clock(t: dt.datetime, like: dt.datetime) -> str:
    return t.astimezone(like.tzinfo).strftime("%H:%M")


def _sun_warnings(plan: Plan, step: Any, row: StepSun) -> list[PlanWarning]:
    out = []
    if row.min_elevation_deg <= 0.0 and getattr(step, "profile", None) is None:
        out.append(PlanWarning("sun_below_horizon", f"step at {plan.step_where(step)} flies with the sun "
                               f"{-row.min_elevation_deg:.1f}° below the horizon: a thermal image at night shows no "
                               "solar load"))
    profile = getattr(step, "profile", None)
    cone = profile.glare_cone_deg if profile is not None else PvProfile().glare_cone_deg
    if row.glare_min_deg is not None and row.glare_min_deg < cone:
        out.append(PlanWarning("glare", f"survey at {plan.step_where(step)}: the camera looks within "
                               f"{row.glare_min_deg:.1f}° of the sun's reflection off the modules (less than "
                               f"{cone:g}°): the reflected sun hides hot spots; tilt the camera 5-10° off the "
                               "module normal (camera_pitch_deg) or fly at another hour"))
    return out


def _window_text(plan: Plan, step: Any, row: StepSun, profile: PvProfile) -> str:
    """The clock times, in the plan's offset, between which the profile's sun conditions hold that day."""
    lat, lon = row.site
    noon = sun_day(lat, lon, row.start).solar_noon
    start = noon + dt.timedelta(hours=profile.solar_time_from_h - 12.0)
    end = noon + dt.timedelta(hours=profile.solar_time_to_h - 12.0)
    margin = dt.timedelta(hours=profile.min_hours_from_sunrise_sunset)
    if row.sunrise is not None:
        start = max(start, row.sunrise + margin)
    if row.sunset is not None:
        end = min(end, row.sunset - margin)
    if start >= end:
        return "the sun does not meet the profile on that day: choose another season or date"
    return f"fly between {_clock(start, row.start)} and {_clock(end, row.start)} (UTC{row.start.strftime('%z')}) that day"


def _profile_problems(plan: Plan, step: SurveyStep, row: StepSun) -> list[Problem]:
    profile: PvProfile = step.profile
    where = _when_where(plan, step)
    out: list[Problem] = []
    window = _window_text(plan, step, row, profile)
    if row.min_elevation_deg <= 0.0:
        out.append(Problem(where, f"night-time flight: the sun is {-row.min_elevation_deg:.1f}° below the horizon "
                           f"during the survey ({_clock(row.start, row.start)}-{_clock(row.end, row.start)}); a PV "
                           "inspection needs the modules under sun and load", window))
    elif not (profile.solar_time_from_h <= row.solar_time_start_h and row.solar_time_end_h <= profile.solar_time_to_h):
        out.append(Problem(where, f"the survey runs {_hours(row.solar_time_start_h)}-{_hours(row.solar_time_end_h)} "
                           f"solar time, outside the profile's {_hours(profile.solar_time_from_h)}-"
                           f"{_hours(profile.solar_time_to_h)}", f"another hour: {window}"))
    elif _near_sunrise_or_sunset(row, profile):
        out.append(Problem(where, f"the survey runs within {profile.min_hours_from_sunrise_sunset:g} h of sunrise "
                           "or sunset", f"another hour: {window}"))
    if row.min_elevation_deg > 0.0 and row.clear_sky_min_wm2 < profile.min_irradiance_wm2:
        out.append(Problem(where, f"even under a clear sky the module plane gets only {row.clear_sky_min_wm2:.0f} "
                           f"W/m² during the survey, below the profile's {profile.min_irradiance_wm2:g} W/m² "
                           "(estimate; irradiance must be measured on site)",
                           "another hour or season (the sun higher on the modules)"))
    if row.viewing_angle_deg is not None and row.viewing_angle_deg > profile.max_viewing_angle_deg:
        need = step.target.tilt_deg - profile.max_viewing_angle_deg
        out.append(Problem(plan.step_where(step, "target", "tilt_deg"), f"the camera views the modules "
                           f"{row.viewing_angle_deg:.1f}° off their normal, more than the profile's "
                           f"{profile.max_viewing_angle_deg:g}°", f"another pitch: camera_pitch_deg: "
                           f"{max(need, 0):g} to {step.target.tilt_deg:g} (towards the modules' face), set on the "
                           "gimbal"))
    if row.wind_mps is not None and row.wind_mps > profile.max_wind_mps:
        at = plan.step_where(step, "when_wind_mps") if step.timing.wind_mps is not None else plan.where("when_wind_mps")
        out.append(Problem(at, f"wind {row.wind_mps:g} m/s is above the profile's {profile.max_wind_mps:g} m/s: "
                           "wind cools the modules and hides hot spots", "fly on a calmer day"))
    return out


def _hours(h: float) -> str:
    minutes = int(round(h * 60.0)) % (24 * 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}"


def _near_sunrise_or_sunset(row: StepSun, profile: PvProfile) -> bool:
    margin = dt.timedelta(hours=profile.min_hours_from_sunrise_sunset)
    early = row.sunrise is not None and row.start < row.sunrise + margin
    late = row.sunset is not None and row.end > row.sunset - margin
    return early or late


def _gsd_problems(plan: Plan, compiled: Compiled, step: SurveyStep) -> list[Problem]:
    profile: PvProfile = step.profile
    area = next((a for a in compiled.areas if a.step == step.index), None)
    lead: PayloadInfo | None = next((p for p in compiled.payloads if p.name == step.payloads[0]), None)
    if area is None or lead is None:
        return []
    gsd = lead.gsd_cm(area.altitude_m)
    if gsd <= profile.max_gsd_cm + 1e-9:
        return []
    highest = optics.altitude_for_gsd(lead, profile.max_gsd_cm)
    what = "cell level (at least 5×5 pixels per 156 mm cell)" if profile.level == "cell" else "module level"
    at = plan.step_where(step, "altitude_m" if step.altitude_m is not None else "gsd_cm")
    return [Problem(at, f"{lead.name}'s GSD {gsd:.2f} cm/px is too coarse for a {what} PV inspection: the profile "
                    f"asks for {profile.max_gsd_cm:g} cm/px or finer",
                    f"fly lower: altitude_m: {int(highest * 10) / 10:g} or below (gsd_cm: {profile.max_gsd_cm:g}), "
                    f"or a longer lens than {lead.focal_mm:g} mm")]


def _settings_warnings(plan: Plan, step: SurveyStep) -> list[PlanWarning]:
    """The radiometric settings the profile proposes, against the lead payload's (its pre-flight settings)."""
    profile: PvProfile = step.profile
    payload = plan.payload(step.payloads[0])
    camera = catalogue().get(payload.camera)
    out = []
    if camera.setting("emissivity") is not None:
        e = payload.value("emissivity")
        if e is None or not profile.emissivity_min - 1e-9 <= float(e) <= profile.emissivity_max + 1e-9:
            shown = "not set" if e is None else f"{float(e):g}"
            out.append(PlanWarning("pv_emissivity", f"{payload.name}: emissivity {shown}; glass-covered modules "
                                   f"take {profile.emissivity_min:g}-{profile.emissivity_max:g} (settings: "
                                   f"emissivity: {profile.emissivity_min:g})"))
    mode = camera.setting("range_mode")
    if mode is not None:
        manual = mode.option_by_key(profile.range_mode)
        if manual is not None and payload.value("range_mode") != manual.value:
            out.append(PlanWarning("pv_range_mode", f"{payload.name}: range_mode is not {profile.range_mode}; a "
                                   "fixed range keeps module temperatures comparable across the mosaic (settings: "
                                   f"range_mode: {profile.range_mode}, range_min_c, range_max_c)"))
    return out
