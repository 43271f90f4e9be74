"""NAME.geojson: what the mission will do, as GIS tools show it — built from the simulated flight, not the intent.

One FeatureCollection (RFC 7946: WGS84 lon/lat, altitude third in metres AMSL = home AMSL + height above
home, flat ground assumed as in the report). Every feature has a `kind` property:

  area        one per survey/corridor step: the area to cover after exclusions (its holes are the holes of
              the source polygon and the exclusion zones inside it); properties: step, area_m2, coverage
  gap         each hole/exclusion of an area again as its own polygon, so GIS styling can colour it
  path        the flown path as a LineString (home → takeoff → … → landing); length, times
  waypoint    each NAV item's position: seq (as on the vehicle), command name, altitude
  home        the home position
  photo       each re-derived photo position: index, payloads, altitude, heading, mission item, time
  footprint   each photo's ground footprint per payload (nadir rectangle at the photo's altitude)

`kml_out` renders the same collection, so the two files can never disagree.
"""

from __future__ import annotations

import math
from typing import Any

from missions.compiled import Compiled
from missions.report import Simulation, footprint_ring

# A 100 km² survey has ~10^6 photos; a GIS tool opening a GeoJSON of a million rectangles is unusable.
# Past this count, footprints are left out (the collection says so); photo points are always written.
MAX_FOOTPRINT_FEATURES = 100_000


def _r7(v: float) -> float:
    return round(float(v), 7)


def _command_name(cmd: int) -> str:
    from missions.items import mavlink
    entry = mavlink.enums["MAV_CMD"].get(cmd)
    return entry.name if entry is not None else str(cmd)


def feature_collection(compiled: Compiled, sim: Simulation, rep: dict) -> dict:
    home_amsl = compiled.home[2]
    feats: list[dict] = []
    for a in compiled.areas:
        rings_by_poly = a.area.latlon_rings()
        coords = [[[[_r7(lon), _r7(lat)] for lat, lon in ring] for ring in rings] for rings in rings_by_poly]
        row = next((r for r in rep.get("areas", []) if r["step"] == a.step), {})
        feats.append({"type": "Feature",
                      "properties": {"kind": "area", "step": a.step, "area_kind": a.kind,
                                     "payloads": list(a.payloads), "altitude_m": a.altitude_m,
                                     "area_m2": round(a.area.area_m2, 1), "coverage": row.get("coverage", {}),
                                     "overlap": row.get("overlap", {})},
                      "geometry": {"type": "MultiPolygon", "coordinates": coords}})
        for poly in coords:
            for hole in poly[1:]:
                feats.append({"type": "Feature", "properties": {"kind": "gap", "step": a.step},
                              "geometry": {"type": "Polygon", "coordinates": [hole]}})
    line = [[_r7(lon), _r7(lat), round(home_amsl + v.alt_m, 2)] for (lat, lon), v in zip(sim.latlon, sim.vertices)]
    feats.append({"type": "Feature",
                  "properties": {"kind": "path", "length_m": rep["path_length_m"], "flight_time_s": rep["flight_time_s"],
                                 "flight_time_qgc_s": rep.get("flight_time_qgc_s")},
                  "geometry": {"type": "LineString", "coordinates": line}})
    feats.append({"type": "Feature", "properties": {"kind": "home", "alt_amsl_m": home_amsl},
                  "geometry": {"type": "Point", "coordinates": [_r7(compiled.home[1]), _r7(compiled.home[0]), home_amsl]}})
    seq_base = 1 if compiled.firmware == "ardupilot" else 0
    seen: set[int] = set()
    for (lat, lon), v in zip(sim.latlon, sim.vertices):
        if v.item < 0 or v.item in seen:
            continue
        seen.add(v.item)
        it = compiled.items[v.item]
        feats.append({"type": "Feature",
                      "properties": {"kind": "waypoint", "seq": v.item + seq_base, "command": _command_name(it.command),
                                     "alt_m": round(v.alt_m, 2), "hold_s": v.hold_s, "comment": it.comment},
                      "geometry": {"type": "Point", "coordinates": [_r7(lon), _r7(lat), round(home_amsl + v.alt_m, 2)]}})
    n_fp = sum(len(p.payloads) for p in sim.photos)
    write_fp = n_fp <= MAX_FOOTPRINT_FEATURES
    for k, p in enumerate(sim.photos):
        feats.append({"type": "Feature",
                      "properties": {"kind": "photo", "index": k, "payloads": list(p.payloads),
                                     "alt_m": round(p.alt_m, 2), "heading_deg": round(p.heading_deg, 2),
                                     "item_seq": p.cause + seq_base if p.cause >= 0 else None, "time_s": round(p.time_s, 1)},
                      "geometry": {"type": "Point", "coordinates": [_r7(p.lon), _r7(p.lat), round(home_amsl + p.alt_m, 2)]}})
    if write_fp:
        for k, p in enumerate(sim.photos):
            for name in p.payloads:
                ring = footprint_ring(p, compiled.payload(name))
                xs = [q[0] for q in ring]
                ys = [q[1] for q in ring]
                lat, lon = sim.projection.to_latlon(xs, ys)
                feats.append({"type": "Feature",
                              "properties": {"kind": "footprint", "photo": k, "payload": name},
                              "geometry": {"type": "Polygon",
                                           "coordinates": [[[_r7(b), _r7(a)] for a, b in zip(lat.tolist(), lon.tolist())]]}})
    props: dict[str, Any] = {"plan": compiled.name, "firmware": compiled.firmware,
                             "generator": "wiris-tools", "altitudes": "metres AMSL (home AMSL + height above home)"}
    if not write_fp:
        props["footprints_omitted"] = (f"{n_fp} footprints exceed {MAX_FOOTPRINT_FEATURES}; "
                                       "photo points are complete")
    return {"type": "FeatureCollection", "properties": props, "features": feats}


def finite(obj: Any) -> Any:
    """JSON has no NaN: replace non-finite floats by null (RFC 8259)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj
