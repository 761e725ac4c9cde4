"""The replay clock and cursor (no Qt): where in a recording a replay stands.

A :class:`ReplayClock` maps wall time onto recorded time. It does not read a
clock itself: the caller passes the wall seconds that went by
(``advance(dt_s)``), so a test drives it step by step and a GUI timer drives it
with a monotonic clock. Speed is limited to 0.5–10×; paused, ``advance`` does
not move; ``seek`` jumps anywhere in ``[t0, t1]``.

:class:`ReplayCursor` turns successive clock positions into half-open windows
``(previous, now]`` so each recorded row is handed out exactly once while the
replay plays forward; after a seek the next window starts at the seek target
(the caller redraws the state at that moment itself).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["MIN_SPEED", "MAX_SPEED", "SPEEDS", "ReplayClock", "ReplayCursor", "Window"]

MIN_SPEED = 0.5
MAX_SPEED = 10.0
SPEEDS = (0.5, 1.0, 2.0, 5.0, 10.0)


class ReplayClock:
    """Recorded time ``position`` in ``[t0, t1]`` (UTC epoch seconds)."""

    def __init__(self, t0: float, t1: float, *, speed: float = 1.0) -> None:
        t0, t1 = float(t0), float(t1)
        if not (math.isfinite(t0) and math.isfinite(t1)):
            raise ValueError("a replay range needs finite times")
        if t1 < t0:
            raise ValueError(f"the replay range ends ({t1}) before it starts ({t0})")
        self.t0, self.t1 = t0, t1
        self.position = t0
        self.paused = True
        self.speed = 1.0
        self.set_speed(speed)

    @property
    def finished(self) -> bool:
        return self.position >= self.t1

    @property
    def fraction(self) -> float:
        span = self.t1 - self.t0
        return 1.0 if span <= 0 else (self.position - self.t0) / span

    def set_speed(self, speed: float) -> float:
        """Set the speed, clamped to 0.5–10×; returns the speed in effect."""
        speed = float(speed)
        if not math.isfinite(speed):
            raise ValueError(f"speed {speed} is not a number")
        self.speed = min(MAX_SPEED, max(MIN_SPEED, speed))
        return self.speed

    def play(self) -> None:
        if self.finished:
            self.position = self.t0
        self.paused = False

    def pause(self) -> None:
        self.paused = True

    def toggle(self) -> bool:
        """Play if paused, pause if playing; returns True when now playing."""
        if self.paused:
            self.play()
        else:
            self.pause()
        return not self.paused

    def seek(self, t: float) -> float:
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"cannot seek to {t}")
        self.position = min(self.t1, max(self.t0, t))
        return self.position

    def seek_fraction(self, f: float) -> float:
        return self.seek(self.t0 + min(1.0, max(0.0, float(f))) * (self.t1 - self.t0))

    def advance(self, wall_dt_s: float) -> float:
        """Let ``wall_dt_s`` seconds of wall time pass; returns the new position.

        Stops (and pauses) at the end of the range."""
        if self.paused or wall_dt_s <= 0:
            return self.position
        self.position = min(self.t1, self.position + float(wall_dt_s) * self.speed)
        if self.finished:
            self.paused = True
        return self.position


@dataclass(frozen=True)
class Window:
    """Rows with ``start < t <= end`` are due (``start`` included when
    ``inclusive``: the first window of a replay and the first after a seek)."""

    start: float
    end: float
    inclusive: bool

    def contains(self, t: float) -> bool:
        return (self.start <= t if self.inclusive else self.start < t) and t <= self.end


class ReplayCursor:
    """Hands out each stretch of recorded time once as the clock moves."""

    def __init__(self, clock: ReplayClock) -> None:
        self.clock = clock
        self._last = clock.position
        self._fresh = True  # the next window includes its start

    def seek(self, t: float, *, inclusive: bool = True) -> float:
        """Jump to ``t``; the next window includes ``t`` itself unless
        ``inclusive`` is False (the caller has shown the state at ``t``)."""
        pos = self.clock.seek(t)
        self._last = pos
        self._fresh = inclusive
        return pos

    def advance(self, wall_dt_s: float) -> Window | None:
        """Advance the clock; the window of recorded time that became due, or
        None when the clock did not move."""
        before = self._last
        now = self.clock.advance(wall_dt_s)
        if now <= before and not (self._fresh and now == before and not self.clock.paused):
            return None
        w = Window(before, now, self._fresh)
        self._last = now
        self._fresh = False
        return w
