"""Turning the crawler in place, to a heading of its estimate.

With the wheels turning opposite ways and the body not moving forward, the
wheels' along-track slip (which the filter knows only as learnt coefficients,
seed 003) cannot move the body: only the turn's own slip acts, and the gyro
sees it. Used at a lane's end (:mod:`.inspection`) and between the
accelerometer's standstills (:mod:`.accel_stops`)."""

from __future__ import annotations

import math
from collections.abc import Callable

TURN_RPS = 0.3  # the turns' yaw rate
TURN_TOL_RAD = math.radians(0.5)  # a turn ends this close to its heading
TURN_TIMEOUT_S = 60.0  # a turn that takes longer than this is given up


def turn_to(move: Callable[[float, float], None], heading_now: Callable[[], float],
            dt_s: float, heading: float) -> bool:
    """Turn in place the short way to ``heading`` (rad, as ``heading_now()``
    reports it); ``move(v, w)`` runs one control step. Whether it got there."""
    for _ in range(int(TURN_TIMEOUT_S / dt_s)):
        left = (heading - heading_now() + math.pi) % (2 * math.pi) - math.pi
        if abs(left) < TURN_TOL_RAD:
            return True
        move(0.0, math.copysign(min(TURN_RPS, 2.0 * abs(left)), left))
    return False
