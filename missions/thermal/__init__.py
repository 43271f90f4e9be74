"""Thermal-aware planning: sharp images (the blur budget), the sun over the flight, and the PV inspection profile.

`blur` limits survey speed by the imager's time constant; `sun` gives the sun's position, the day and a clear-sky
irradiance estimate; `pv` holds the PV inspection profile's numbers (one table, overridable) and its checks;
`speed` chooses `vehicle.speed_mps: auto`. Pure: no sockets, no files.
"""
