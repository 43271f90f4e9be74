"""Capture plan -> mission compiler. Pure: no sockets, no MAVLink links."""
