"""A plan split into two sorties by its battery: sitl_plans' survey with an endurance that does not hold it."""

from __future__ import annotations

import sitl_plans

ENDURANCE_MIN = 5.0       # the 4.7 min survey does not fit one battery with a 20 % reserve: two sorties


def write_sortie_plan(directory):
    path = sitl_plans.write_plan(directory, "survey")
    path.write_text(path.read_text().replace("speed_mps: 5", f"speed_mps: 5, endurance_min: {ENDURANCE_MIN}"))
    return path
