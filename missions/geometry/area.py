"""Survey areas: read (inline [lat, lon] list, GeoJSON, KML), clean, validate, project, subtract exclusions
(dropping the slivers narrower than MIN_PART_WIDTH_M they cut off; `Area.excluded` keeps the zones as drawn).

    area = load_area("areas/north.kml", exclude=["areas/substation.geojson"], base_dir=plan_dir)
    area.geometry      # shapely Polygon | MultiPolygon in metres (x east, y north), exterior CCW
    area.projection    # missions.geometry.geo.LocalProjection used for it (and for everything planned on it)

Every problem is a `PlanError` saying where (file:line for KML, file + JSON path for GeoJSON, `area[i]`
for inline points), what, and a hint: fewer than 3 points, zero area, self-intersection (with the two
crossing edges and the crossing's lat/lon), KML without a polygon, GeoJSON in a projected CRS, an area that
is empty once exclusions are removed. Files are parsed with limits (size cap; KML without DTD, entities or
network access).
"""

from __future__ import annotations

from dataclasses import dataclass
import json
import math
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np

from cdf.errors import ECHO_CHARS, clip, shown
from cdf.userfile import UserFile, read_user_file
from missions.errors import PlanError
from missions.geometry.geo import LocalProjection, leaf_parts

MAX_AREA_FILE_BYTES = 20 * 1024 * 1024   # a 20 MB boundary file is already ~500k vertices
MAX_VERTICES = 200_000
# Vertices closer than this are one vertex: KML/GeoJSON exports often repeat points at 1e-9° noise.
DEDUP_TOLERANCE_M = 0.01
# Anything smaller is a degenerate (collinear) ring, not a survey area.
MIN_AREA_M2 = 0.5
# A piece of the area that an exclusion cuts off and that is nowhere this wide is dropped: a multirotor's
# GNSS cross-track error is ~0.5–1 m (swaths.DEFAULT_EDGE_MARGIN_M), so a strip narrower than 1 m cannot be
# flown or photographed without photographing the exclusion beside it, and such strips are almost always a
# digitising gap (an exclusion drawn to "the boundary" that stops a few decimetres short), not ground anyone
# wants surveyed. Kept, each became a part with lines, turns and photos of its own.
MIN_PART_WIDTH_M = 1.0

# GeoJSON "crs" names that mean WGS84 lon/lat (RFC 7946 dropped the member; old files still carry it).
_WGS84_NAMES = ("CRS84", "CRS:84", "EPSG:4326", "EPSG::4326", "WGS84", "WGS 84")


@dataclass(frozen=True)
class LatLonPolygon:
    """One polygon as read from the source, before projection. Points are (lat, lon) degrees."""

    outer: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...]
    where: str
    ring_wheres: tuple[str, ...] = ()     # per ring (outer first), e.g. the line of each KML <coordinates>


@dataclass(frozen=True)
class Area:
    """A cleaned, projected survey area."""

    geometry: Any                      # shapely Polygon | MultiPolygon, metres
    projection: LocalProjection
    source: str = ""
    # the source polygons' holes and the exclusion zones as drawn (not clipped to the area), metres; empty when
    # there are none, None when not recorded (an Area built by hand: its geometry's holes are all there is).
    # The route keeps its turnarounds out of them and the report measures the path inside them.
    excluded: Any = None
    # pieces narrower than MIN_PART_WIDTH_M that the exclusions cut off and that were dropped: (count, m²)
    dropped: tuple[int, float] = (0, 0.0)
    # the polygons as drawn, before the exclusions (and their margin) were taken away; None: not recorded
    drawn: Any = None
    # what the route keeps its turnarounds and connections out of when that is more than `excluded`: the holes and
    # the exclusions grown by their margin (build_area's margin_m); None: `excluded`
    keep_out: Any = None

    @property
    def area_m2(self) -> float:
        return float(self.geometry.area)

    @property
    def polygons(self) -> list[Any]:
        g = self.geometry
        return list(g.geoms) if g.geom_type == "MultiPolygon" else [g]

    def latlon_rings(self) -> list[list[list[tuple[float, float]]]]:
        """[[outer, hole, ...], ...] with (lat, lon) tuples — for GeoJSON/KML/fence output."""
        out = []
        for p in self.polygons:
            rings = []
            for ring in [p.exterior, *p.interiors]:
                xy = np.asarray(ring.coords)
                lat, lon = self.projection.to_latlon(xy[:, 0], xy[:, 1])
                rings.append(list(zip(lat.tolist(), lon.tolist())))
            out.append(rings)
        return out


