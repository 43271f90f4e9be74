"""The PV inspection profile: the numbers of IEC TS 62446-3 practice in one table, each with where it was read.

    profile = pv_profile({"name": "pv-inspection", "level": "cell", "min_irradiance_wm2": 700})

IEC TS 62446-3:2017 itself is not public; its numbers as drone inspection guides state them are. Every number
below names the public page that gives it (docs/pv-inspection.md lists them). A plan overrides any of them
(`profile: {name: pv-inspection, min_irradiance_wm2: 700}`): the table is the default, not a law.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any, ClassVar, Mapping

PROFILE_NAMES = ("pv-inspection",)


@dataclass(frozen=True)
class PvProfile:
    """The numbers a PV inspection flight is held to (defaults: IEC TS 62446-3 practice, see SOURCES)."""

    LEVELS: ClassVar[tuple[str, ...]] = ("module", "cell")
    OVERRIDABLE: ClassVar[tuple[str, ...]] = (
        "min_irradiance_wm2", "solar_time_from_h", "solar_time_to_h", "min_hours_from_sunrise_sunset",
        "max_gsd_cm_cell", "max_gsd_cm_module", "max_viewing_angle_deg", "max_wind_mps", "emissivity_min",
        "emissivity_max", "glare_cone_deg")

    level: str = "module"
    min_irradiance_wm2: float = 600.0
    solar_time_from_h: float = 10.0
    solar_time_to_h: float = 15.0
    min_hours_from_sunrise_sunset: float = 2.0
    max_gsd_cm_cell: float = 3.0
    max_gsd_cm_module: float = 5.5
    max_viewing_angle_deg: float = 30.0
    max_wind_mps: float = 4.0
    emissivity_min: float = 0.85
    emissivity_max: float = 0.95
    range_mode: str = "manual"
    glare_cone_deg: float = 10.0

    @property
    def max_gsd_cm(self) -> float:
        return self.max_gsd_cm_cell if self.level == "cell" else self.max_gsd_cm_module


# Where each default was read (confirmed at the page named), in the order of docs/pv-inspection.md.
SOURCES: Mapping[str, str] = {
    "min_irradiance_wm2": "≥ 600 W/m² on the module plane, measured on site with a pyranometer: Tenzan Logic, "
                          "'Understanding IEC TS 62446-3 for Drone-Based Thermography' (tenzanlogic.com); "
                          "Aerometrix inspection docs 'POA irradiance 600 W/m² minimum' (docs.aerometrix.co)",
    "solar_time_from_h": "10:00-15:00 local solar time: Aerometrix inspection docs, environmental requirements",
    "solar_time_to_h": "10:00-15:00 local solar time: Aerometrix inspection docs, environmental requirements",
    "min_hours_from_sunrise_sunset": "not within 2 h of sunrise or sunset: the practice guides as issue 30 "
                                     "quotes them; NOT confirmed at a public page in this work (the 10:00-15:00 "
                                     "solar-time window implies it at most latitudes)",
    "max_gsd_cm_cell": "3 cm/px thermal GSD for cell level (detailed inspection): Aerometrix 'GSD (IR) 3.0 cm/px'; "
                       "Above Surveying flight parameters (3 / 5.5 / 8 cm/px); Teledyne FLIR via coastlineuav.com "
                       "'3 cm-per-pixel' for a detailed inspection; ≥ 5×5 px per cell (Tenzan Logic, olil.lv): "
                       "156 mm / 5 = 3.1 cm",
    "max_gsd_cm_module": "5.5 cm/px for module level: Above Surveying 'Flight & Camera Parametres for a "
                         "Thermographic Inspection' (support.abovesurveying.com)",
    "max_viewing_angle_deg": "camera within 30° of the module normal: Aerometrix 'never exceed 30 deg' from normal "
                             "(5-10° off it against glare); Jersey IR: more than 45° from the module surface",
    "max_wind_mps": "wind below 15 km/h (4.2 m/s): Aerometrix environmental requirements; < 4.0 m/s: "
                    "solarlogicmanuals.com technical specifications",
    "emissivity_min": "glass-covered modules 0.85 (the value widely quoted for PV glass; NOT confirmed at a public "
                      "page in this work)",
    "emissivity_max": "0.95: Aerometrix camera settings 'Emissivity 0.95'",
    "range_mode": "a fixed (manual) range keeps temperatures comparable across the mosaic: Aerometrix camera "
                  "settings ('do not change mid-mission'); our reading, not a number of the standard",
    "glare_cone_deg": "10°: Aerometrix 'glare mitigation 5-10 deg tilt from normal'; ours: the camera is warned "
                      "when it looks within this angle of the sun's specular reflection",
}


def override_schema() -> dict[str, dict]:
    """JSON Schema of the overridable numbers (plan key -> a positive number)."""
    return {name: {"type": "number", "minimum": 0, "description": f"override: {SOURCES[name].split(':')[0]}"}
            for name in PvProfile.OVERRIDABLE}


def pv_profile(written: str | Mapping[str, Any]) -> PvProfile:
    """The profile a plan asks for: `pv-inspection`, or a mapping with name, level and overrides (schema-checked)."""
    if isinstance(written, str):
        return PvProfile()
    known = {f.name for f in fields(PvProfile)}
    changes = {k: (v if k == "level" else float(v)) for k, v in written.items() if k != "name" and k in known}
    return replace(PvProfile(), **changes)
