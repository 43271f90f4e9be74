"""Camera emulators that behave as the vendors' manuals describe, driven by the camera catalogue.

    wiris.WirisState     a Workswell WIRIS camera component (Workswell MAVLink Interface manual rev 231108EN)
    rededge.RedEdgeState a MicaSense RedEdge on its serial API (MAVLink 1, classic PARAM_*, messages 154/155)
    runner.run_emulator  the thin I/O shell: a Link, a tick thread, and the definition's HTTP server

The states are pure: `handle(msg, now)` and `tick(now)` return the messages to send, so tests and the
fuzzer drive them without sockets. What they share with the camera client lives beside it in wiris_tools:
`paramext` (the PARAM_EXT value codec) and `camera_definition` (the parameter list of a definition file).
"""
