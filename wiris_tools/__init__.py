"""Everything that touches a MAVLink link (emulators, camera client, mission transfer) and the CLI."""
