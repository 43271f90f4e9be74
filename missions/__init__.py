"""Capture plan -> mission compiler. Pure: no sockets, no MAVLink links.

The folders are the pipeline, in the order a plan goes through them (`compile.compile_plan` drives it):

    plan/       the capture plan: schema, positioned YAML reader, meaning checks  -> Plan
    geometry/   areas in a local projection, swaths, routes, triggers, footprints -> a flown route with photo points
    emit/       MAVLink mission items per firmware profile and camera, setup sequence, Lua bridge, parameters
    formats/    files: QGroundControl .plan, WPL 110, GeoJSON, KML, preview pictures, atomic outputs
    measure/    the re-flight of the emitted items and the report measured from it
    compiler/   the stages `compile.compile_plan` runs them in: payloads, speed, steps, lines, zones, preflight, fence

`compiled.py` holds the compiler's result types, `errors.py` the one error family (`PlanError`).
"""
