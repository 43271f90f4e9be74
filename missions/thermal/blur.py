"""The blur budget: a microbolometer integrates the scene over its thermal time constant, so the ground moves
speed × time constant under the camera while it does; the image stays sharp while that is at most `blur_px`
ground pixels (default 1).

    sharp_speed_mps(gsd_cm=5.2, time_constant_ms=10, blur_px=1.0)   # 5.2 m/s
"""

from __future__ import annotations

DEFAULT_BLUR_PX = 1.0


def sharp_speed_mps(gsd_cm: float, time_constant_ms: float, blur_px: float = DEFAULT_BLUR_PX) -> float:
    """The fastest ground speed at which the smear during one time constant stays within `blur_px` pixels."""
    return blur_px * (gsd_cm / 100.0) / (time_constant_ms / 1000.0)


def blur_px(speed_mps: float, gsd_cm: float, time_constant_ms: float) -> float:
    """Pixels the ground moves during one time constant at `speed_mps`."""
    return speed_mps * (time_constant_ms / 1000.0) / (gsd_cm / 100.0)