# ----------------------------------------------------------------------------------------------- readers

AREA_FILE = UserFile("area file", MAX_AREA_FILE_BYTES, PlanError,
                     hint="paths in a plan are relative to the plan file",
                     size_hint="simplify the boundary (e.g. ogr2ogr -simplify 0.5)")


def _read_bytes(path: Path) -> bytes:
    return read_user_file(path, AREA_FILE)


def read_area_source(source: Any, base_dir: str | Path | None = None, where: str = "area") -> list[LatLonPolygon]:
    """An inline list of [lat, lon] points, or a path to a .kml / .geojson / .json file."""
    if isinstance(source, (str, Path)):
        path = Path(source)
        if base_dir is not None and not path.is_absolute():
            path = Path(base_dir) / path
        suffix = path.suffix.lower()
        if suffix == ".kml":
            return read_kml(path)
        if suffix in (".geojson", ".json"):
            return read_geojson(path)
        if suffix == ".kmz":
            raise PlanError("KMZ (zipped KML) is not read directly", where=str(path),
                            hint="unzip it and point the plan at the doc.kml inside")
        raise PlanError(f"unknown area file type '{suffix or path.name}'", where=str(path),
                        hint="use a .kml, .geojson or .json file, or an inline list of [lat, lon] points")
    if isinstance(source, (list, tuple)):
        return [_inline_polygon(source, where)]
    raise PlanError(f"an area must be a file path or a list of [lat, lon] points, got {type(source).__name__}",
                    where=where, hint="e.g. area: areas/field.kml, or [[50.110, 14.500], [50.110, 14.503], "
                                      "[50.112, 14.503]]")


def _inline_polygon(points: Sequence[Any], where: str) -> LatLonPolygon:
    pts: list[tuple[float, float]] = []
    for i, p in enumerate(points):
        here = f"{where}[{i}]"
        if not (isinstance(p, (list, tuple)) and len(p) in (2, 3)
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)):
            raise PlanError(f"point must be [lat, lon], got {shown(p)}", where=here,
                            hint="each point is two numbers, latitude then longitude in degrees, "
                                 "e.g. [50.0696, 14.7263]")
        lat, lon = float(p[0]), float(p[1])
        if not (math.isfinite(lat) and math.isfinite(lon)):
            raise PlanError("point is not finite", where=here,
                            hint="replace the NaN/infinite value by a latitude and longitude in degrees")
        if abs(lat) > 90 or abs(lon) > 180:
            hint = ("inline points are [lat, lon]; this looks like [lon, lat]"
                    if abs(lat) <= 180 and abs(lon) <= 90 else "coordinates must be WGS84 degrees")
            raise PlanError(f"point {shown(p)} is outside ±90° latitude / ±180° longitude", where=here, hint=hint)
        pts.append((lat, lon))
    return LatLonPolygon(tuple(pts), (), where)


# GeoJSON --------------------------------------------------------------------------------------------------

