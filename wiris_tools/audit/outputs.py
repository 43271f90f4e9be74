"""What `wiris mission audit -o DIR` writes: NAME.audit.json, NAME.gaps.geojson, NAME.audit.png (the plan's
areas, the captured footprints and the gaps drawn) and, when there are gaps, NAME-refly.yaml with its
compiled mission in DIR/NAME-refly/. Each file is written atomically; the refly plan is compiled before
anything is written, so a refly that cannot be built leaves nothing half-written."""

from __future__ import annotations

import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from missions.compiled import Compiled
from wiris_tools.audit.measure import Audit, gap_geojson

PNG_SIZE_PX = 1000


def _atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def audit_png(compiled: Compiled, audit: Audit) -> bytes:
    """The areas (outline), the captured footprints (blue) and the gaps (red), north up, to scale."""
    import shapely
    from PIL import Image, ImageDraw

    from missions.geometry.geo import leaf_parts
    from missions.measure.flight import simulate
    from missions.measure.report import area_geometry

    proj = simulate(compiled).projection
    areas = [area_geometry(a.area, proj) for a in compiled.areas]
    covered = [s.footprints.polygons for s in audit.steps if s.footprints is not None]
    gaps = []
    for s in audit.steps:
        for g in s.gaps:
            x, y = proj.to_xy([p[0] for p in g.rings[0]], [p[1] for p in g.rings[0]])
            gaps.append(shapely.Polygon(list(zip(x.tolist(), y.tolist()))))
    everything = shapely.union_all([*areas, *covered, *gaps]) if areas else shapely.Polygon()
    img = Image.new("RGB", (PNG_SIZE_PX, PNG_SIZE_PX), "white")
    if everything.is_empty:
        return _png(img)
    x0, y0, x1, y1 = everything.bounds
    scale = (PNG_SIZE_PX - 40) / max(x1 - x0, y1 - y0, 1.0)
    draw = ImageDraw.Draw(img, "RGBA")

    def px(coords) -> list[tuple[float, float]]:
        return [(20 + (x - x0) * scale, PNG_SIZE_PX - 20 - (y - y0) * scale) for x, y in coords]

    for geom, fill, line in [(shapely.union_all(covered) if covered else None, (40, 90, 220, 90), (40, 90, 220, 255)),
                             (shapely.union_all(gaps) if gaps else None, (230, 30, 30, 170), (180, 0, 0, 255))]:
        if geom is None:
            continue
        for part in leaf_parts(geom, "Polygon"):
            draw.polygon(px(part.exterior.coords), fill=fill, outline=line)
            for hole in part.interiors:
                draw.polygon(px(hole.coords), fill=(255, 255, 255, 255))
    for a in areas:
        for part in leaf_parts(a, "Polygon"):
            draw.line(px(part.exterior.coords), fill=(0, 0, 0, 255), width=2)
            for hole in part.interiors:
                draw.line(px(hole.coords), fill=(120, 0, 120, 255), width=2)
    bar = 10 ** int(f"{(x1 - x0) / 4:e}".split("e")[1])       # a round scale bar about a tenth of the width
    draw.line([(20, PNG_SIZE_PX - 10), (20 + bar * scale, PNG_SIZE_PX - 10)], fill=(0, 0, 0, 255), width=3)
    draw.text((24 + bar * scale, PNG_SIZE_PX - 18), f"{bar:g} m", fill=(0, 0, 0, 255))
    draw.text((20, 4), "black: area  blue: captured footprints  red: gaps", fill=(0, 0, 0, 255))
    return _png(img)


def _png(img: Any) -> bytes:
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue()


def write_audit(out_dir: str | Path, compiled: Compiled, audit: Audit, plan_path: str | None,
                doc: dict | None = None) -> list[Path]:
    """Write the audit's files into `out_dir`; returns their paths. `audit` gives the gaps and the refly (the
    union of several flights'); `doc` is NAME.audit.json when it is more than `audit` (several flights)."""
    from missions.compile import compile_plan
    from missions.formats.outputs import write_outputs
    from wiris_tools.audit.refly import refly_yaml

    out = Path(out_dir)
    name = compiled.name
    refly_text = refly_yaml(plan_path, audit) if plan_path else None
    refly_compiled = None
    if refly_text is not None:
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / f"{name}-refly.yaml"
            p.write_text(refly_text, encoding="utf-8")
            refly_compiled = compile_plan(p)
    files = {out / f"{name}.audit.json": json.dumps(doc or audit.to_json(), indent=1).encode(),
             out / f"{name}.gaps.geojson": json.dumps(gap_geojson(audit), indent=1).encode(),
             out / f"{name}.audit.png": audit_png(compiled, audit)}
    if refly_text is not None:
        files[out / f"{name}-refly.yaml"] = refly_text.encode()
    for path, data in files.items():
        _atomic(path, data)
    written = list(files)
    if refly_compiled is not None:
        written += write_outputs(refly_compiled, out / f"{name}-refly")
    return written
