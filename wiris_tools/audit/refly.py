"""The refly capture plan: the original plan's vehicle, home and payloads, and one survey per gap of each
audited step with that step's payloads, altitude, overlaps and trigger, over the gap grown by a margin (a
footprint edge that just touches the gap leaves no sliver after the refly).

    text = refly_yaml(plan_path, audit)      # None: nothing to refly
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from missions.errors import PlanError
from wiris_tools.audit.measure import MIN_GAP_M2, Audit

# Each gap grows by this much (m) before it becomes a refly area.
REFLY_MARGIN_M = 3.0


def _grown(rings: list, margin_m: float) -> list[list[tuple[float, float]]]:
    """The union of the gaps (lat/lon rings) grown by `margin_m`, as outer rings (lat, lon)."""
    import shapely
    from shapely.geometry import Polygon

    from missions.geometry.geo import LocalProjection, leaf_parts
    lat0 = sum(p[0] for r in rings for p in r[0]) / sum(len(r[0]) for r in rings)
    lon0 = sum(p[1] for r in rings for p in r[0]) / sum(len(r[0]) for r in rings)
    proj = LocalProjection(lat0, lon0)
    polys = []
    for r in rings:
        xy = [list(zip(*[a.tolist() for a in proj.to_xy([p[0] for p in ring], [p[1] for p in ring])]))
              for ring in r]
        polys.append(Polygon(xy[0], xy[1:]).buffer(0))
    grown = shapely.union_all(polys).buffer(margin_m, join_style="mitre").simplify(0.5)
    out = []
    for part in leaf_parts(grown, "Polygon"):
        if part.area < MIN_GAP_M2:
            continue
        xs, ys = (list(v) for v in zip(*part.exterior.coords[:-1]))
        la, lo = proj.to_latlon(xs, ys)
        out.append([(round(float(a), 7), round(float(o), 7)) for a, o in zip(la, lo)])
    return out


def _absolute(value: Any, base: Path) -> Any:
    """Paths of files the plan names (exclude zones, the terrain block's DEMs) made absolute: the refly plan is
    written elsewhere."""
    if isinstance(value, str) and not Path(value).is_absolute() and (base / value).exists():
        return str((base / value).resolve())
    if isinstance(value, list):
        return [_absolute(v, base) for v in value]
    if isinstance(value, dict):
        return {k: _absolute(v, base) for k, v in value.items()}
    return value


def refly_plan(plan_path: str | Path, audit: Audit) -> dict | None:
    """The refly plan as a mapping (None: no gap to refly)."""
    path = Path(plan_path)
    try:
        plan = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as err:
        raise PlanError(f"cannot read the plan for the refly: {err}", where=str(path),
                        hint="give the capture plan (YAML) the flight was compiled from") from None
    mission = plan.get("mission") or []
    steps: list[dict] = []
    for step_no in sorted({s.step for s in audit.steps if s.gaps}):
        rings = [g.rings for s in audit.steps if s.step == step_no for g in s.gaps]
        original = mission[step_no]
        kind = next(iter(original))
        body = dict(original[kind])
        survey = {k: _absolute(v, path.parent) for k, v in body.items()
                  if k in ("payloads", "altitude_m", "gsd_cm", "overlap", "trigger", "exclude", "no_photo",
                           "speed_mps", "turnaround_m", "landscape")}
        if "altitude_m" not in survey and "gsd_cm" not in survey:
            survey["altitude_m"] = next(s.altitude_m for s in audit.steps if s.step == step_no)
        for ring in _grown(rings, REFLY_MARGIN_M):
            steps.append({"survey": {"area": [list(p) for p in ring], **survey}})
    if not steps:
        return None
    first_alt = next(iter(steps))["survey"].get("altitude_m", 40)
    out = {k: _absolute(v, path.parent) if k != "mission" else v for k, v in plan.items()}
    out["name"] = f"{plan.get('name', path.stem)}-refly"
    out["mission"] = [{"takeoff": {"alt_m": first_alt}}, *steps, {"rtl": {}}]
    return out


def refly_yaml(plan_path: str | Path, audit: Audit) -> str | None:
    plan = refly_plan(plan_path, audit)
    if plan is None:
        return None
    head = (f"# Refly of the gaps the audit of {audit.log} found in {plan_path}:\n"
            "# the original payloads, altitude, overlaps and trigger, over each gap grown by "
            f"{REFLY_MARGIN_M:g} m.\n")
    return head + yaml.safe_dump(plan, sort_keys=False, default_flow_style=None)