def read_geojson(path: Path) -> list[LatLonPolygon]:
    data = _read_bytes(path)
    try:
        # every number as a float: coordinates are floats, and an integer of 5000 digits would stop
        # Python's int() (ValueError) or float(int) (OverflowError); as a float it is inf, reported below
        doc = json.loads(data.decode("utf-8-sig"), parse_int=float)
    except UnicodeDecodeError as e:
        raise PlanError(f"GeoJSON is not UTF-8 ({e.reason})", where=str(path),
                        hint="save it as UTF-8 (not UTF-16 or a legacy code page): RFC 7946 GeoJSON is "
                             "UTF-8") from None
    except json.JSONDecodeError as e:
        raise PlanError(f"invalid JSON: {clip(e.msg, 2 * ECHO_CHARS)}", where=f"{path}:{e.lineno}:{e.colno}",
                        hint="fix the JSON there (a missing comma, bracket or quote?) or export the area "
                             "again") from None
    except RecursionError:
        raise PlanError("JSON nested too deeply", where=str(path),
                        hint="a GeoJSON area nests arrays at most 4 deep (MultiPolygon); export it again "
                             "from your GIS") from None
    if not isinstance(doc, dict):
        raise PlanError("GeoJSON must be an object", where=str(path),
                        hint='the file must hold one object, e.g. {"type": "Polygon", "coordinates": '
                             '[[[lon, lat], ...]]}')
    _check_geojson_crs(doc, str(path))
    polys: list[LatLonPolygon] = []
    _collect_geojson(doc, str(path), "$", polys, depth=0)
    if not polys:
        raise PlanError("GeoJSON contains no Polygon or MultiPolygon", where=str(path),
                        hint="draw the survey area as a polygon (points and lines cannot be surveyed)")
    return polys


def _check_geojson_crs(doc: dict, where: str) -> None:
    crs = doc.get("crs")
    if crs is None:
        return
    name = ""
    if isinstance(crs, dict):
        props = crs.get("properties")
        if isinstance(props, dict):
            name = str(props.get("name") or props.get("href") or "")
    if not any(w.lower() in name.lower() for w in _WGS84_NAMES):
        raise PlanError(f"GeoJSON declares the coordinate system {clip(name) if name else shown(crs)}; only WGS84 longitude/latitude is read",
                        where=f"{where}: crs",
                        hint="reproject it to WGS84, e.g. `ogr2ogr -t_srs EPSG:4326 out.geojson in.geojson`")


def _collect_geojson(obj: Any, file: str, jpath: str, out: list[LatLonPolygon], depth: int) -> None:
    if depth > 32:
        raise PlanError("GeoJSON nested too deeply", where=f"{file}: {jpath}",
                        hint="put the polygons in one FeatureCollection (collections nest at most 32 levels)")
    if not isinstance(obj, dict):
        raise PlanError("expected a GeoJSON object", where=f"{file}: {jpath}",
                        hint='features and geometries are objects with a "type", e.g. {"type": "Polygon", ...}')
    kind = obj.get("type")
    if kind == "FeatureCollection":
        feats = obj.get("features")
        if not isinstance(feats, list):
            raise PlanError("FeatureCollection without a 'features' list", where=f"{file}: {jpath}",
                            hint='give it "features": [...], a list of Feature objects (RFC 7946 §3.3)')
        for i, f in enumerate(feats):
            _collect_geojson(f, file, f"{jpath}.features[{i}]", out, depth + 1)
    elif kind == "Feature":
        g = obj.get("geometry")
        if g is not None:
            _collect_geojson(g, file, f"{jpath}.geometry", out, depth + 1)
    elif kind == "GeometryCollection":
        geoms = obj.get("geometries")
        if not isinstance(geoms, list):
            raise PlanError("GeometryCollection without a 'geometries' list", where=f"{file}: {jpath}",
                            hint='give it "geometries": [...], a list of geometry objects (RFC 7946 §3.1.8)')
        for i, g in enumerate(geoms):
            _collect_geojson(g, file, f"{jpath}.geometries[{i}]", out, depth + 1)
    elif kind == "Polygon":
        out.append(_geojson_polygon(obj.get("coordinates"), file, f"{jpath}.coordinates"))
    elif kind == "MultiPolygon":
        coords = obj.get("coordinates")
        if not isinstance(coords, list):
            raise PlanError("MultiPolygon without coordinates", where=f"{file}: {jpath}",
                            hint='give it "coordinates": [[[[lon, lat], ...]]] (polygons > rings > positions)')
        for i, c in enumerate(coords):
            out.append(_geojson_polygon(c, file, f"{jpath}.coordinates[{i}]"))
    elif kind in ("Point", "MultiPoint", "LineString", "MultiLineString"):
        return
    else:
        raise PlanError(f"unknown GeoJSON type {shown(kind)}", where=f"{file}: {jpath}",
                        hint="supported: Polygon, MultiPolygon, Feature, FeatureCollection, GeometryCollection "
                             "(case matters)")


