"""How old each robot-derived value is, and whether it may still look live.

The desk shows values the robot sent: telemetry, its mode, the patrol state, the
control lease, its pose, the round-trip time. Once the link is lost, or while a
periodic source has gone quiet, the last value shown is only *last known*; the
operator must see that, with its age ("last known 15:17:21, 40 s ago"), and it
must not look like an alarm (ISA-101: stale data greyed, outlined or hatched;
colour is kept for abnormal process states).

:class:`FreshnessTracker` keeps, per source (a name such as ``"telemetry"``),
the last value, when it arrived on the monotonic clock (for ages) and in UTC
(for the operator), and the interval between arrivals. A source is

* ``LIVE`` while the link is up and it came recently enough;
* ``OLD`` while the link is up but a periodic source has been quiet for
  ``old_after_periods`` of its usual interval (and at least ``min_old_s``);
* ``NO_LINK`` while the link is down and it was received before it went down
  (a value that arrives while the link is said to be down is judged by its age);
* ``NONE`` when nothing was ever received.

An aperiodic source (the control lease: it changes only when someone takes or
gives control) is never ``OLD``; it is ``NO_LINK`` when the link is down.
No Qt here: the views ask and draw.
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from datetime import datetime
from typing import Any

__all__ = ["Age", "Freshness", "FreshnessTracker", "Reading", "age_text", "last_known_text"]


class Age(enum.Enum):
    NONE = "none"
    LIVE = "live"
    OLD = "old"
    NO_LINK = "no link"


@dataclass(frozen=True)
class Reading:
    value: Any
    received_mono_s: float  # monotonic clock: ages
    received_utc_s: float  # POSIX seconds (UTC): shown to the operator


def age_text(age_s: float) -> str:
    """"40 s ago", "3 min ago", "2 h 5 min ago" (whole units, rounded down)."""
    s = max(0, int(age_s))
    if s < 60:
        return f"{s} s ago"
    if s < 3600:
        return f"{s // 60} min ago"
    return f"{s // 3600} h {s % 3600 // 60} min ago"


def last_known_text(received_utc_s: float, age_s: float) -> str:
    """"last known 15:17:21, 40 s ago" (the desk's local clock time)."""
    hms = datetime.fromtimestamp(received_utc_s).strftime("%H:%M:%S")
    return f"last known {hms}, {age_text(age_s)}"


@dataclass(frozen=True)
class Freshness:
    age: Age
    age_s: float | None = None
    received_utc_s: float | None = None

    @property
    def stale(self) -> bool:
        """A value is shown but no longer current (old, or the link is down)."""
        return self.age in (Age.OLD, Age.NO_LINK)

    def text(self) -> str:
        """"" while live or never received, else "last known HH:MM:SS, N s ago"."""
        if not self.stale or self.received_utc_s is None or self.age_s is None:
            return ""
        return last_known_text(self.received_utc_s, self.age_s)


# the widest texts a pose field shows (live; stale with its age), to size it
POSE_WIDEST = ("x -888.88 m  y -888.88 m  θ -180°", "pose -888.8, -888.8 · 59 min ago")


def pose_status_text(pose: tuple[float, float, float] | None,
                     f: Freshness) -> tuple[str, str]:
    """(shown, full) for a status-bar pose: live "x 1.50 m  y -2.00 m  θ 90°"; once
    stale the short "pose 1.5, -2.0 · 7 s ago" (it must fit a narrow field) and the
    full text with "last known ..." for a tooltip; ("pose —", "") before any pose."""
    if pose is None:
        return "pose —", ""
    x, y, th = pose
    full = f"x {x:.2f} m  y {y:.2f} m  θ {math.degrees(th):.0f}°"
    if f.stale and f.age_s is not None:
        return f"pose {x:.1f}, {y:.1f} · {age_text(f.age_s)}", f"{full}, {f.text()}"
    return full, full


class _Source:
    __slots__ = ("reading", "interval_s", "periodic", "period_s")

    def __init__(self, periodic: bool, period_s: float | None) -> None:
        self.reading: Reading | None = None
        self.interval_s: float | None = period_s  # learnt from arrivals unless given
        self.periodic = periodic
        self.period_s = period_s


class FreshnessTracker:
    """Last value, arrival times and freshness of each named source.

    ``old_after_periods``: a periodic source is OLD after this many of its usual
    intervals without an update (the interval is given, or learnt as a moving
    average of the arrivals, so a 10 Hz stream is old after 0.3 s of silence
    and a 1 Hz one after 3 s), but never before ``min_old_s`` (jitter of a
    loaded machine is not staleness)."""

    SMOOTHING = 0.2  # weight of a new interval in the moving average

    def __init__(self, *, old_after_periods: float = 3.0, min_old_s: float = 2.0,
                 mono: Callable[[], float] = time.monotonic,
                 utc: Callable[[], float] = time.time) -> None:
        if old_after_periods <= 0 or min_old_s < 0:
            raise ValueError("old_after_periods must be positive and min_old_s not negative")
        self.old_after_periods = old_after_periods
        self.min_old_s = min_old_s
        self._mono = mono
        self._utc = utc
        self._sources: dict[str, _Source] = {}
        self.link_up = False
        self._down_since: float | None = None  # monotonic time the link went down

    # ------------------------------------------------------------ inputs
    def expect(self, name: str, *, periodic: bool = True, period_s: float | None = None) -> None:
        """Declare a source (optional: an unknown name is periodic, its interval learnt)."""
        if period_s is not None and not (period_s > 0 and math.isfinite(period_s)):
            raise ValueError(f"period of {name!r} must be a positive number of seconds")
        old = self._sources.get(name)
        src = _Source(periodic, period_s)
        if old is not None:
            src.reading = old.reading
        self._sources[name] = src

    def note(self, name: str, value: Any = None, *, mono_s: float | None = None,
             utc_s: float | None = None) -> None:
        """``name`` arrived now (or at ``mono_s`` / ``utc_s``) with ``value``."""
        src = self._sources.get(name)
        if src is None:
            src = self._sources[name] = _Source(True, None)
        t = self._mono() if mono_s is None else float(mono_s)
        u = self._utc() if utc_s is None else float(utc_s)
        prev = src.reading
        if prev is not None and src.period_s is None:
            dt = t - prev.received_mono_s
            if dt > 0:
                src.interval_s = dt if src.interval_s is None else (
                    (1 - self.SMOOTHING) * src.interval_s + self.SMOOTHING * dt)
        src.reading = Reading(value, t, u)

    def set_link_up(self, up: bool, mono_s: float | None = None) -> None:
        up = bool(up)
        if self.link_up and not up:
            self._down_since = self._mono() if mono_s is None else float(mono_s)
        elif up:
            self._down_since = None
        self.link_up = up

    # ------------------------------------------------------------ queries
    def reading(self, name: str) -> Reading | None:
        src = self._sources.get(name)
        return None if src is None else src.reading

    def value(self, name: str, default: Any = None) -> Any:
        r = self.reading(name)
        return default if r is None else r.value

    def names(self) -> list[str]:
        return list(self._sources)

    def old_after_s(self, name: str) -> float | None:
        """Silence after which ``name`` is OLD with the link up (None: never)."""
        src = self._sources.get(name)
        if src is None or not src.periodic:
            return None
        if src.interval_s is None:
            return None  # one arrival so far: no interval to judge by
        return max(self.min_old_s, self.old_after_periods * src.interval_s)

    def freshness(self, name: str, now_mono_s: float | None = None) -> Freshness:
        src = self._sources.get(name)
        if src is None or src.reading is None:
            return Freshness(Age.NONE)
        now = self._mono() if now_mono_s is None else now_mono_s
        r = src.reading
        age_s = max(0.0, now - r.received_mono_s)
        if (not self.link_up and self._down_since is not None
                and r.received_mono_s <= self._down_since):
            return Freshness(Age.NO_LINK, age_s, r.received_utc_s)
        limit = self.old_after_s(name)
        if limit is not None and age_s > limit:
            return Freshness(Age.OLD, age_s, r.received_utc_s)
        return Freshness(Age.LIVE, age_s, r.received_utc_s)

    def snapshot(self, names: Iterable[str] | None = None,
                 now_mono_s: float | None = None) -> dict[str, Freshness]:
        """The freshness of every source (or of ``names``) at one instant."""
        now = self._mono() if now_mono_s is None else now_mono_s
        return {n: self.freshness(n, now) for n in (self.names() if names is None else names)}
