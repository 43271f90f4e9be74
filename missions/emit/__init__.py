"""Stage 3, MAVLink: the mission item value (`items`), what each firmware accepts (`firmware`), the emitter that
turns planned geometry and steps into items (`emitter`), the pre-flight camera sequence (`setup`), the ArduPilot
Lua bridge (`lua`) and proposed autopilot parameters (`params`)."""