def _geojson_polygon(coords: Any, file: str, jpath: str) -> LatLonPolygon:
    if not isinstance(coords, list) or not coords:
        raise PlanError("Polygon without rings", where=f"{file}: {jpath}",
                        hint='"coordinates" is a list of rings, the outer one first: [[[lon, lat], [lon, lat], ...]]')
    rings = []
    for r, ring in enumerate(coords):
        if not isinstance(ring, list):
            raise PlanError("a ring must be a list of [lon, lat] positions", where=f"{file}: {jpath}[{r}]",
                            hint="a Polygon's coordinates nest three levels: [[[14.7263, 50.0696], "
                                 "[14.7281, 50.0696], ...]]")
        pts = []
        for i, p in enumerate(ring):
            here = f"{file}: {jpath}[{r}][{i}]"
            if not (isinstance(p, list) and len(p) >= 2
                    and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p[:2])):
                raise PlanError(f"position must be [lon, lat], got {shown(p)}", where=here,
                                hint="each position is [lon, lat] in degrees (GeoJSON order), "
                                     "e.g. [14.7263, 50.0696]")
            lon, lat = float(p[0]), float(p[1])
            if not (math.isfinite(lat) and math.isfinite(lon)):
                raise PlanError(f"position {shown(p[:2])} holds a number that is not finite (or too long to read)",
                                where=here, hint="each position is [lon, lat] in degrees (GeoJSON order), "
                                                 "e.g. [14.7263, 50.0696]")
            if abs(lat) > 90 or abs(lon) > 180:
                raise PlanError(f"position {shown(p[:2])} is not a longitude/latitude in degrees", where=here,
                                hint="the file looks like it uses a projected CRS (metres); reproject it to "
                                     "WGS84: `ogr2ogr -t_srs EPSG:4326 out.geojson in.geojson`")
            pts.append((lat, lon))
        rings.append(tuple(pts))
    wheres = tuple(f"{file}: {jpath}[{r}]" for r in range(len(rings)))
    return LatLonPolygon(rings[0], tuple(rings[1:]), f"{file}: {jpath}", wheres)


# KML ------------------------------------------------------------------------------------------------------

def read_kml(path: Path) -> list[LatLonPolygon]:
    from lxml import etree

    data = _read_bytes(path)
    # No DTD, no entities, no network: KML needs none of them and each is an attack surface (XXE,
    # billion laughs). lxml with resolve_entities=False still records a DOCTYPE, so refuse it explicitly.
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, dtd_validation=False,
                             huge_tree=False, remove_comments=True, remove_pis=True)
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as e:
        # libxml2 refuses an entity bomb (billion laughs, a reference loop) while parsing, before the
        # DOCTYPE check below can run: these are its messages
        if "entity amplification" in e.msg or "entity reference loop" in e.msg:
            raise _dtd_refused(path) from None
        line = e.position[0] if e.position else None
        hint = ("write a literal & in text as &amp;" if "Entity '" in e.msg and "not defined" in e.msg else
                "fix the XML at that line (an unclosed or misspelt tag?) or export the KML again")
        raise PlanError(f"KML is not well-formed XML: {clip(e.msg, 2 * ECHO_CHARS)}",
                        where=f"{path}:{line}" if line else str(path), hint=hint) from None
    if root is None:
        raise PlanError("KML is empty", where=str(path),
                        hint="export the area again as KML from Google Earth or QGIS")
    doc = root.getroottree().docinfo
    if doc.doctype or doc.internalDTD is not None:
        raise _dtd_refused(path)
    polys: list[LatLonPolygon] = []
    for el in root.iter():
        if isinstance(el.tag, str) and etree.QName(el).localname == "Polygon":
            polys.append(_kml_polygon(el, path))
    if not polys:
        raise PlanError("KML contains no Polygon", where=str(path),
                        hint="draw the survey area as a polygon (Google Earth: 'Add Polygon'); "
                             "paths and placemarks cannot be surveyed")
    return polys


