"""Alarm rules and the small filters that turn samples into alarm conditions (no Qt).

In ISA-18.2 terms each rule is an *alarm setpoint* with its *alarm deadband*
and *on/off delays* (clause 10, "alarm design"; the standard's guidance is to
use deadband and delays so that a noisy process value near its setpoint does
not chatter). The rules here:

* :class:`LimitRule` — high and/or low limits of one channel with deadband and
  on/off delays;
* :class:`RateRule` — rate of rise of a channel (gas) in units per minute,
  the least-squares slope over a sliding window;
* :class:`StaleRule` — a channel silent for longer than ``after_s``;
* :class:`FlagRule` — one bit of the MCU's alarm flag word (robot faults:
  fail-safe stop, e-stop, low battery, ...);
* :class:`ConditionRule` — priority and text of a discrete condition fed by
  :meth:`AlarmMonitor.set_condition` (link lost, archive failing, meter band).

:class:`Debounce`, :class:`LimitTracker` and :class:`RateTracker` are the
filters; each is usable and testable on its own.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from app.core.alarms.model import Priority

__all__ = [
    "ConditionRule", "Debounce", "DEFAULT_LIMITS", "FlagRule", "LimitRule", "LimitTracker",
    "RateRule", "RateTracker", "StaleRule", "slope_per_min",
]


def _check_delays(name: str, on_delay_s: float, off_delay_s: float) -> None:
    for what, v in (("on_delay_s", on_delay_s), ("off_delay_s", off_delay_s)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise ValueError(f"rule for {name!r}: {what} must be a number >= 0, got {v!r}")


@dataclass(frozen=True)
class LimitRule:
    """Limits of one channel. ``deadband`` is in the channel's unit: a high
    alarm clears only at ``high - deadband`` or below (a low one mirrors this).
    ``on_delay_s``: the value must stay beyond the limit this long before the
    alarm is raised; ``off_delay_s``: back inside this long before it clears."""

    channel: str
    high: float | None = None
    low: float | None = None
    deadband: float = 0.0
    unit: str = ""
    label: str = ""
    priority: Priority = Priority.MEDIUM
    on_delay_s: float = 0.0
    off_delay_s: float = 0.0
    source: str = ""  # defaults to the channel

    def __post_init__(self) -> None:
        if self.high is None and self.low is None:
            raise ValueError(f"rule for {self.channel!r} has neither a high nor a low limit")
        for what in ("high", "low"):
            v = getattr(self, what)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(f"rule for {self.channel!r}: {what} must be a finite number")
        if not (isinstance(self.deadband, (int, float)) and self.deadband >= 0):
            raise ValueError(f"rule for {self.channel!r}: deadband must be >= 0")
        if self.high is not None and self.low is not None and self.low >= self.high:
            raise ValueError(f"rule for {self.channel!r}: low {self.low} >= high {self.high}")
        _check_delays(self.channel, self.on_delay_s, self.off_delay_s)


@dataclass(frozen=True)
class RateRule:
    """Rate-of-rise alarm: the channel's slope over the last ``window_s`` seconds
    above ``rise_per_min`` (units per minute); clears at ``rise_per_min - deadband``."""

    channel: str
    rise_per_min: float
    window_s: float = 30.0
    deadband: float = 0.0
    unit: str = ""
    label: str = ""
    priority: Priority = Priority.HIGH
    on_delay_s: float = 0.0
    off_delay_s: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        if not (isinstance(self.rise_per_min, (int, float)) and self.rise_per_min > 0):
            raise ValueError(f"rate rule for {self.channel!r}: rise_per_min must be > 0")
        if not (isinstance(self.window_s, (int, float)) and self.window_s > 0):
            raise ValueError(f"rate rule for {self.channel!r}: window_s must be > 0")
        if not (isinstance(self.deadband, (int, float)) and 0 <= self.deadband < self.rise_per_min):
            raise ValueError(f"rate rule for {self.channel!r}: deadband must be >= 0 "
                             f"and below rise_per_min")
        _check_delays(self.channel, self.on_delay_s, self.off_delay_s)


@dataclass(frozen=True)
class StaleRule:
    """Stale data: no sample of ``channel`` for more than ``after_s`` seconds."""

    channel: str
    after_s: float
    label: str = ""
    priority: Priority = Priority.MEDIUM
    source: str = ""

    def __post_init__(self) -> None:
        if not (isinstance(self.after_s, (int, float)) and self.after_s > 0):
            raise ValueError(f"stale rule for {self.channel!r}: after_s must be > 0")


@dataclass(frozen=True)
class FlagRule:
    """One bit of a flag word that is an alarm while set."""

    bit: int  # the bit's mask, e.g. 1 << 3
    name: str
    priority: Priority = Priority.MEDIUM
    text: str = ""


@dataclass(frozen=True)
class ConditionRule:
    """Configured priority/text of a discrete condition (overrides the caller's)."""

    alarm_id: str
    priority: Priority
    text: str = ""


DEFAULT_LIMITS: tuple[LimitRule, ...] = (
    LimitRule("gas_lel_pct", high=10.0, deadband=0.5, unit="%LEL", label="Gas",
              priority=Priority.HIGH),
    LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C", label="Temperature"),
    LimitRule("humidity_pct", high=90.0, deadband=2.0, unit="%RH", label="Humidity",
              priority=Priority.LOW),
    LimitRule("battery_v", low=22.0, deadband=0.3, unit="V", label="Battery"),
)


class Debounce:
    """On/off delay of a boolean condition.

    ``feed(raw, t)`` returns the new filtered state when it changes, else None:
    the raw value must hold ``on_delay_s`` (to become true) or ``off_delay_s``
    (to become false) since it first differed. ``poll(t)`` completes a pending
    change when time passes without samples (the last raw value is assumed to
    hold)."""

    def __init__(self, on_delay_s: float = 0.0, off_delay_s: float = 0.0,
                 state: bool = False) -> None:
        self.on_delay_s = float(on_delay_s)
        self.off_delay_s = float(off_delay_s)
        self.state = state
        self._since: float | None = None

    def feed(self, raw: bool, t: float) -> bool | None:
        if raw == self.state:
            self._since = None
            return None
        if self._since is None:
            self._since = t
        return self.poll(t)

    def poll(self, t: float) -> bool | None:
        if self._since is None:
            return None
        delay = self.off_delay_s if self.state else self.on_delay_s
        if t - self._since >= delay:
            self.state = not self.state
            self._since = None
            return self.state
        return None

    @property
    def pending(self) -> bool:
        return self._since is not None


class LimitTracker:
    """High or low limit with deadband and delays, for one condition of a rule."""

    def __init__(self, rule: LimitRule, cond: str) -> None:
        if cond not in ("high", "low"):
            raise ValueError(f"condition must be 'high' or 'low', not {cond!r}")
        self.rule = rule
        self.cond = cond
        self.limit = rule.high if cond == "high" else rule.low
        if self.limit is None:
            raise ValueError(f"rule for {rule.channel!r} has no {cond} limit")
        self.debounce = Debounce(rule.on_delay_s, rule.off_delay_s)

    def raw(self, value: float) -> bool:
        """The undelayed condition for ``value``, with the deadband applied."""
        db = self.rule.deadband
        if self.cond == "high":
            return value > self.limit - db if self.debounce.state else value > self.limit
        return value < self.limit + db if self.debounce.state else value < self.limit

    def feed(self, value: float, t: float) -> bool | None:
        return self.debounce.feed(self.raw(value), t)


def slope_per_min(ts, vs) -> float:
    """Least-squares slope of ``vs`` over ``ts`` (seconds), in units per minute."""
    n = len(ts)
    if n < 2:
        return 0.0
    mt = sum(ts) / n
    mv = sum(vs) / n
    sxx = sum((t - mt) ** 2 for t in ts)
    if sxx <= 0:
        return 0.0
    sxy = sum((t - mt) * (v - mv) for t, v in zip(ts, vs, strict=True))
    return 60.0 * sxy / sxx


class _SlidingSlope:
    """Running sums for the least-squares slope of a sliding window, O(1) per
    sample. Times are kept relative to a reference near the window so the sums
    do not lose precision; they are summed afresh whenever the reference moves."""

    def __init__(self) -> None:
        self.samples: deque[tuple[float, float]] = deque()
        self._ref = 0.0
        self._st = self._sv = self._stt = self._stv = 0.0

    def clear(self) -> None:
        self.samples.clear()
        self._st = self._sv = self._stt = self._stv = 0.0

    def __len__(self) -> int:
        return len(self.samples)

    def _add(self, t: float, v: float, sign: float) -> None:
        x = t - self._ref
        self._st += sign * x
        self._sv += sign * v
        self._stt += sign * x * x
        self._stv += sign * x * v

    def _resum(self) -> None:
        self._ref = self.samples[0][0] if self.samples else 0.0
        self._st = self._sv = self._stt = self._stv = 0.0
        for t, v in self.samples:
            self._add(t, v, 1.0)

    def append(self, t: float, v: float) -> None:
        self.samples.append((t, v))
        self._add(t, v, 1.0)

    def drop_older_than(self, t: float, window_s: float) -> None:
        s = self.samples
        while s and t - s[0][0] > window_s:
            t, v = s.popleft()
            self._add(t, v, -1.0)
        if s and s[0][0] - self._ref > 3600.0:
            self._resum()

    def per_min(self) -> float:
        n = len(self.samples)
        if n < 2:
            return 0.0
        sxx = self._stt - self._st * self._st / n
        if sxx <= 1e-12 * max(1.0, self._stt):
            return 0.0
        return 60.0 * (self._stv - self._st * self._sv / n) / sxx


class RateTracker:
    """Rate of rise over a sliding window; needs samples spanning half the
    window (and at least three) before it judges, so a single jump at start-up
    is not a rate. The slope is the least-squares one of :func:`slope_per_min`,
    kept by running sums so a long window costs nothing per sample."""

    def __init__(self, rule: RateRule) -> None:
        self.rule = rule
        self.samples = _SlidingSlope()
        self.debounce = Debounce(rule.on_delay_s, rule.off_delay_s)
        self.rate: float = 0.0

    def feed(self, value: float, t: float) -> bool | None:
        s = self.samples
        if len(s) and t < s.samples[-1][0]:
            s.clear()  # time went backwards: start again
        if not len(s):
            s._ref = t
        s.append(t, value)
        s.drop_older_than(t, self.rule.window_s)
        if len(s) < 3 or s.samples[-1][0] - s.samples[0][0] < 0.5 * self.rule.window_s:
            self.rate = 0.0
            return self.debounce.feed(False, t)
        self.rate = s.per_min()
        limit = self.rule.rise_per_min
        raw = self.rate > (limit - self.rule.deadband if self.debounce.state else limit)
        return self.debounce.feed(raw, t)
