"""First alarm rules for the desk (no Qt).

Two kinds of alarm, both kept by :class:`AlarmMonitor`:

* **limit alarms** on a measured channel: a high (and/or low) warning limit
  with a deadband. A high alarm is raised when the value goes above ``high``
  and clears only when it returns to ``high - deadband`` or below (a low alarm
  mirrors this), so a value hovering at the limit does not chatter.
* **flag alarms** from a bit field (the MCU's own alarm flags): raised when a
  bit sets, cleared when it clears.

Every change is returned as an :class:`AlarmChange`; :meth:`AlarmMonitor.active`
lists the standing alarms with time raised, value and limit. This is a first,
deliberately small set of rules; shelving, acknowledgement and the rest of an
ISA-18.2 alarm manager come later.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

__all__ = [
    "Alarm", "AlarmChange", "AlarmMonitor", "FlagRule", "LimitRule", "Priority",
    "DEFAULT_LIMITS",
]


class Priority(enum.IntEnum):
    """Alarm priority; higher is more urgent."""

    LOW = 1
    MEDIUM = 2
    HIGH = 3


@dataclass(frozen=True)
class LimitRule:
    """Warning limits of one channel. ``deadband`` is in the channel's unit."""

    channel: str
    high: float | None = None
    low: float | None = None
    deadband: float = 0.0
    unit: str = ""
    label: str = ""
    priority: Priority = Priority.MEDIUM

    def __post_init__(self) -> None:
        if self.high is None and self.low is None:
            raise ValueError(f"rule for {self.channel!r} has neither a high nor a low limit")
        if self.deadband < 0:
            raise ValueError(f"rule for {self.channel!r}: deadband must be >= 0")
        if self.high is not None and self.low is not None and self.low >= self.high:
            raise ValueError(f"rule for {self.channel!r}: low {self.low} >= high {self.high}")


@dataclass(frozen=True)
class FlagRule:
    """One bit of a flag word that is an alarm while set."""

    bit: int  # the bit's mask, e.g. 1 << 3
    name: str
    priority: Priority = Priority.MEDIUM
    text: str = ""


DEFAULT_LIMITS: tuple[LimitRule, ...] = (
    LimitRule("gas_lel_pct", high=10.0, deadband=0.5, unit="%LEL", label="Gas",
              priority=Priority.HIGH),
    LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C", label="Temperature"),
    LimitRule("humidity_pct", high=90.0, deadband=2.0, unit="%RH", label="Humidity",
              priority=Priority.LOW),
    LimitRule("battery_v", low=22.0, deadband=0.3, unit="V", label="Battery"),
)


@dataclass(frozen=True)
class Alarm:
    """A standing (or just cleared) alarm."""

    key: str  # e.g. "temp_c.high", "flags.GAS_HIGH"
    source: str  # the channel, or "flags"
    condition: str  # "high" | "low" | flag name
    priority: Priority
    raised_t: float  # UTC epoch seconds
    value: float  # value when raised (1.0 for a flag)
    limit: float | None
    unit: str = ""
    label: str = ""
    active: bool = True
    cleared_t: float | None = None
    last_value: float | None = None  # latest value seen while standing

    @property
    def text(self) -> str:
        """One line for the operator, e.g. "Gas 12.5 %LEL above limit 10 %LEL"."""
        name = self.label or self.source
        if self.limit is None:
            return self.label or f"{self.source}: {self.condition}"
        word = "above" if self.condition == "high" else "below"
        unit = f" {self.unit}" if self.unit else ""
        v = self.last_value if self.last_value is not None else self.value
        return f"{name} {v:.1f}{unit} {word} limit {self.limit:g}{unit}"

    @property
    def cleared_text(self) -> str:
        """One line for the return to normal."""
        name = self.label or self.source
        if self.limit is None:
            return f"{self.text}: cleared"
        unit = f" {self.unit}" if self.unit else ""
        v = self.last_value if self.last_value is not None else self.value
        return f"{name} back to {v:.1f}{unit} (limit {self.limit:g}{unit})"


@dataclass(frozen=True)
class AlarmChange:
    alarm: Alarm
    raised: bool  # True: raised now; False: cleared now
    t: float