def _dtd_refused(path: Path) -> PlanError:
    return PlanError("KML with a DTD or entities is refused (entity expansion)", where=str(path),
                     hint="KML needs no DTD: remove the <!DOCTYPE ...> declaration and its <!ENTITY ...> lines")


def _kml_children(el: Any, name: str) -> list[Any]:
    from lxml import etree
    return [c for c in el if isinstance(c.tag, str) and etree.QName(c).localname == name]


def _kml_ring_where(boundary: Any, path: Path) -> str:
    from lxml import etree
    for el in boundary.iter():
        if isinstance(el.tag, str) and etree.QName(el).localname == "coordinates":
            return f"{path}:{el.sourceline}"
    return f"{path}:{boundary.sourceline}"


def _kml_ring(boundary: Any, path: Path) -> tuple[tuple[float, float], ...]:
    from lxml import etree
    coords_el = None
    for el in boundary.iter():
        if isinstance(el.tag, str) and etree.QName(el).localname == "coordinates":
            coords_el = el
            break
    where = f"{path}:{(coords_el if coords_el is not None else boundary).sourceline}"
    if coords_el is None or not (coords_el.text or "").strip():
        raise PlanError("polygon boundary without <coordinates>", where=where,
                        hint="give the ring as <LinearRing><coordinates>lon,lat lon,lat ...</coordinates>"
                             "</LinearRing>")
    pts = []
    for tok in coords_el.text.split():
        parts = tok.split(",")
        try:
            lon, lat = float(parts[0]), float(parts[1])
        except (ValueError, IndexError):
            raise PlanError(f"bad KML coordinate {shown(tok)}; expected lon,lat[,alt]", where=where,
                            hint="no spaces inside a tuple, one between tuples: 14.7263,50.0696,0 "
                                 "14.7281,50.0696,0") from None
        if not (math.isfinite(lat) and math.isfinite(lon)):
            raise PlanError(f"KML coordinate {shown(tok)} holds a number that is not finite", where=where,
                            hint="longitude first, in WGS84 degrees: 14.7263,50.0696")
        if abs(lat) > 90 or abs(lon) > 180:
            raise PlanError(f"KML coordinate {shown(tok)} is not lon,lat in degrees", where=where,
                            hint="longitude first, in WGS84 degrees (14.7263,50.0696); reproject a file in "
                                 "metres to EPSG:4326")
        pts.append((lat, lon))
    return tuple(pts)


def _kml_polygon(poly: Any, path: Path) -> LatLonPolygon:
    outer = _kml_children(poly, "outerBoundaryIs")
    if not outer:
        raise PlanError("Polygon without <outerBoundaryIs>", where=f"{path}:{poly.sourceline}",
                        hint="the outer ring goes in <outerBoundaryIs><LinearRing><coordinates> inside "
                             "the <Polygon>")
    inner = _kml_children(poly, "innerBoundaryIs")
    holes = tuple(_kml_ring(b, path) for b in inner)
    wheres = tuple(_kml_ring_where(b, path) for b in [outer[0], *inner])
    return LatLonPolygon(_kml_ring(outer[0], path), holes, f"{path}:{poly.sourceline}", wheres)


# ------------------------------------------------------------------------------------- cleaning & checks

