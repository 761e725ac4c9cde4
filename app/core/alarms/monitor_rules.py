"""The alarm monitor's rules (no Qt): limits, set-points and gas rules, rates of
rise, stale data, the MCU's flag bits and discrete conditions; replacing them all
from a configuration, and the metadata (source, priority, limit, unit, label) a
new alarm takes from the rule that makes it.

A mixin of :class:`~app.core.alarms.monitor.AlarmMonitor`: the rule tables and
trackers are the monitor's, changed under its lock. A standing alarm whose rule
is replaced keeps its state and is judged by the new rule from the next sample.
"""

from __future__ import annotations

from collections.abc import Iterable

from app.core.alarms.entry import Entry
from app.core.alarms.model import Alarm, Priority, Transition
from app.core.alarms.rules import (
    ConditionRule,
    FlagRule,
    LimitRule,
    LimitTracker,
    RateRule,
    RateTracker,
    StaleRule,
)
from app.core.alarms.setpoints import FaultTracker, GasRule, SetPoint, SetPointTracker

__all__ = ["RuleBook"]


class RuleBook:
    """The monitor's rules and what each alarm learns from its rule (mixin)."""

    def apply_config(self, cfg, t: float | None = None) -> list[Transition]:
        """Replace every rule by those of ``cfg``. Standing alarms whose rule is
        still there keep their state; an active alarm whose rule is gone returns
        to normal at ``t`` (default: the latest time the monitor has seen). Limit
        rules added by :meth:`set_rule` outside a configuration (a meter's band)
        are kept."""
        with self._lock:
            for ch in self._config_channels:
                self._rules.pop(ch, None)
                self._limit_trackers.pop(f"{ch}.high", None)
                self._limit_trackers.pop(f"{ch}.low", None)
            self._config_channels = {r.channel for r in cfg.limits}
            self._rates.clear()
            self._rate_trackers.clear()
            self._stale.clear()
            self._flags = []
            self._conditions.clear()
            self._setpoints.clear()
            self._gas.clear()
            self._faults.clear()
            self.flood.max_per_minute = int(cfg.flood_per_minute)  # the count goes on
            self.flood.window_s = float(cfg.flood_window_s)
            self.max_shelve_s = float(cfg.max_shelve_s)
            self.configure(cfg.limits, cfg.flag_rules(), rates=cfg.rates, stale=cfg.stale,
                           conditions=cfg.conditions,
                           setpoints=getattr(cfg, "setpoints", ()), gas=getattr(cfg, "gas", ()))
            when = self._t_latest if t is None else t
            trs: list[Transition] = []
            for key, e in list(self._entries.items()):
                if e.active and not self._has_rule(key):
                    trs += self._condition(key, False, when)
        return self._emit(trs)

    def _has_rule(self, key: str) -> bool:
        """False for a rule-made alarm (limit, rate, stale, flag) whose rule is gone."""
        channel, _, cond = key.rpartition(".")
        if key in self._sp_made:
            return key in self._setpoints or (cond == "fault" and channel in self._faults)
        if cond in ("high", "low"):
            return key in self._limit_trackers
        if cond == "rate":
            return channel in self._rate_trackers
        if cond == "stale":
            return channel in self._stale
        if channel == "flag":
            return any(f.name == cond for f in self._flags)
        return True  # a discrete condition: its caller clears it

    def configure(self, rules: Iterable[LimitRule] = (), flags: Iterable[FlagRule] = (), *,
                  rates: Iterable[RateRule] = (), stale: Iterable[StaleRule] = (),
                  conditions: Iterable[ConditionRule] = (),
                  setpoints: Iterable[SetPoint] = (), gas: Iterable[GasRule] = ()) -> None:
        """Add or replace rules (by channel / flag / alarm id / set-point id)."""
        with self._lock:
            for sp in setpoints:
                self.set_setpoint(sp)
            for g in gas:
                self._gas[g.channel] = g
                self._faults[g.channel] = FaultTracker(g)
                self._sp_made.add(f"{g.channel}.fault")
            for r in rules:
                self.set_rule(r)
            for r in rates:
                self.set_rate_rule(r)
            for r in stale:
                self._stale[r.channel] = r
            known = {f.name: i for i, f in enumerate(self._flags)}
            for f in flags:
                if f.name in known:
                    self._flags[known[f.name]] = f
                else:
                    self._flags.append(f)
            for c in conditions:
                self._conditions[c.alarm_id] = c

    def rule(self, channel: str) -> LimitRule | None:
        return self._rules.get(channel)

    @property
    def rules(self) -> list[LimitRule]:
        return list(self._rules.values())

    def configured(self) -> list[Alarm]:
        """An alarm (as it stands, or as it is while normal) for every key the rules
        can raise: limits, set-points, gas faults, rates, stale data, MCU flags."""
        with self._lock:
            keys = [f"{ch}.{c}" for ch, r in self._rules.items() for c in ("high", "low")
                    if getattr(r, c, None) is not None]
            keys += list(self._setpoints)
            keys += [f"{ch}.fault" for ch in self._faults]
            keys += [f"{ch}.rate" for ch in self._rates]
            keys += [f"{ch}.stale" for ch in self._stale]
            keys += [f"flag.{f.name}" for f in self._flags]
            return [(self._entries.get(k) or self._new_entry(k)).snapshot() for k in keys]

    @property
    def rate_rules(self) -> list[RateRule]:
        return list(self._rates.values())

    @property
    def stale_rules(self) -> list[StaleRule]:
        return list(self._stale.values())

    @property
    def flag_rules(self) -> list[FlagRule]:
        return list(self._flags)

    def set_rule(self, rule: LimitRule) -> None:
        """Add or replace the limit rule of ``rule.channel``; a standing alarm
        stays standing and is judged by the new limits from the next sample."""
        with self._lock:
            self._rules[rule.channel] = rule
            for cond in ("high", "low"):
                key = f"{rule.channel}.{cond}"
                if getattr(rule, cond) is None:
                    self._limit_trackers.pop(key, None)
                    continue
                tr = LimitTracker(rule, cond)
                e = self._entries.get(key)
                if e is not None:
                    tr.debounce.state = e.active
                    e.limit, e.priority = tr.limit, rule.priority
                    e.unit, e.label = rule.unit, rule.label
                    e.source = rule.source or rule.channel
                self._limit_trackers[key] = tr

    def set_setpoint(self, sp: SetPoint) -> None:
        """Add or replace one set-point; a standing (or latched) alarm stays."""
        with self._lock:
            tr = SetPointTracker(sp)
            e = self._entries.get(sp.key)
            if e is not None:
                tr.debounce.state = e.active
                tr.latched = e.active and sp.latching  # an active latching alarm is latched
                tr.value = e.last_value
                e.limit, e.priority, e.unit = sp.value, sp.priority, sp.unit
                e.label = sp.label or e.label
            self._setpoints[sp.key] = tr
            self._sp_made.add(sp.key)

    @property
    def setpoints(self) -> list[SetPoint]:
        return [tr.sp for tr in self._setpoints.values()]

    @property
    def gas_rules(self) -> list[GasRule]:
        return list(self._gas.values())

    def set_rate_rule(self, rule: RateRule) -> None:
        with self._lock:
            self._rates[rule.channel] = rule
            tr = RateTracker(rule)
            e = self._entries.get(f"{rule.channel}.rate")
            if e is not None:
                tr.debounce.state = e.active
                e.limit, e.priority = rule.rise_per_min, rule.priority
            self._rate_trackers[rule.channel] = tr

    # ------------------------------------------------------------- metadata
    def _new_entry(self, key: str) -> Entry:
        """Metadata of alarm ``key`` from the rules that make it."""
        channel, _, cond = key.rpartition(".")
        sp = self._setpoints.get(key)
        if sp is not None:
            r = sp.sp
            return Entry(key, r.source or channel, r.condition, r.priority, r.value,
                          r.unit, r.label or f"{channel} {r.name}", channel)
        if cond == "fault" and channel in self._gas:
            g = self._gas[channel]
            return Entry(key, g.source or channel, "fault", g.fault_priority, None,
                          g.unit, f"{g.label} sensor fault", channel)
        if cond in ("high", "low") and channel in self._rules:
            r = self._rules[channel]
            return Entry(key, r.source or channel, cond, r.priority, getattr(r, cond),
                          r.unit, r.label, channel)
        if cond == "rate" and channel in self._rates:
            r = self._rates[channel]
            unit = r.unit or (self._rules[channel].unit if channel in self._rules else "")
            label = r.label or (self._rules[channel].label if channel in self._rules else "")
            return Entry(key, r.source or channel, "rate", r.priority, r.rise_per_min,
                          unit, f"{label or channel} rate of rise", channel)
        if cond == "stale" and channel in self._stale:
            r = self._stale[channel]
            label = r.label or (self._rules[channel].label if channel in self._rules else "")
            return Entry(key, r.source or channel, "stale", r.priority, r.after_s, "s",
                          f"{label or channel} stale", channel)
        if channel == "flag":
            for f in self._flags:
                if f.name == cond:
                    return Entry(key, "robot", f.name, f.priority, label=f.text or f.name,
                                  description=f.text)
        c = self._conditions.get(key)
        return Entry(key, channel or key, cond or key,
                      c.priority if c else Priority.MEDIUM,
                      label=(c.text if c else "") or key, description=c.text if c else "")

