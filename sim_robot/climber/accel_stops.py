"""The crawler's accelerometer calibration at the start: four standstills a
quarter turn apart, turning in place between them, then back to the start
heading; the bias from the readings' circle
(:mod:`app.core.localisation.accel_calibration`).

The turns are measured by the estimate (the gyro), not by the simulator; a
turn that slips ends a little short or long, which the circle fit does not
mind."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from app.core.localisation.accel_calibration import AccelCalibration, fit_accel_bias

from .turns import turn_to

STOP_S = 20.0  # seconds of samples at each stop
SETTLE_S = 1.0  # seconds left out after each turn (the body settling)


def calibrate_accelerometer(move: Callable[[float, float], None],
                            force: Callable[[], list[float]], ekf,
                            dt_s: float, stops: int = 4) -> AccelCalibration | None:
    """Stand, sample, turn on by a quarter; ``stops`` times, the last turn
    back to the heading of the start (each turn to its heading from the
    start's, so that the turns' small misses do not add up). ``move(v, w)``
    runs one control step; ``force()`` is the accelerometer's last (f_x, f_y);
    ``ekf.pose`` the estimate."""
    samples: list[np.ndarray] = []
    start = ekf.pose[2]
    for k in range(stops):
        for _ in range(int(SETTLE_S / dt_s)):
            move(0.0, 0.0)
        got = []
        for _ in range(int(STOP_S / dt_s)):
            move(0.0, 0.0)
            got.append(tuple(force()))
        samples.append(np.array(got))
        if not turn_to(move, lambda: ekf.pose[2], dt_s, start + (k + 1) * 2 * math.pi / stops):
            break
    return fit_accel_bias(samples)