def _clean_ring(lats: np.ndarray, lons: np.ndarray, proj: LocalProjection, where: str, what: str):
    """Projected ring without duplicate/closing vertices, and the original index of each kept vertex."""
    if len(lats) > MAX_VERTICES:
        raise PlanError(f"{what} has {len(lats)} vertices (limit {MAX_VERTICES})", where=where,
                        hint="simplify the boundary")
    x, y = proj.to_xy(lats, lons)
    from missions.geometry.geo import MAX_EXTENT_M
    far = ~(np.isfinite(x) & np.isfinite(y)) | (np.hypot(x, y) > MAX_EXTENT_M)
    if far.any():
        i = int(np.argmax(far))
        raise PlanError(f"{what} vertex {i} lies more than {MAX_EXTENT_M / 1000:.0f} km from the area's centre",
                        where=where, hint="one plan covers a local area; split it, or check the coordinates "
                                          "(lat/lon swapped, or a vertex at 0,0)")
    keep: list[int] = []
    for i in range(len(x)):
        if keep and math.hypot(x[i] - x[keep[-1]], y[i] - y[keep[-1]]) < DEDUP_TOLERANCE_M:
            continue
        keep.append(i)
    while len(keep) > 1 and math.hypot(x[keep[0]] - x[keep[-1]], y[keep[0]] - y[keep[-1]]) < DEDUP_TOLERANCE_M:
        keep.pop()
    if len(keep) < 3:
        raise PlanError(f"{what} has fewer than 3 distinct points ({len(keep)})", where=where,
                        hint="a survey area needs at least 3 corners")
    idx = np.asarray(keep)
    return np.column_stack([x[idx], y[idx]]), idx


def _check_ring(xy: np.ndarray, idx: np.ndarray, proj: LocalProjection, where: str, what: str):
    import shapely
    from shapely.geometry import LinearRing, Polygon

    ring = LinearRing(xy)
    # "Zero" is relative: three points along a 3 km line enclose ~200 m² through the projection's
    # curvature, but a ring whose mean width is below 10 cm is a line, not an area.
    # make_valid: a bow-tie has signed area 0 but is two real triangles; a fold is a line.
    zero = shapely.make_valid(Polygon(ring)).area < max(MIN_AREA_M2, 0.05 * ring.length)
    if zero:
        raise PlanError(f"{what} has zero area (its points are collinear or it folds onto itself)", where=where,
                        hint="check that the points are corners of an area, not a line")
    if not ring.is_simple:
        n = len(xy)
        segs = shapely.linestrings(np.stack([xy, np.roll(xy, -1, axis=0)], axis=1))
        tree = shapely.STRtree(segs)
        a, b = tree.query(segs, predicate="intersects")
        for i, j in zip(a.tolist(), b.tolist()):
            if j <= i or (j - i) % n in (1, n - 1):
                continue
            cross = segs[i].intersection(segs[j])
            if cross.geom_type != "Point":
                continue        # overlapping edges: a fold, reported below
            c = cross
            lat, lon = proj.point_to_latlon(c.x, c.y)
            ei = f"{idx[i]}→{idx[(i + 1) % n]}"
            ej = f"{idx[j]}→{idx[(j + 1) % n]}"
            raise PlanError(f"{what} intersects itself: edge {ei} crosses edge {ej} near lat {lat:.7f}, lon {lon:.7f}",
                            where=where, hint="reorder the points so the boundary does not cross itself "
                                              "(vertex numbers count from 0 in file order)")
        raise PlanError(f"{what} intersects itself (an edge doubles back on its neighbour)", where=where,
                        hint="remove the spike in the boundary")
    return ring


