"""The stages `missions.compile.compile_plan` drives, one module each: `context` (the values they pass),
`payloads`, `speed`, `steps` (one function per step type), `lines` (surveys and corridors), `zones`, `facts`
(what the report reads of a step), `preflight` (setup sequence, Lua bridge, params), `fence`,
`mission_warnings`, `terrain`."""
