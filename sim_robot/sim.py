"""The simulation clock: sim time runs ``time_scale`` times faster than wall time."""

from __future__ import annotations

import time


class SimClock:
    def __init__(self, time_scale: float = 1.0) -> None:
        if time_scale <= 0:
            raise ValueError("time scale must be positive")
        self.time_scale = time_scale
        self._t0 = time.monotonic()

    def now(self) -> float:
        """Sim seconds since start."""
        return (time.monotonic() - self._t0) * self.time_scale

    def wall_until(self, t_sim: float) -> float:
        """Wall seconds until sim time ``t_sim`` (negative when past)."""
        return (t_sim - self.now()) / self.time_scale