def _project_polygon(p: LatLonPolygon, proj: LocalProjection):
    from shapely.geometry import Polygon
    from shapely.geometry.polygon import orient
    from shapely.validation import explain_validity

    def ring_of(pts, what, r):
        where = p.ring_wheres[r] if r < len(p.ring_wheres) else p.where
        arr = np.asarray(pts, dtype=float).reshape(-1, 2)
        xy, idx = _clean_ring(arr[:, 0], arr[:, 1], proj, where, what)
        return _check_ring(xy, idx, proj, where, what)

    outer = ring_of(p.outer, "polygon", 0)
    holes = [ring_of(h, f"hole {k}", k + 1) for k, h in enumerate(p.holes)]
    shell = Polygon(outer)
    for k, hole in enumerate(holes):
        if not shell.covers(Polygon(hole)):
            where = p.ring_wheres[k + 1] if k + 1 < len(p.ring_wheres) else p.where
            lat, lon = proj.point_to_latlon(*_outside_point(shell, hole))
            raise PlanError(f"hole {k} is not inside the polygon's outer boundary (it reaches out near lat "
                            f"{lat:.7f}, lon {lon:.7f})", where=where,
                            hint="a hole (inner boundary) cuts an area out of its polygon and must lie within "
                                 "it; to leave out ground elsewhere, use exclude:")
    poly = Polygon(outer, holes)
    if not poly.is_valid:
        raise PlanError(f"polygon is invalid: {_in_latlon(explain_validity(poly), proj)}", where=p.where,
                        hint="holes must lie inside the outer boundary and must not touch each other")
    return orient(poly, 1.0)


def _outside_point(shell: Any, hole: Any) -> tuple[float, float]:
    """A vertex of `hole` outside `shell` (x, y), or where the two boundaries cross when none is."""
    from shapely.geometry import Point

    for x, y in hole.coords:
        if not shell.covers(Point(x, y)):
            return x, y
    c = shell.exterior.intersection(hole).representative_point()
    return c.x, c.y


def _in_latlon(reason: str, proj: LocalProjection) -> str:
    """shapely's validity reason ("Self-intersection[x y]", local metres) with the place in lat/lon."""
    import re

    def latlon(m: re.Match) -> str:
        lat, lon = proj.point_to_latlon(float(m[1]), float(m[2]))
        return f" near lat {lat:.7f}, lon {lon:.7f}"
    return re.sub(r"\[(\S+) (\S+)\]", latlon, reason)


def _polygonal(g: Any) -> Any:
    """Only the areal parts of a shapely result (differences can leave lines and points behind)."""
    from shapely.geometry import MultiPolygon
    parts = [h for h in leaf_parts(g, "Polygon") if h.area >= MIN_AREA_M2]
    if not parts:
        return MultiPolygon()
    return parts[0] if len(parts) == 1 else MultiPolygon(parts)


def build_area(polygons: Sequence[LatLonPolygon], exclusions: Sequence[LatLonPolygon] = (),
               source: str = "", projection: LocalProjection | None = None, margin_m: float = 0.0) -> Area:
    """Project, clean and validate polygons (centring the projection on them), union them, subtract exclusions
    grown by `margin_m` (the position error a zone is kept clear by: missions.geometry.zones)."""
    import shapely
    from shapely.geometry.polygon import orient

    if not polygons:
        raise PlanError("no polygon given for the area", where=source or None,
                        hint="give build_area at least one polygon (from a plan: a bug in wiris-tools, "
                             "please report it)")
    for p in [*polygons, *exclusions]:
        if len(p.outer) < 3:
            raise PlanError(f"polygon has fewer than 3 points ({len(p.outer)})", where=p.where,
                            hint="a survey area needs at least 3 corners")
    if projection is None:
        lats = [pt[0] for p in polygons for pt in p.outer]
        lons = [pt[1] for p in polygons for pt in p.outer]
        projection = LocalProjection.centred_on(lats, lons)
    for p in [*polygons, *exclusions]:
        _check_latitudes(p)
    projected = [_project_polygon(p, projection) for p in polygons]
    geom = shapely.union_all(projected) if len(projected) > 1 else projected[0]
    _check_extent(geom, source)
    drawn = geom
    from shapely.geometry import Polygon
    holes = [Polygon(r) for p in projected for r in p.interiors]
    cut = None
    dropped = (0, 0.0)
    if exclusions:
        cut = shapely.union_all([_project_polygon(e, projection) for e in exclusions])
        grown = cut.buffer(margin_m, join_style="mitre") if margin_m > 0 else cut
        geom = geom.difference(grown)
        geom, dropped = _drop_slivers(_polygonal(geom), grown)
        if geom.is_empty:
            raise PlanError("the area is empty once the exclusion zones are removed", where=source or None,
                            hint="check that the exclusions do not cover the whole area (pieces narrower than "
                                 f"{MIN_PART_WIDTH_M:g} m that they leave are not surveyed)")
    geom = _polygonal(geom)
    if geom.geom_type == "Polygon":
        geom = orient(geom, 1.0)
    else:
        from shapely.geometry import MultiPolygon
        geom = MultiPolygon([orient(g, 1.0) for g in geom.geoms])
    zones = [*holes, *([cut] if cut is not None else [])]
    excluded = (shapely.union_all(zones) if len(zones) > 1 else zones[0]) if zones else Polygon()
    keep_out = shapely.union_all([*holes, grown]) if exclusions and margin_m > 0 else None
    return Area(geom, projection, source, excluded, dropped, drawn, keep_out)


