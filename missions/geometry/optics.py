"""Payload optics: the catalogue imager + lens (+ orientation) as a PayloadInfo, and the arithmetic that
follows from it — GSD <-> altitude, footprint, line spacing and trigger distance from overlaps, and the
check that photos do not come faster than the camera can take them.

Same model as QGroundControl's CameraCalc (reference survey-planners §1.2): a nadir pinhole over flat
ground at the altitude above home; GSD from the across-track sensor side and pixel count (square pixels).
Facts the catalogue marks as assumed (pitch, lens set) make every number here an assumption too: the
compiler says so as a warning, never silently.
"""

from __future__ import annotations

import math

from missions.compiled import PayloadInfo, PlanWarning
from missions.errors import PlanError
from missions.geometry.footprint import Footprint, transect_spacing_m, trigger_distance_m


def _imager(camera, imager_id: str | None, where: str | None):
    if imager_id is not None:
        im = camera.imager(imager_id)
        if im is None:
            raise PlanError(f"{camera.id} has no imager {imager_id!r}", where=where,
                            hint="imagers: " + ", ".join(i.id for i in camera.imagers))
        return im
    known = [i for i in camera.imagers if i.known]
    if known:
        return known[0]
    if camera.imagers:
        return camera.imagers[0]
    raise PlanError(f"{camera.id} lists no imagers", where=where,
                    hint=f"add its imagers (sensor_mm, resolution_px, lenses_mm) to cdf/tables/{camera.table}")


def payload_info(payload, camera, where: str | None = None) -> tuple[PayloadInfo, tuple[str, ...]]:
    """PayloadInfo for a plan payload (missions.plan.load.Payload) on a catalogue camera, and warnings.

    Raises PlanError for an imager with unknown optics (naming the catalogue table's note) and for a lens
    that is not in the table (listing the lenses)."""
    im = _imager(camera, payload.imager, where)
    table = f"cdf/tables/{camera.table}" if camera.table else "the catalogue"
    if not im.known or im.resolution_px is None or im.sensor_size_mm is None:
        raise PlanError(f"the optics of {camera.id}'s {im.id} imager are unknown, so no footprint or GSD can be "
                        f"computed", where=where,
                        hint=(im.note or f"see {table}") + f" — add the sensor and lenses to {table} once known,"
                             " or let another payload set the lines")
    if payload.lens_mm is None:
        if len(im.lenses_mm) == 1:
            focal = im.lenses_mm[0]
        else:
            raise PlanError(f"payload {payload.name}: which lens is fitted? {camera.id}'s {im.id} imager has "
                            f"several", where=where,
                            hint="add lens_mm: one of " + ", ".join(f"{l:g}" for l in im.lenses_mm))
    else:
        focal = float(payload.lens_mm)
        if im.lenses_mm and not any(abs(focal - l) < 1e-6 for l in im.lenses_mm):
            raise PlanError(f"payload {payload.name}: {camera.id}'s {im.id} imager has no {focal:g} mm lens",
                            where=where, hint="lenses in " + table + ": "
                            + ", ".join(f"{l:g} mm" for l in im.lenses_mm))
    warnings = []
    assumed = [a for a in im.assumed if a in ("pixel_pitch", "lenses", "resolution", "sensor")]
    if assumed:
        warnings.append(PlanWarning("assumed_optics", f"{payload.name} ({camera.id} {im.id}): "
                        f"{', '.join(a.replace('_', ' ') for a in assumed)} assumed, not from a datasheet "
                        f"({table}); GSD, footprint and spacing are only as good as that assumption"))
    info = PayloadInfo(name=payload.name, camera_id=camera.id, imager=im.id, component_id=payload.component_id,
                       focal_mm=focal, sensor_mm=tuple(im.sensor_size_mm), resolution_px=tuple(im.resolution_px),
                       landscape=payload.landscape, min_interval_s=im.min_interval_s,
                       time_constant_ms=im.time_constant_ms, time_constant_assumed="time_constant" in im.assumed)
    return info, tuple(warnings)


def altitude_for_gsd(info: PayloadInfo, gsd_cm: float) -> float:
    """Altitude above ground (m) at which `info` images with `gsd_cm` cm/px (inverse of PayloadInfo.gsd_cm)."""
    if not (math.isfinite(gsd_cm) and gsd_cm > 0):
        raise PlanError(f"GSD {gsd_cm!r} cm/px must be positive",
                        hint="give the GSD in centimetres per pixel, e.g. gsd_cm: 3.5")
    return gsd_cm / info.gsd_cm(1.0)


def footprint(info: PayloadInfo, altitude_m: float) -> Footprint:
    across, along = info.footprint_m(altitude_m)
    return Footprint(across_m=across, along_m=along)


def spacing_m(info: PayloadInfo, altitude_m: float, side_pct: float) -> float:
    return transect_spacing_m(footprint(info, altitude_m), side_pct)


def trigger_m(info: PayloadInfo, altitude_m: float, front_pct: float) -> float:
    return trigger_distance_m(footprint(info, altitude_m), front_pct)


def max_speed_mps(trigger_distance: float, min_interval_s: float) -> float:
    """The highest ground speed at which photos `trigger_distance` apart come no faster than the camera allows."""
    return trigger_distance / min_interval_s


def check_interval(info: PayloadInfo, trigger_distance: float, speed_mps: float, where: str | None = None) -> float:
    """Seconds between photos at `speed_mps`; PlanError naming the speed that works when it is shorter than the
    camera's minimum capture interval."""
    interval = trigger_distance / speed_mps
    if info.min_interval_s and interval < info.min_interval_s - 1e-9:
        ok = max_speed_mps(trigger_distance, info.min_interval_s)
        raise PlanError(
            f"{info.name}: photos every {trigger_distance:.1f} m at {speed_mps:g} m/s come {interval:.2f} s apart, "
            f"faster than {info.camera_id}'s minimum capture interval of {info.min_interval_s:g} s",
            where=where,
            hint=f"fly at {math.floor(ok * 10) / 10:g} m/s or slower (vehicle.speed_mps), lower the front overlap, "
                 "or fly higher")
    return interval
