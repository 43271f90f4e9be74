"""NAME.kml: the GeoJSON feature collection of `geojson_out` rendered as KML 2.2 (Google Earth, QGIS).

Same features, same coordinates; folders by kind. Altitudes are absolute (AMSL), as in the GeoJSON, so
Google Earth draws the path at its flying height. Text is escaped; nothing from the plan reaches the file
unescaped.
"""

from __future__ import annotations

from xml.sax.saxutils import escape

STYLES = {
    "area": ("7f3cb44b", "ff3cb44b", 2),        # aabbggrr: green fill, green line
    "gap": ("7f4b4be6", "ff4b4be6", 2),         # red
    "path": ("00000000", "ffd86b1e", 3),        # blue line
    "footprint": ("1400a5ff", "6000a5ff", 1),   # faint orange
    "fence": ("200000ff", "ff0000ff", 2),       # red line, faint fill (`wiris mission convert`)
}
# one line colour per sortie (cycled), so that neighbouring sorties tell apart
SORTIE_COLOURS = ("ff3030e6", "ff1ea0ff", "ff00b000", "ffb01ea0", "ffa0a000", "ff0060c0")
FOLDERS = (("area", "Areas"), ("gap", "Holes and exclusions"), ("path", "Flight path"), ("sortie", "Sorties"),
           ("home", "Home"), ("waypoint", "Waypoints"), ("photo", "Photos"), ("footprint", "Footprints"),
           ("fence", "Fence"), ("fence_return", "Fence return point"), ("rally", "Rally points"))


def _coords(points) -> str:
    # GeoJSON side already rounded to 7 decimals (~1 cm); %g keeps that and drops trailing zeros
    return " ".join(",".join(["%.12g" % c for c in p]) for p in points)


def _ring(points) -> str:
    return f"<LinearRing><coordinates>{_coords(points)}</coordinates></LinearRing>"


def _polygon(rings) -> str:
    inner = "".join(f"<innerBoundaryIs>{_ring(r)}</innerBoundaryIs>" for r in rings[1:])
    return f"<Polygon><outerBoundaryIs>{_ring(rings[0])}</outerBoundaryIs>{inner}</Polygon>"


def _geometry(g: dict) -> str:
    t = g["type"]
    c = g["coordinates"]
    if t == "Point":
        return f"<Point><altitudeMode>absolute</altitudeMode><coordinates>{_coords([c])}</coordinates></Point>"
    if t == "LineString":
        return (f"<LineString><altitudeMode>absolute</altitudeMode><tessellate>0</tessellate>"
                f"<coordinates>{_coords(c)}</coordinates></LineString>")
    if t == "Polygon":
        return _polygon(c)
    if t == "MultiPolygon":
        return "<MultiGeometry>" + "".join(_polygon(p) for p in c) + "</MultiGeometry>"
    raise ValueError(f"no KML for geometry {t}")


def _name(p: dict) -> str:
    kind = p["kind"]
    if kind == "area":
        return f"step {p['step']}: {p['area_kind']} ({p['area_m2']:.0f} m²)"
    if kind == "waypoint":
        return f"{p['seq']} {p['command']}"
    if kind == "photo":
        return f"photo {p['index']}"
    if kind == "footprint":
        return f"footprint {p['photo']} {p['payload']}"
    if kind == "sortie":
        return f"sortie {p['sortie']} ({p['file']})"
    if kind == "fence":
        return f"fence {'inclusion' if p['inclusion'] else 'exclusion'}"
    if kind == "rally":
        return f"rally point {p['index']}"
    return kind


def _description(p: dict) -> str:
    rows = "".join(f"{k}: {v}\n" for k, v in p.items() if k != "kind" and v not in ("", None))
    return escape(rows)


def render_kml(fc: dict) -> str:
    name = escape(str(fc.get("properties", {}).get("plan", "mission")))
    out = ['<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2"><Document>',
           f"<name>{name}</name>"]
    for kind, (fill, line, width) in STYLES.items():
        out.append(f'<Style id="{kind}"><LineStyle><color>{line}</color><width>{width}</width></LineStyle>'
                   f"<PolyStyle><color>{fill}</color></PolyStyle></Style>")
    for k, line in enumerate(SORTIE_COLOURS):
        out.append(f'<Style id="sortie{k}"><LineStyle><color>{line}</color><width>3</width></LineStyle></Style>')
    for kind, title in FOLDERS:
        feats = [f for f in fc["features"] if f["properties"]["kind"] == kind]
        if not feats:
            continue
        out.append(f"<Folder><name>{escape(title)}</name>")
        for f in feats:
            p = f["properties"]
            style = f"<styleUrl>#{kind}</styleUrl>" if kind in STYLES else ""
            if kind == "sortie":
                style = f"<styleUrl>#sortie{(p['sortie'] - 1) % len(SORTIE_COLOURS)}</styleUrl>"
            # footprints are many and say nothing beyond their photo's number: no description
            desc = "" if kind == "footprint" else f"<description>{_description(p)}</description>"
            out.append(f"<Placemark><name>{escape(_name(p))}</name>{desc}{style}{_geometry(f['geometry'])}</Placemark>")
        out.append("</Folder>")
    out.append("</Document></kml>\n")
    return "\n".join(out)
