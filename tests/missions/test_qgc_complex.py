"""The compiled .plan as QGroundControl's pattern editor loads it: surveys as `survey` ComplexItems (and corridors
as CorridorScan when asked), the other items SimpleItems around them, exclusion zones and the optional inclusion
fence in the geoFence; MAVSDK's importer (a real third-party reader) still yields exactly the compiled items."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

import mission_peers
from mission_plans import small_plan
from missions.compile import compile_plan
from missions.emit.items import FRAME_MISSION, MISSION_TYPE_FENCE, MissionItem, mavlink
from missions.errors import PlanError
from missions.formats.planfile import read_plan, write_plan
from wiris_tools.cli import cli

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

# The keys QGroundControl's load code refuses a pattern without (JsonHelper::validateKeys, `true` = required),
# with the JSON type it checks: SurveyComplexItem::_loadV4V5 (version 5), TransectStyleComplexItem::_load
# (version 2), CameraCalc::load (version 2; the second list for a camera other than "Manual"), CameraSpec::load,
# CorridorScanComplexItem::_loadWorker (version 2).
NUMBER, BOOL, STRING, ARRAY, OBJECT = (int, float), bool, str, list, dict
SURVEY_KEYS = {"type": STRING, "complexItemType": STRING, "entryLocation": NUMBER, "angle": NUMBER,
               "splitConcavePolygons": BOOL, "polygon": ARRAY, "version": NUMBER,
               "TransectStyleComplexItem": OBJECT}
CORRIDOR_KEYS = {"version": NUMBER, "type": STRING, "complexItemType": STRING, "CorridorWidth": NUMBER,
                 "EntryPoint": NUMBER, "polyline": ARRAY, "TransectStyleComplexItem": OBJECT}
TRANSECT_KEYS = {"version": NUMBER, "TurnAroundDistance": NUMBER, "CameraTriggerInTurnAround": BOOL,
                 "HoverAndCapture": BOOL, "Refly90Degrees": BOOL, "CameraCalc": OBJECT,
                 "VisualTransectPoints": ARRAY, "Items": ARRAY, "CameraShots": NUMBER}
CAMERA_CALC_KEYS = {"CameraName": STRING, "AdjustedFootprintSide": NUMBER, "AdjustedFootprintFrontal": NUMBER,
                    "DistanceToSurface": NUMBER, "DistanceMode": NUMBER, "ValueSetIsDistance": BOOL,
                    "ImageDensity": NUMBER, "FrontalOverlap": NUMBER, "SideOverlap": NUMBER,
                    "SensorWidth": NUMBER, "SensorHeight": NUMBER, "ImageWidth": NUMBER, "ImageHeight": NUMBER,
                    "FocalLength": NUMBER, "Landscape": BOOL, "FixedOrientation": BOOL, "MinTriggerInterval": NUMBER}
TRANSECT_COMMANDS = {mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
                     mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL, mavlink.MAV_CMD_DO_TRIGGER_CONTROL,
                     mavlink.MAV_CMD_IMAGE_START_CAPTURE}


def _has_keys(obj: dict, keys: dict) -> list[str]:
    """The keys of `keys` that `obj` lacks or holds with another JSON type (a bool is no number to Qt)."""
    bad = []
    for key, kind in keys.items():
        v = obj.get(key)
        ok = isinstance(v, kind) and not (kind is NUMBER and isinstance(v, bool))
        if not ok:
            bad.append(key)
    return bad


def _plan_doc(compiled, tmp_path: Path) -> dict:
    target = tmp_path / f"{compiled.name}.plan"
    write_plan(target, compiled)
    return json.loads(target.read_text())


def _complex(doc: dict) -> list[dict]:
    return [it for it in doc["mission"]["items"] if it["type"] == "ComplexItem"]


def _same(a: list[MissionItem], b: list[MissionItem]) -> bool:
    return len(a) == len(b) and all(x.same_on_wire(y) for x, y in zip(a, b))


@pytest.fixture(scope="module")
def solar_park():
    return compile_plan(EXAMPLES / "solar-park.yaml")


def test_survey_is_one_complex_item_with_every_key_qgc_requires(solar_park, tmp_path):
    doc = _plan_doc(solar_park, tmp_path)
    [survey] = _complex(doc)
    assert survey["complexItemType"] == "survey" and survey["version"] == 5
    assert _has_keys(survey, SURVEY_KEYS) == []
    transect = survey["TransectStyleComplexItem"]
    assert transect["version"] == 2 and _has_keys(transect, TRANSECT_KEYS) == []
    calc = transect["CameraCalc"]
    assert calc["version"] == 2 and calc["CameraName"] == "Custom Camera" and _has_keys(calc, CAMERA_CALC_KEYS) == []
    # the camera numbers are the payload's optics and the compiled spacing, not QGC's defaults
    pattern = solar_park.patterns[0]
    optics = solar_park.payload("thermal")
    assert calc["FocalLength"] == optics.focal_mm and (calc["ImageWidth"], calc["ImageHeight"]) == optics.resolution_px
    assert calc["AdjustedFootprintSide"] == pytest.approx(pattern.spacing_m)
    assert calc["AdjustedFootprintFrontal"] == pytest.approx(pattern.trigger_distance_m)
    assert calc["DistanceToSurface"] == 40 and calc["DistanceMode"] == 1
    assert (calc["FrontalOverlap"], calc["SideOverlap"]) == (80, 70)
    assert transect["TurnAroundDistance"] == 10 and transect["HoverAndCapture"] is False
    assert len(survey["polygon"]) >= 3 and all(len(p) == 2 for p in survey["polygon"])
    # the photo count QGC shows is the one the report measures
    from missions.measure.report import report
    assert transect["CameraShots"] == report(solar_park).photos["thermal"]


def test_flattened_items_are_exactly_the_compiled_ones_with_simple_items_around(solar_park, tmp_path):
    doc = _plan_doc(solar_park, tmp_path)
    items = doc["mission"]["items"]
    k = next(i for i, it in enumerate(items) if it["type"] == "ComplexItem")
    inner = items[k]["TransectStyleComplexItem"]["Items"]
    # take-off and the speed change before the lines, RTL after: SimpleItems
    assert [it["command"] for it in items[:k]] == [mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_DO_CHANGE_SPEED]
    assert all(it["type"] == "SimpleItem" for it in items[:k] + items[k + 1:])
    assert {it["command"] for it in inner} <= TRANSECT_COMMANDS
    # MissionItem::load's required keys and types for each stored item
    assert all(_has_keys(it, {"type": STRING, "frame": NUMBER, "command": NUMBER, "params": ARRAY,
                              "autoContinue": BOOL}) == [] and it["type"] == "SimpleItem" and len(it["params"]) == 7
               for it in inner)
    assert inner[0]["command"] == mavlink.MAV_CMD_NAV_WAYPOINT
    # doJumpId numbers every flattened item from 1, as QGC does
    flat = items[:k] + inner + items[k + 1:]
    assert [it["doJumpId"] for it in flat] == list(range(1, len(solar_park.items) + 1))
    # what QGC (and our reader) flies from the file is the compiled mission, item for item
    assert _same(read_plan(json.dumps(doc))[0], list(solar_park.items))
    pts = items[k]["TransectStyleComplexItem"]["VisualTransectPoints"]
    assert len(pts) == sum(1 for it in inner if it["command"] == mavlink.MAV_CMD_NAV_WAYPOINT)


def test_non_transect_items_stay_simple_items(tmp_path):
    # small_plan: a survey, then a hover capture waypoint, an in-flight camera change (Lua bridge), RTL
    c = compile_plan(small_plan(tmp_path))
    doc = _plan_doc(c, tmp_path)
    [survey] = _complex(doc)
    inner = survey["TransectStyleComplexItem"]["Items"]
    simple = [it for it in doc["mission"]["items"] if it["type"] == "SimpleItem"]
    assert len(simple) + len(inner) == len(c.items)
    script = {mavlink.MAV_CMD_DO_SEND_SCRIPT_MESSAGE} if hasattr(mavlink, "MAV_CMD_DO_SEND_SCRIPT_MESSAGE") else set()
    assert {it["command"] for it in simple} & ({mavlink.MAV_CMD_DO_CHANGE_SPEED} | script)
    assert not {it["command"] for it in inner} & ({mavlink.MAV_CMD_DO_CHANGE_SPEED} | script)
    assert _same(read_plan(json.dumps(doc))[0], list(c.items))


def test_parts_carry_simple_items_only(tmp_path):
    # a part's items are numbered from its own start: the whole mission's pattern indices do not apply to it
    c = compile_plan(small_plan(tmp_path, limit=20))
    assert len(c.parts) > 1
    target = tmp_path / "p1.plan"
    write_plan(target, c, items=c.parts[0])
    doc = json.loads(target.read_text())
    assert not _complex(doc) and _same(read_plan(target.read_text())[0], list(c.parts[0]))


def _corridor_plan(tmp_path: Path, corridor_scan: bool | None) -> Path:
    text = (EXAMPLES / "powerline-corridor.yaml").read_text()
    if corridor_scan is not None:
        text += f"qgc: {{corridor_scan: {'true' if corridor_scan else 'false'}}}\n"
    path = tmp_path / "corridor.yaml"
    path.write_text(text)
    return path


def test_corridors_stay_simple_items_unless_asked(tmp_path):
    c = compile_plan(_corridor_plan(tmp_path, None))
    assert [p.kind for p in c.patterns] == ["corridor"] and not c.corridor_scan
    assert not _complex(_plan_doc(c, tmp_path))


def test_corridor_scan_has_every_key_qgc_requires(tmp_path):
    c = compile_plan(_corridor_plan(tmp_path, True))
    doc = _plan_doc(c, tmp_path)
    [corridor] = _complex(doc)
    assert corridor["complexItemType"] == "CorridorScan" and corridor["version"] == 2
    assert _has_keys(corridor, CORRIDOR_KEYS) == []
    assert _has_keys(corridor["TransectStyleComplexItem"], TRANSECT_KEYS) == []
    assert corridor["CorridorWidth"] == 50 and len(corridor["polyline"]) == 4
    assert corridor["polyline"][0] == [-35.261, 149.04]
    assert _same(read_plan(json.dumps(doc))[0], list(c.items))


def _zone_plan(tmp_path: Path, extra: str = "") -> Path:
    """A small survey with an exclusion zone inside its area."""
    path = small_plan(tmp_path, camera_change=False)
    text = path.read_text().replace(
        "      altitude_m: 40\n",
        "      altitude_m: 40\n      exclude: [[[50.1114, 14.5048], [50.1114, 14.5052], [50.1116, 14.5052], "
        "[50.1116, 14.5048]]]\n", 1)
    path.write_text(text + extra)
    return path


def test_exclusion_zone_is_an_exclusion_polygon_of_the_geofence(tmp_path):
    c = compile_plan(_zone_plan(tmp_path))
    assert all(f.mission_type == MISSION_TYPE_FENCE for f in c.fence)
    assert {f.command for f in c.fence} == {mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION}
    doc = _plan_doc(c, tmp_path)
    [poly] = doc["geoFence"]["polygons"]
    assert poly["inclusion"] is False
    assert sorted(map(tuple, poly["polygon"])) == sorted([(50.1114, 14.5048), (50.1114, 14.5052), (50.1116, 14.5052),
                                                         (50.1116, 14.5048)])
    assert _same(read_plan(json.dumps(doc))[1], list(c.fence))


def test_inclusion_fence_lies_margin_m_around_the_whole_flight(tmp_path):
    from shapely.geometry import Point, Polygon

    from missions.geometry.geo import LocalProjection

    c = compile_plan(_zone_plan(tmp_path, "fence: {margin_m: 30}\n"))
    inclusion = [f for f in c.fence if f.command == mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION]
    assert len(inclusion) >= 3 and all(f.param1 == len(inclusion) for f in inclusion)
    proj = LocalProjection(c.home[0], c.home[1])
    fence = Polygon([proj.point_to_xy(f.lat, f.lon) for f in inclusion])
    places = [(0.0, 0.0)] + [proj.point_to_xy(it.lat, it.lon) for it in c.items
                             if it.frame != FRAME_MISSION and (it.x or it.y)]
    # every place flown to is inside, at least the margin from the fence (less the 1e-7° rounding of the vertices)
    assert min(fence.exterior.distance(Point(p)) for p in places) >= 30 - 0.05
    assert all(fence.contains(Point(p)) for p in places)
    assert max(fence.exterior.distance(Point(p)) for p in places) < 400      # and not absurdly far out
    doc = _plan_doc(c, tmp_path)
    assert [p["inclusion"] for p in doc["geoFence"]["polygons"]] == [False, True]


@pytest.mark.parametrize("fence,fragment", [
    ("fence: {margin_m: -3}", "margin_m"),
    ("fence: {margin_m: thirty}", "margin_m"),
    ("fence: {margin: 30}", "margin"),
    ("qgc: {corridor_scan: yes please}", "corridor_scan"),
])
def test_bad_fence_or_qgc_key_is_a_located_error_and_writes_nothing(tmp_path, fence, fragment):
    path = small_plan(tmp_path)
    path.write_text(path.read_text() + fence + "\n")
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["mission", "compile", str(path), "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert f"{path.name}:" in r.output and fragment in r.output and "Traceback" not in r.output
    assert not out.exists()
    with pytest.raises(PlanError):
        compile_plan(path)


# -- MAVSDK's import_qgroundcontrol_mission reads exactly the compiled items ----------------------------------

def _mavsdk_mission(res: dict, compiled) -> list[MissionItem]:
    got = res["mission"]
    # MAVSDK puts plannedHomePosition in as item 0 for ArduPilot (when it knows the vehicle is one, see
    # test_examples.py: in 4.1.0 that knowledge can arrive after the import)
    if compiled.firmware == "ardupilot" and len(got) == len(compiled.items) + 1:
        got = got[1:]
    return got


def _close(a: MissionItem, b: MissionItem) -> bool:
    def eq(x: float, y: float) -> bool:
        return (math.isnan(x) and math.isnan(y)) or x == pytest.approx(y, rel=1e-6, abs=1e-6)

    return (a.command, a.frame, a.x, a.y, a.autocontinue) == (b.command, b.frame, b.x, b.y, b.autocontinue) and all(
        eq(x, y) for x, y in zip((a.param1, a.param2, a.param3, a.param4, a.z), (b.param1, b.param2, b.param3,
                                                                               b.param4, b.z)))


@pytest.mark.peer
@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
@pytest.mark.parametrize("plan", ["solar-park", "field-multispectral", "small-hover"])
def test_mavsdk_imports_the_complex_item_plan_exactly(tmp_path, firmware, plan):
    if plan == "small-hover":
        path = small_plan(tmp_path, firmware=firmware, camera_change=False)
        path.write_text(path.read_text().replace("      altitude_m: 40\n", "      altitude_m: 40\n"
                                                 "      trigger: hover\n", 1))
    else:
        path = EXAMPLES / f"{plan}.yaml"
    c = compile_plan(path, firmware=firmware)
    doc = _plan_doc(c, tmp_path)
    assert _complex(doc), "no ComplexItem written"
    res = mission_peers.mavsdk_import_plan(json.dumps(doc), tmp_path, autopilot=firmware)
    assert res["ok"], res.get("error")
    got = _mavsdk_mission(res, c)
    assert len(got) == len(c.items)
    bad = [(i, g, w) for i, (g, w) in enumerate(zip(got, c.items)) if not _close(g, w)]
    assert not bad, bad[:3]
    assert len(res["fence"]) == len(c.fence)


@pytest.mark.peer
def test_mavsdk_refuses_a_plan_with_a_corridor_scan(tmp_path):
    """Why corridors are SimpleItems unless `qgc: {corridor_scan: true}`: MAVSDK 4.1.0's importer knows the
    "survey" ComplexItem only and fails the whole file on any other (FAILED_TO_PARSE_QGC_PLAN)."""
    c = compile_plan(_corridor_plan(tmp_path, True))
    res = mission_peers.mavsdk_import_plan(json.dumps(_plan_doc(c, tmp_path)), tmp_path, autopilot="px4")
    assert not res["ok"] and "PARSE" in res["error"]
    c = compile_plan(_corridor_plan(tmp_path, False))
    res = mission_peers.mavsdk_import_plan(json.dumps(_plan_doc(c, tmp_path)), tmp_path, autopilot="px4")
    assert res["ok"] and len(res["mission"]) == len(c.items)


def test_lines_only_a_rededge_flies_store_no_trigger_distance(tmp_path):
    # the RedEdge captures itself: its lines carry no camera command, and neither would lines QGC rebuilds
    text = (EXAMPLES / "field-multispectral.yaml").read_text().replace(
        "      payloads: [thermal, multispectral]", "      payloads: [multispectral]")
    plan = tmp_path / "rededge-only.yaml"
    plan.write_text(text)
    (tmp_path / "areas").symlink_to(EXAMPLES / "areas")        # the plan's area file, as beside the example
    c = compile_plan(plan)
    [survey] = _complex(_plan_doc(c, tmp_path))
    transect = survey["TransectStyleComplexItem"]
    assert {it["command"] for it in transect["Items"]} == {mavlink.MAV_CMD_NAV_WAYPOINT}
    assert transect["CameraCalc"]["AdjustedFootprintFrontal"] == 0 and transect["CameraShots"] == 0
    # with the WIRIS beside it the autopilot triggers, and the trigger distance is stored
    [both] = _complex(_plan_doc(compile_plan(EXAMPLES / "field-multispectral.yaml"), tmp_path))
    assert both["TransectStyleComplexItem"]["CameraCalc"]["AdjustedFootprintFrontal"] > 0
