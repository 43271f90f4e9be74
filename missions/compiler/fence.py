"""The mission's fence: an exclusion polygon for each zone the vehicle must not enter, and the plan's inclusion
fence around everything it flies (missions.geometry.fence).
"""

from __future__ import annotations

import numpy as np

from missions.emit.items import MissionItem
from missions.geometry.geo import LocalProjection
from missions.compiler.context import Compilation


def mission_fence(c: Compilation, items: tuple[MissionItem, ...]) -> tuple[MissionItem, ...]:
    """The fence: each zone the vehicle must not enter as an exclusion polygon, and with the plan's
    `fence: {margin_m: M}` an inclusion polygon M metres around everything the mission flies. (A path through a
    zone is the report's path_over_exclusion warning: with the fence enabled the vehicle breaches it there.)"""
    from missions.geometry.fence import exclusion_polygon, inclusion_polygon

    out: list[MissionItem] = []
    seen: set[tuple] = set()
    for ring in _fence_rings(c):
        if ring not in seen:
            seen.add(ring)
            out.extend(exclusion_polygon(ring))
    home = c.plan.home
    if c.plan.fence_margin_m is not None:
        out.extend(inclusion_polygon(items, (home.lat, home.lon), c.plan.fence_margin_m))
    return tuple(out)


def _fence_rings(c: Compilation) -> list[tuple[tuple[float, float], ...]]:
    """The outline (lat, lon) of every zone the vehicle must not enter (no_fly and exclude; a no_photo zone may
    be flown over), cleaned as the compiler keeps out of it."""
    import numpy as np

    proj = LocalProjection(c.plan.home.lat, c.plan.home.lon)
    rings = []
    for zone in c.zones:
        if not zone.keeps_path_out:
            continue
        g = zone.xy(proj)
        for poly in getattr(g, "geoms", [g]):
            xy = np.asarray(poly.exterior.coords)[:-1]
            lat, lon = proj.to_latlon(xy[:, 0], xy[:, 1])
            rings.append(tuple((round(float(a), 7), round(float(b), 7)) for a, b in zip(lat, lon)))
    return rings
