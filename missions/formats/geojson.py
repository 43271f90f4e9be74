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
  footprint   each photo's ground footprint per payload (nadir rectangle at the photo's altitude; with a DEM the
              view cone cut by the terrain, missions.terrain.reflight)
  sortie      a mission flown in sorties: each sortie's own re-flown path (home to home) as a LineString;
              properties: sortie (1..N), file, flight_time_s, photos, items, first_line, last_line

`kml_out` renders the same collection, so the two files can never disagree.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from missions.compiled import Compiled
from missions.emit.items import mavlink
from missions.formats.jsonfinite import finite
from missions.measure.flight import Simulation
from missions.measure.report import MissionReport


# A 100 km² survey has ~10^6 photos; a GIS tool opening a GeoJSON of a million rectangles is unusable.
# Past this count, footprints are left out (the collection says so); photo points are always written.
MAX_FOOTPRINT_FEATURES = 100_000


def _r7(v: float) -> float:
    return round(float(v), 7)


def _command_name(cmd: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(cmd)
    return entry.name if entry is not None else str(cmd)


def feature_collection(compiled: Compiled, sim: Simulation, rep: MissionReport) -> dict:
    home_amsl = compiled.home[2]
    feats: list[dict] = []
    for a in compiled.areas:
        rings_by_poly = a.area.latlon_rings()
        coords = [[[[_r7(lon), _r7(lat)] for lat, lon in ring] for ring in rings] for rings in rings_by_poly]
        row = next((r.to_json() for r in rep.areas if r.step == a.step), {})
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
    amsl = _vertex_amsl(compiled, sim)
    line = [[_r7(lon), _r7(lat), round(z, 2)] for (lat, lon), z in zip(sim.latlon, amsl)]
    feats.append({"type": "Feature",
                  "properties": {"kind": "path", "length_m": rep.path_length_m, "flight_time_s": rep.flight_time_s,
                                 "flight_time_qgc_s": rep.flight_time_qgc_s},
                  "geometry": {"type": "LineString", "coordinates": line}})
    feats.append({"type": "Feature", "properties": {"kind": "home", "alt_amsl_m": home_amsl},
                  "geometry": {"type": "Point", "coordinates": [_r7(compiled.home[1]), _r7(compiled.home[0]), home_amsl]}})
    seq_base = 1 if compiled.firmware == "ardupilot" else 0
    seen: set[int] = set()
    for (lat, lon), v, z in zip(sim.latlon, sim.vertices, amsl):
        if v.item < 0 or v.item in seen:
            continue
        seen.add(v.item)
        it = compiled.items[v.item]
        feats.append({"type": "Feature",
                      "properties": {"kind": "waypoint", "seq": v.item + seq_base, "command": _command_name(it.command),
                                     "alt_m": round(v.alt_m, 2), "hold_s": v.hold_s, "comment": it.comment},
                      "geometry": {"type": "Point", "coordinates": [_r7(lon), _r7(lat), round(z, 2)]}})
    n_fp = sum(len(p.payloads) for p in sim.photos)
    write_fp = n_fp <= MAX_FOOTPRINT_FEATURES
    heights = _photo_heights(compiled, sim)
    for k, p in enumerate(sim.photos):
        props = {"kind": "photo", "index": k, "payloads": list(p.payloads),
                 "alt_m": round(p.alt_m, 2), "heading_deg": round(p.heading_deg, 2),
                 "item_seq": p.cause + seq_base if p.cause >= 0 else None, "time_s": round(p.time_s, 1)}
        amsl = home_amsl + p.alt_m
        if heights is not None:          # over a DEM: the camera's altitude and its height above the ground below
            amsl = float(heights[0][k])
            props["agl_m"] = round(float(heights[0][k] - heights[1][k]), 2)
        feats.append({"type": "Feature", "properties": props,
                      "geometry": {"type": "Point", "coordinates": [_r7(p.lon), _r7(p.lat), round(amsl, 2)]}})
    if write_fp:
        feats.extend(_footprints(compiled, sim))
    feats.extend(_sortie_features(rep, home_amsl))
    props: dict[str, Any] = {"plan": compiled.name, "firmware": compiled.firmware,
                             "generator": "wiris-tools", "altitudes": "metres AMSL (home AMSL + height above home)"}
    if not write_fp:
        props["footprints_omitted"] = (f"{n_fp} footprints exceed {MAX_FOOTPRINT_FEATURES}; "
                                       "photo points are complete")
    return {"type": "FeatureCollection", "properties": props, "features": feats}


def _vertex_amsl(compiled: Compiled, sim: Simulation) -> list[float]:
    """Each path vertex's altitude above mean sea level: home's elevation plus its height above home, or over a
    DEM the ground plus its height for a vertex in the terrain frame (missions.terrain.clearance)."""
    if getattr(compiled, "terrain", None) is None or not sim.vertices:
        return [compiled.home[2] + v.alt_m for v in sim.vertices]
    from missions.terrain.clearance import vertex_heights
    return vertex_heights(compiled, sim, compiled.terrain.dem)[0].tolist()


def _photo_heights(compiled: Compiled, sim: Simulation) -> tuple[np.ndarray, np.ndarray] | None:
    """(camera altitude AMSL, ground AMSL below) of every photo when the plan has a DEM, else None."""
    if getattr(compiled, "terrain", None) is None or not sim.photos:
        return None
    from missions.terrain.reflight import camera_amsl
    ground = compiled.terrain.dem.ground_amsl([p.lat for p in sim.photos], [p.lon for p in sim.photos])
    return camera_amsl(compiled, sim.photos, ground), ground


def _sortie_features(rep: MissionReport, home_amsl: float) -> list[dict]:
    table = rep.sorties
    if table is None:
        return []
    return [{"type": "Feature", "properties": {"kind": "sortie", "sortie": k, **row},
             "geometry": {"type": "LineString",
                          "coordinates": [[_r7(lon), _r7(lat), round(home_amsl + alt, 2)] for lat, lon, alt in path]}}
            for k, (row, path) in enumerate(zip(table.rows, table.paths), start=1)]


def _footprints(compiled: Compiled, sim: Simulation) -> list[dict]:
    """Footprint polygons of every photo and payload, corners computed at once (one projection call)."""
    owners = [(k, name) for k, p in enumerate(sim.photos) for name in p.payloads]
    if not owners:
        return []
    if getattr(compiled, "terrain", None) is not None:      # cut by the DEM (missions.terrain.reflight)
        from missions.terrain.reflight import footprint_rings
        return _polygon_features(owners, footprint_rings(compiled, sim, owners), sim)
    ph = sim.photos
    idx = np.array([k for k, _ in owners])
    c = np.array([(ph[k].x, ph[k].y) for k in idx], dtype=float)
    alt = np.maximum(np.array([ph[k].alt_m for k in idx]), 0.0)
    h = np.radians([ph[k].heading_deg for k in idx])
    unit = {p.name: p.footprint_m(1.0) for p in compiled.payloads}      # footprints scale with altitude
    across = alt * np.array([unit[n][0] for _, n in owners]) / 2
    along = alt * np.array([unit[n][1] for _, n in owners]) / 2
    d = np.column_stack([np.sin(h), np.cos(h)])
    n = np.column_stack([np.cos(h), -np.sin(h)])
    a, b = d * along[:, None], n * across[:, None]
    corners = np.stack([c - a - b, c + a - b, c + a + b, c - a + b, c - a - b], axis=1)   # as footprint_ring
    return _polygon_features(owners, corners, sim)


def _polygon_features(owners: list[tuple[int, str]], corners: np.ndarray, sim: Simulation) -> list[dict]:
    """Footprint features from closed rings (m, k, 2) in the simulation's metres."""
    k_pts = corners.shape[1]
    lat, lon = sim.projection.to_latlon(corners[..., 0].ravel(), corners[..., 1].ravel())
    lat = np.round(lat, 7).reshape(-1, k_pts).tolist()
    lon = np.round(lon, 7).reshape(-1, k_pts).tolist()
    return [{"type": "Feature", "properties": {"kind": "footprint", "photo": k, "payload": name},
             "geometry": {"type": "Polygon", "coordinates": [[[b, a] for a, b in zip(la, lo)]]}}
            for (k, name), la, lo in zip(owners, lat, lon)]


def dumps_collection(fc: dict) -> str:
    """The collection as text: one feature per line (diffable, and json's C encoder instead of its slow
    indenting one). JSON has no NaN: a non-finite number anywhere becomes null."""
    def dump(obj: Any) -> str:
        try:
            return json.dumps(obj, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
        except ValueError:
            return json.dumps(finite(obj), ensure_ascii=False, allow_nan=False, separators=(",", ":"))

    head = dump({k: v for k, v in fc.items() if k != "features"})[:-1]
    return head + ',"features":[\n' + ",\n".join(dump(f) for f in fc["features"]) + "\n]}\n"