def _drop_slivers(geom: Any, cut: Any) -> tuple[Any, tuple[int, float]]:
    """`geom` without the parts next to the exclusions `cut` that are nowhere MIN_PART_WIDTH_M wide (see there),
    and (how many were dropped, their m²). Parts that do not touch an exclusion are the user's own polygons and
    stay whatever their width."""
    from shapely.geometry import MultiPolygon
    parts = list(leaf_parts(geom, "Polygon"))
    keep, gone = [], []
    for g in parts:
        # every point of a narrow part lies within half the width of its boundary, so its area is at most
        # perimeter x half the width: a larger part is wide somewhere without the costlier inward buffer
        narrow = g.area <= g.length * MIN_PART_WIDTH_M / 2.0 and g.buffer(-MIN_PART_WIDTH_M / 2.0).is_empty
        (gone if narrow and g.distance(cut) < 1e-6 else keep).append(g)
    if not gone:
        return geom, (0, 0.0)
    out = keep[0] if len(keep) == 1 else MultiPolygon(keep)
    return out, (len(gone), float(sum(g.area for g in gone)))


def _check_latitudes(p: LatLonPolygon) -> None:
    from missions.geometry.geo import MAX_ABS_LAT_DEG
    for ring in (p.outer, *p.holes):
        for i, (lat, _lon) in enumerate(ring):
            if abs(lat) > MAX_ABS_LAT_DEG:
                raise PlanError(f"vertex {i} at latitude {lat:.5f}° is too close to a pole", where=p.where,
                                hint=f"areas must lie within ±{MAX_ABS_LAT_DEG:g}° latitude")


def _check_extent(geom: Any, source: str) -> None:
    from missions.geometry.geo import MAX_EXTENT_M
    x0, y0, x1, y1 = geom.bounds
    size = max(x1 - x0, y1 - y0)
    if size > MAX_EXTENT_M:
        raise PlanError(f"area spans {size / 1000:.0f} km, more than the {MAX_EXTENT_M / 1000:.0f} km one plan can hold",
                        where=source or None, hint="split it into several plans")


def load_area(source: Any, exclude: Iterable[Any] = (), base_dir: str | Path | None = None,
              where: str = "area") -> Area:
    """Read an area (file path or inline [lat, lon] list) and its exclusion zones; return the projected Area."""
    polys = read_area_source(source, base_dir, where)
    excl: list[LatLonPolygon] = []
    for k, e in enumerate(exclude):
        excl.extend(read_area_source(e, base_dir, f"exclude[{k}]"))
    label = str(source) if isinstance(source, (str, Path)) else where
    return build_area(polys, excl, label)