class AlarmMonitor:
    """Evaluates limit rules and flag bits, and remembers what is standing."""

    def __init__(self, rules: Iterable[LimitRule] = DEFAULT_LIMITS,
                 flags: Iterable[FlagRule] = ()) -> None:
        self._rules: dict[str, LimitRule] = {}
        for r in rules:
            self._rules[r.channel] = r
        self._flags: list[FlagRule] = list(flags)
        self._active: dict[str, Alarm] = {}
        self._flag_word = 0
        self.ignored = 0  # non-finite values skipped

    # ----------------------------------------------------------------- rules
    def rule(self, channel: str) -> LimitRule | None:
        return self._rules.get(channel)

    @property
    def rules(self) -> list[LimitRule]:
        return list(self._rules.values())

    def set_rule(self, rule: LimitRule) -> None:
        """Add or replace the rule of ``rule.channel``; its standing alarms are
        re-evaluated at the next update."""
        self._rules[rule.channel] = rule

    # ---------------------------------------------------------------- update
    def update(self, channel: str, value: float, t: float) -> list[AlarmChange]:
        """Feed one value of ``channel`` at time ``t``; returns what changed."""
        rule = self._rules.get(channel)
        if rule is None:
            return []
        value = float(value)
        if not math.isfinite(value):
            self.ignored += 1
            return []
        changes: list[AlarmChange] = []
        if rule.high is not None:
            self._check(rule, "high", value, t, changes,
                        beyond=value > rule.high,
                        back=value <= rule.high - rule.deadband)
        if rule.low is not None:
            self._check(rule, "low", value, t, changes,
                        beyond=value < rule.low,
                        back=value >= rule.low + rule.deadband)
        return changes

    def update_many(self, values: Mapping[str, float], t: float) -> list[AlarmChange]:
        changes: list[AlarmChange] = []
        for channel, value in values.items():
            changes += self.update(channel, value, t)
        return changes

    def update_flags(self, word: int, t: float) -> list[AlarmChange]:
        """Feed the current flag word; bits that set raise, bits that clear clear."""
        word = int(word)
        changes: list[AlarmChange] = []
        for fr in self._flags:
            key = f"flags.{fr.name}"
            on = bool(word & fr.bit)
            standing = key in self._active
            if on and not standing:
                a = Alarm(key, "flags", fr.name, fr.priority, t, 1.0, None,
                          label=fr.text or fr.name)
                self._active[key] = a
                changes.append(AlarmChange(a, True, t))
            elif standing and not on:
                a = replace(self._active.pop(key), active=False, cleared_t=t)
                changes.append(AlarmChange(a, False, t))
        self._flag_word = word
        return changes

    def _check(self, rule: LimitRule, cond: str, value: float, t: float,
               changes: list[AlarmChange], *, beyond: bool, back: bool) -> None:
        key = f"{rule.channel}.{cond}"
        standing = self._active.get(key)
        limit = rule.high if cond == "high" else rule.low
        if standing is None:
            if beyond:
                a = Alarm(key, rule.channel, cond, rule.priority, t, value, limit,
                          rule.unit, rule.label, last_value=value)
                self._active[key] = a
                changes.append(AlarmChange(a, True, t))
        elif back:
            a = replace(self._active.pop(key), active=False, cleared_t=t, last_value=value)
            changes.append(AlarmChange(a, False, t))
        else:
            self._active[key] = replace(standing, last_value=value)

    # --------------------------------------------------------------- queries
    def active(self) -> list[Alarm]:
        """Standing alarms, most urgent first, then oldest first."""
        return sorted(self._active.values(), key=lambda a: (-a.priority, a.raised_t))

    def most_severe(self) -> Alarm | None:
        act = self.active()
        return act[0] if act else None

    def is_active(self, key: str) -> bool:
        return key in self._active

    def channel_priority(self, channel: str) -> Priority | None:
        """The highest priority standing on ``channel`` (limit alarms), or None."""
        ps = [a.priority for a in self._active.values() if a.source == channel]
        return max(ps) if ps else None

    def clear_all(self, t: float) -> list[AlarmChange]:
        changes = [AlarmChange(replace(a, active=False, cleared_t=t), False, t)
                   for a in self._active.values()]
        self._active.clear()
        self._flag_word = 0
        return changes
