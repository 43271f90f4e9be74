"""The float32 limit: MAVLink carries PARAM_EXT float values and mission params 1-4 and z as IEEE float32."""

FLOAT32_MAX = 3.4028234663852886e38   # the largest finite float32, (2 - 2**-23) * 2**127
