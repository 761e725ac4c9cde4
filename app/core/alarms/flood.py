"""Alarm flood guard (no Qt).

ISA-18.2 (clause 16.5, and EEMUA 191's operator-load figures it builds on)
calls it an *alarm flood* when alarms arrive faster than an operator can act
on them — commonly more than 10 in 10 minutes per operator; this desk uses a
configurable count per minute. During a flood the desk says so once (the
``alarm.flood`` notice) and groups the list by source instead of adding a line
per alarm; every transition is still recorded.
"""

from __future__ import annotations

from collections import deque

__all__ = ["FloodGuard"]


class FloodGuard:
    """Counts annunciations in a sliding window.

    The flood starts when more than ``max_per_minute`` alarms were raised in the
    last ``window_s`` seconds, and ends when the count falls to half of that or
    less (hysteresis, so the notice itself does not chatter)."""

    def __init__(self, max_per_minute: int = 10, window_s: float = 60.0) -> None:
        if int(max_per_minute) < 1:
            raise ValueError("max_per_minute must be >= 1")
        if window_s <= 0:
            raise ValueError("window_s must be > 0")
        self.max_per_minute = int(max_per_minute)
        self.window_s = float(window_s)
        self.active = False
        self.floods = 0  # how many floods so far
        self._times: deque[float] = deque()

    def _trim(self, t: float) -> None:
        while self._times and t - self._times[0] > self.window_s:
            self._times.popleft()

    def count(self, t: float) -> int:
        """Annunciations in the window ending at ``t``."""
        self._trim(t)
        return len(self._times)

    def note(self, t: float) -> bool:
        """One alarm raised at ``t``; True when this starts a flood."""
        self._times.append(t)
        self._trim(t)
        if not self.active and len(self._times) > self.max_per_minute:
            self.active = True
            self.floods += 1
            return True
        return False

    def check(self, t: float) -> bool:
        """True when the flood ends at ``t``."""
        self._trim(t)
        if self.active and len(self._times) <= self.max_per_minute // 2:
            self.active = False
            return True
        return False
