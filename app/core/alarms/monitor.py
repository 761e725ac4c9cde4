"""AlarmMonitor: the desk's ISA-18.2 alarm manager (no Qt).

It evaluates the rules (limits, rate of rise, stale data, the MCU's flag bits,
discrete conditions such as link lost), runs every alarm through the ISA-18.2
state diagram of :mod:`app.core.alarms.model`, keeps the timers (on/off delays,
stale data, shelving expiry, the flood guard) and hands every transition to its
listeners.

Time is always given by the caller (UTC epoch seconds), so the monitor runs the
same live, in replay and in tests. Every public method that changes something
returns the transitions it made, and also passes each one to every listener
(``add_listener``) from the calling thread, after its internal lock is released.
A comment on an alarm (:meth:`AlarmMonitor.comment`) is not a transition: it is kept
with the alarm and passed to the comment listeners (``add_comment_listener``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

from app.core.alarms.flood import FloodGuard
from app.core.alarms.model import (
    Alarm,
    AlarmEvent,
    AlarmState,
    Priority,
    Transition,
    next_state,
)
from app.core.alarms.rules import (
    DEFAULT_LIMITS,
    ConditionRule,
    FlagRule,
    LimitRule,
    LimitTracker,
    RateRule,
    RateTracker,
    StaleRule,
)
from app.core.alarms.setpoints import FaultTracker, GasRule, SetPoint, SetPointTracker, gas_stage
from app.core.i18n import translate

log = logging.getLogger(__name__)

__all__ = ["AlarmGroup", "AlarmMonitor", "FLOOD_ID", "MAX_SHELVE_S"]

FLOOD_ID = "alarm.flood"
MAX_SHELVE_S = 8 * 3600.0  # one shift


@dataclass
class _Entry:
    key: str
    source: str
    condition: str
    priority: Priority
    limit: float | None = None
    unit: str = ""
    label: str = ""
    channel: str | None = None
    description: str = ""
    state: AlarmState = AlarmState.NORMAL
    active: bool = False
    raised_t: float = math.nan
    value: float | None = None
    last_value: float | None = None
    cleared_t: float | None = None
    acked_t: float | None = None
    acked_by: str | None = None
    shelved_until: float | None = None
    reason: str | None = None
    in_flood: bool = False
    comment: str | None = None
    comment_by: str | None = None
    comment_t: float | None = None

    def snapshot(self) -> Alarm:
        return Alarm(self.key, self.source, self.condition, self.priority, self.raised_t,
                     self.value, self.limit, self.unit, self.label, self.active,
                     self.cleared_t, self.last_value, self.state, self.channel,
                     self.description, self.acked_t, self.acked_by, self.shelved_until,
                     self.reason, self.in_flood, self.comment, self.comment_by,
                     self.comment_t)


@dataclass(frozen=True)
class AlarmGroup:
    """Listed alarms of one source, for the grouped view during a flood."""

    source: str
    priority: Priority  # the most urgent in the group
    count: int
    unacked: int
    keys: tuple[str, ...] = field(default=())


def _reason(reason: str | None, what: str) -> str:
    if not isinstance(reason, str) or not reason.strip():
        raise ValueError(f"{what} needs a reason")
    return reason.strip()


class AlarmMonitor:
    """The alarm manager: rules in, ISA-18.2 transitions out."""

    def __init__(self, rules: Iterable[LimitRule] = DEFAULT_LIMITS,
                 flags: Iterable[FlagRule] = (), *, rates: Iterable[RateRule] = (),
                 stale: Iterable[StaleRule] = (), conditions: Iterable[ConditionRule] = (),
                 setpoints: Iterable[SetPoint] = (), gas: Iterable[GasRule] = (),
                 flood_per_minute: int = 10, flood_window_s: float = 60.0,
                 max_shelve_s: float = MAX_SHELVE_S) -> None:
        self._lock = threading.RLock()
        self._listeners: list[Callable[[Transition], None]] = []
        self._comment_listeners: list[Callable[[Alarm], None]] = []
        self.listener_errors = 0
        self.ignored = 0  # non-finite values skipped
        self._entries: dict[str, _Entry] = {}
        self._rules: dict[str, LimitRule] = {}
        self._limit_trackers: dict[str, LimitTracker] = {}
        self._rates: dict[str, RateRule] = {}
        self._rate_trackers: dict[str, RateTracker] = {}
        self._stale: dict[str, StaleRule] = {}
        self._last_seen: dict[str, float] = {}
        self._last_value: dict[str, float] = {}
        self._flags: list[FlagRule] = []
        self._flag_word = 0
        self._conditions: dict[str, ConditionRule] = {}
        self._setpoints: dict[str, SetPointTracker] = {}  # by alarm id "<channel>.<name>"
        self._sp_made: set[str] = set()  # every alarm id a set-point or gas rule made
        self._gas: dict[str, GasRule] = {}
        self._faults: dict[str, FaultTracker] = {}
        self.flood = FloodGuard(flood_per_minute, flood_window_s)
        self.max_shelve_s = float(max_shelve_s)
        self._t_latest = 0.0  # the latest time given to the monitor
        self._config_channels: set[str] = set()  # limit rules that came from a configuration
        self.configure(rules, flags, rates=rates, stale=stale, conditions=conditions,
                       setpoints=setpoints, gas=gas)

    @classmethod
    def from_config(cls, cfg) -> AlarmMonitor:
        """A monitor with the rules of an :class:`~app.core.alarms.config.AlarmConfig`."""
        m = cls(())
        m.apply_config(cfg)
        return m

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

    # ------------------------------------------------------------ listeners
    def add_listener(self, fn: Callable[[Transition], None]) -> None:
        """``fn(transition)`` is called for every transition, from the thread
        that drives the monitor."""
        with self._lock:
            if fn not in self._listeners:
                self._listeners.append(fn)

    def remove_listener(self, fn: Callable[[Transition], None]) -> None:
        with self._lock:
            if fn in self._listeners:
                self._listeners.remove(fn)

    def _emit(self, trs: list[Transition]) -> list[Transition]:
        for tr in trs:  # every transition in the desk's log too
            a = tr.alarm
            log.info("alarm %s %s: %s -> %s (%s%s%s%s) %s", a.key, tr.event.name.lower(),
                     tr.from_state.name, tr.to_state.name, a.priority.name,
                     "" if a.value is None else f", value {a.value}",
                     f", by {tr.user}" if tr.user else "",
                     f", {tr.reason}" if tr.reason else "", a.text)
        if trs:
            with self._lock:
                listeners = list(self._listeners)
            for tr in trs:
                for fn in listeners:
                    try:
                        fn(tr)
                    except Exception:  # a listener's failure must not stop the alarms
                        self.listener_errors += 1
                        log.exception("alarm listener %r failed on %s", fn, tr.alarm.key)
        return trs

    # ---------------------------------------------------------------- rules
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

    # ------------------------------------------------------------- entries
    def _entry(self, key: str) -> _Entry:
        e = self._entries.get(key)
        if e is None:
            e = self._new_entry(key)
            self._entries[key] = e
        return e

    def _new_entry(self, key: str) -> _Entry:
        """Metadata of alarm ``key`` from the rules that make it."""
        channel, _, cond = key.rpartition(".")
        sp = self._setpoints.get(key)
        if sp is not None:
            r = sp.sp
            return _Entry(key, r.source or channel, r.condition, r.priority, r.value,
                          r.unit, r.label or f"{channel} {r.name}", channel)
        if cond == "fault" and channel in self._gas:
            g = self._gas[channel]
            return _Entry(key, g.source or channel, "fault", g.fault_priority, None,
                          g.unit, f"{g.label} sensor fault", channel)
        if cond in ("high", "low") and channel in self._rules:
            r = self._rules[channel]
            return _Entry(key, r.source or channel, cond, r.priority, getattr(r, cond),
                          r.unit, r.label, channel)
        if cond == "rate" and channel in self._rates:
            r = self._rates[channel]
            unit = r.unit or (self._rules[channel].unit if channel in self._rules else "")
            label = r.label or (self._rules[channel].label if channel in self._rules else "")
            return _Entry(key, r.source or channel, "rate", r.priority, r.rise_per_min,
                          unit, f"{label or channel} rate of rise", channel)
        if cond == "stale" and channel in self._stale:
            r = self._stale[channel]
            label = r.label or (self._rules[channel].label if channel in self._rules else "")
            return _Entry(key, r.source or channel, "stale", r.priority, r.after_s, "s",
                          f"{label or channel} stale", channel)
        if channel == "flag":
            for f in self._flags:
                if f.name == cond:
                    return _Entry(key, "robot", f.name, f.priority, label=f.text or f.name,
                                  description=f.text)
        c = self._conditions.get(key)
        return _Entry(key, channel or key, cond or key,
                      c.priority if c else Priority.MEDIUM,
                      label=(c.text if c else "") or key, description=c.text if c else "")

    def _move(self, e: _Entry, new: AlarmState, event: AlarmEvent, t: float,
              user: str | None = None, reason: str | None = None) -> list[Transition]:
        old = e.state
        if new is old:
            return []
        e.state = new
        if event is AlarmEvent.ACK:
            e.acked_t, e.acked_by = t, user
        if new in (AlarmState.UNACK,):
            e.acked_t = e.acked_by = None
        if old is AlarmState.NORMAL and new is AlarmState.UNACK:  # a new occurrence
            e.comment = e.comment_by = e.comment_t = None
        if new is not AlarmState.SHELVED:
            e.shelved_until = None
        if new not in (AlarmState.SHELVED, AlarmState.OUT_OF_SERVICE):
            e.reason = None
        out: list[Transition] = []
        raised = new is AlarmState.UNACK and e.key != FLOOD_ID
        if raised:
            started = self.flood.note(t)
            e.in_flood = self.flood.active
            if started:
                out += self._flood_notice(True, t)
        tr = Transition(e.snapshot(), t, old, new, event, user, reason)
        return [tr] + out

    def _flood_notice(self, on: bool, t: float) -> list[Transition]:
        n = self.flood.count(t)
        text = translate("Alarm", "Alarm flood: more than {max} alarms in {window} s — the "
                         "list is grouped by source").format(max=self.flood.max_per_minute,
                                                             window=f"{self.flood.window_s:g}")
        return self._condition(FLOOD_ID, on, t, value=float(n), source="alarms",
                               priority=Priority.HIGH, text=text)

    def _condition(self, key: str, active: bool, t: float, *, value: float | None = None,
                   user: str | None = None, reason: str | None = None,
                   **meta) -> list[Transition]:
        e = self._entries.get(key)
        if e is None:
            e = self._new_entry(key)
            for name in ("source", "priority", "text", "unit", "label"):
                v = meta.get(name)
                if v is None:
                    continue
                if name == "text":
                    if not (key in self._conditions and self._conditions[key].text):
                        e.description = v
                        e.label = e.label if e.label != key else v
                elif name == "priority" and key in self._conditions:
                    continue  # the configured priority wins
                else:
                    setattr(e, name, v)
            self._entries[key] = e
        if value is not None:
            e.last_value = value
        self._t_latest = max(self._t_latest, t)
        if e.active == bool(active):
            return []
        e.active = bool(active)
        if active:
            e.raised_t, e.value, e.cleared_t = t, value, None
            e.last_value = value
            event = AlarmEvent.ACTIVATE
        else:
            e.cleared_t = t
            event = AlarmEvent.CLEAR
        new = next_state(e.state, event, e.active)
        return self._move(e, new, event, t, user, reason)

    # --------------------------------------------------------------- inputs
    def update(self, channel: str, value: float, t: float) -> list[Transition]:
        """Feed one value of ``channel`` at time ``t``; returns the transitions."""
        with self._lock:
            trs = self._update(channel, value, t)
        return self._emit(trs)

    def _update(self, channel: str, value, t: float) -> list[Transition]:
        try:
            value = float(value)
        except (TypeError, ValueError):
            value = math.nan
        if not math.isfinite(value):
            if channel in self._rules or channel in self._rates:
                self.ignored += 1
            return []
        out: list[Transition] = []
        self._t_latest = max(self._t_latest, t)
        before = self._last_value.get(channel)
        self._last_value[channel] = value
        if before is not None and before != value:
            for ch, ft in self._faults.items():
                if ch != channel:
                    ft.other_moved(t)
        if channel in self._stale:
            self._last_seen[channel] = t
            out += self._condition(f"{channel}.stale", False, t)
        for cond in ("high", "low"):
            key = f"{channel}.{cond}"
            tr = self._limit_trackers.get(key)
            if tr is None:
                continue
            e = self._entries.get(key)
            if e is not None:
                e.last_value = value
            flip = tr.feed(value, t)
            if flip is not None:
                out += self._condition(key, flip, t, value=value)
        rt = self._rate_trackers.get(channel)
        if rt is not None:
            flip = rt.feed(value, t)
            key = f"{channel}.rate"
            e = self._entries.get(key)
            if e is not None:
                e.last_value = rt.rate
            if flip is not None:
                out += self._condition(key, flip, t, value=rt.rate)
        out += self._update_setpoints(channel, value, t)
        return out

    def _update_setpoints(self, channel: str, value: float, t: float) -> list[Transition]:
        out: list[Transition] = []
        for key, tr in self._setpoints.items():
            if tr.sp.channel != channel:
                continue
            e = self._entries.get(key)
            if e is not None:
                e.last_value = value
            flip = tr.feed(value, t)
            if flip is not None:
                out += self._condition(key, flip, t, value=value)
        ft = self._faults.get(channel)
        if ft is not None:
            ft.feed(value, t)
            key = f"{channel}.fault"
            e = self._entries.get(key)
            if ft.active and (e is None or not e.active):
                self._entry(key).description = ft.why()
                out += self._condition(key, True, t, value=value)
            elif not ft.active and e is not None and e.active:
                out += self._condition(key, False, t, value=value)
        return out

    def reset(self, alarm_id: str, t: float, user: str | None = None
              ) -> tuple[list[Transition], str]:
        """Reset a latched set-point (the operator's reset, not an acknowledgement).

        Returns the transitions and "" when the latch is released, or no
        transitions and the reason when it is refused (not latched, unknown,
        or the value still beyond the set-point less its deadband). The alarm
        still needs its acknowledgement if it has none."""
        with self._lock:
            tr = self._setpoints.get(alarm_id)
            if tr is None:
                return [], f"{alarm_id} has no latching set-point"
            ok, why = tr.reset()
            if not ok:
                log.info("alarm reset of %s by %s refused: %s", alarm_id, user, why)
                return [], why
            trs = self._condition(alarm_id, False, t, value=tr.value, user=user,
                                  reason="reset")
            log.info("alarm %s reset by %s", alarm_id, user)
        return self._emit(trs), ""

    def latched(self, alarm_id: str) -> bool:
        tr = self._setpoints.get(alarm_id)
        return bool(tr and tr.latched)

    def stage(self, channel: str) -> str | None:
        """The gas stage of ``channel`` (normal, A1, A2, over-range, fault), or
        None if it has no gas rule. Its ``high`` limit counts as A1."""
        if channel not in self._gas:
            return None
        act = {tr.sp.stage for k, tr in self._setpoints.items()
               if tr.sp.channel == channel and tr.sp.stage and self._raw_active(k)}
        if self._raw_active(f"{channel}.high"):
            act.add("A1")
        return gas_stage(act, self._raw_active(f"{channel}.fault"))

    def _raw_active(self, key: str) -> bool:
        e = self._entries.get(key)
        return bool(e and e.active)

    def update_many(self, values: Mapping[str, float], t: float) -> list[Transition]:
        with self._lock:
            trs = []
            for channel, value in values.items():
                trs += self._update(channel, value, t)
        return self._emit(trs)

    def update_flags(self, word: int, t: float) -> list[Transition]:
        """Feed the current flag word; a set bit is an active condition."""
        with self._lock:
            word = int(word)
            trs: list[Transition] = []
            for fr in self._flags:
                trs += self._condition(f"flag.{fr.name}", bool(word & fr.bit), t)
            self._flag_word = word
        return self._emit(trs)

    def set_condition(self, alarm_id: str, active: bool, t: float, *, source: str,
                      priority: Priority, text: str, value: float | None = None
                      ) -> list[Transition]:
        """A discrete condition (link lost, archive failing, meter out of band):
        ``active`` true raises it, false returns it to normal. A priority or text
        configured for ``alarm_id`` wins over the one given here."""
        with self._lock:
            trs = self._condition(alarm_id, active, t, value=value, source=source,
                                  priority=Priority(priority), text=text)
        return self._emit(trs)

    def tick(self, t: float) -> list[Transition]:
        """Run the timers at time ``t``: pending on/off delays, stale data,
        shelving expiry and the end of a flood."""
        with self._lock:
            self._t_latest = max(self._t_latest, t)
            trs: list[Transition] = []
            for key, tr in self._limit_trackers.items():
                flip = tr.debounce.poll(t)
                if flip is not None:
                    trs += self._condition(key, flip, t,
                                           value=self._last_value.get(tr.rule.channel))
            for channel, rt in self._rate_trackers.items():
                flip = rt.debounce.poll(t)
                if flip is not None:
                    trs += self._condition(f"{channel}.rate", flip, t, value=rt.rate)
            for key, sp in self._setpoints.items():
                flip = sp.poll(t)
                if flip is not None:
                    trs += self._condition(key, flip, t, value=sp.value)
            for channel, rule in self._stale.items():
                seen = self._last_seen.get(channel)
                if seen is not None and t - seen > rule.after_s:
                    trs += self._condition(f"{channel}.stale", True, t, value=t - seen)
            for e in list(self._entries.values()):
                if (e.state is AlarmState.SHELVED and e.shelved_until is not None
                        and t >= e.shelved_until):
                    trs += self._move(e, next_state(e.state, AlarmEvent.UNSHELVE, e.active),
                                      AlarmEvent.UNSHELVE, t, reason="shelving expired")
            if self.flood.check(t):
                trs += self._flood_notice(False, t)
        return self._emit(trs)

    # ------------------------------------------------------------- operator
    def acknowledge(self, alarm_id: str, t: float, user: str | None = None, *,
                    comment: str | None = None, origin: str | None = None
                    ) -> list[Transition]:
        """Acknowledge one alarm (UNACK → ACKED, RTN_UNACK → NORMAL); anything
        else is left alone and returns []. ``comment`` (kept as the transition's
        reason) and ``origin`` (where the user acted from, e.g. an OPC UA client's
        address) go on record with it."""
        with self._lock:
            trs = self._ack(alarm_id, t, user, comment or None)
            if origin:
                trs = [dataclasses.replace(tr, origin=origin) for tr in trs]
        return self._emit(trs)

    def _ack(self, alarm_id: str, t: float, user: str | None,
             comment: str | None = None) -> list[Transition]:
        e = self._entries.get(alarm_id)
        if e is None:
            return []
        return self._move(e, next_state(e.state, AlarmEvent.ACK, e.active),
                          AlarmEvent.ACK, t, user, comment)

    def comment(self, alarm_id: str, t: float, text: str, user: str | None = None
                ) -> Alarm | None:
        """A comment on an alarm (who, what, when; e.g. an OPC UA client's AddComment):
        kept with it until its next occurrence and passed to the comment listeners.
        Returns the alarm, or None for an alarm the monitor does not know."""
        with self._lock:
            e = self._entries.get(alarm_id)
            if e is None:
                return None
            e.comment, e.comment_by, e.comment_t = str(text), user, float(t)
            a = e.snapshot()
            listeners = list(self._comment_listeners)
        log.info("alarm %s comment by %s: %s", alarm_id, user, text)
        for fn in listeners:
            try:
                fn(a)
            except Exception:  # a listener's failure must not stop the alarms
                self.listener_errors += 1
                log.exception("alarm comment listener %r failed on %s", fn, alarm_id)
        return a

    def add_comment_listener(self, fn: Callable[[Alarm], None]) -> None:
        """``fn(alarm)`` is called for every comment, from the commenting thread."""
        with self._lock:
            if fn not in self._comment_listeners:
                self._comment_listeners.append(fn)

    def remove_comment_listener(self, fn: Callable[[Alarm], None]) -> None:
        with self._lock:
            if fn in self._comment_listeners:
                self._comment_listeners.remove(fn)

    def acknowledge_all(self, ids: Iterable[str], t: float, user: str | None = None
                        ) -> list[Transition]:
        with self._lock:
            trs: list[Transition] = []
            for i in list(ids):
                trs += self._ack(i, t, user)
        return self._emit(trs)

    def shelve(self, alarm_id: str, t: float, duration_s: float, reason: str,
               user: str | None = None, *, origin: str | None = None) -> list[Transition]:
        """Shelve an alarm for ``duration_s`` (0 < duration ≤ ``max_shelve_s``)
        with a reason; it comes back by itself when the time is up. Raises
        ValueError for a bad duration or an empty reason. ``origin``: where the user
        acted from, as for :meth:`acknowledge`."""
        reason = _reason(reason, "shelving")
        try:
            d = float(duration_s)
        except (TypeError, ValueError):
            raise ValueError(f"shelving duration {duration_s!r} is not a number") from None
        if not (math.isfinite(d) and 0 < d <= self.max_shelve_s):
            raise ValueError(f"shelving duration must be between 0 and "
                             f"{self.max_shelve_s:g} s, not {duration_s!r}")
        with self._lock:
            e = self._entry(alarm_id)
            new = next_state(e.state, AlarmEvent.SHELVE, e.active)
            if new is e.state:
                trs = []
            else:
                e.shelved_until, e.reason = t + d, reason
                trs = self._move(e, new, AlarmEvent.SHELVE, t, user, reason)
        return self._emit([dataclasses.replace(tr, origin=origin) for tr in trs]
                          if origin else trs)

    def unshelve(self, alarm_id: str, t: float, user: str | None = None, *,
                 origin: str | None = None) -> list[Transition]:
        with self._lock:
            e = self._entries.get(alarm_id)
            trs = [] if e is None else self._move(
                e, next_state(e.state, AlarmEvent.UNSHELVE, e.active), AlarmEvent.UNSHELVE,
                t, user)
        return self._emit([dataclasses.replace(tr, origin=origin) for tr in trs]
                          if origin else trs)

    def set_out_of_service(self, alarm_id: str, on: bool, t: float, reason: str | None = None,
                           user: str | None = None) -> list[Transition]:
        """Take an alarm out of service for maintenance (``on``; a reason is
        required) or put it back (it annunciates again if its condition stands)."""
        with self._lock:
            if on:
                reason = _reason(reason, "out of service")
                e = self._entry(alarm_id)
                new = next_state(e.state, AlarmEvent.REMOVE, e.active)
                trs = []
                if new is not e.state:
                    e.reason = reason
                    trs = self._move(e, new, AlarmEvent.REMOVE, t, user, reason)
            else:
                e = self._entries.get(alarm_id)
                trs = [] if e is None else self._move(
                    e, next_state(e.state, AlarmEvent.RETURN, e.active), AlarmEvent.RETURN,
                    t, user, reason)
        return self._emit(trs)

    def clear_all(self, t: float) -> list[Transition]:
        """Every condition returns to normal (e.g. a new robot connected)."""
        with self._lock:
            trs: list[Transition] = []
            for key, e in list(self._entries.items()):
                if e.active:
                    trs += self._condition(key, False, t)
            for tr in self._limit_trackers.values():
                tr.debounce.state = False
            for rt in self._rate_trackers.values():
                rt.debounce.state = False
                rt.samples.clear()
            for key, sp in self._setpoints.items():
                self._setpoints[key] = SetPointTracker(sp.sp)
            for ch, g in self._gas.items():
                self._faults[ch] = FaultTracker(g)
            self._flag_word = 0
        return self._emit(trs)

    # -------------------------------------------------------------- queries
    def get(self, alarm_id: str) -> Alarm | None:
        e = self._entries.get(alarm_id)
        return None if e is None else e.snapshot()

    def state(self, alarm_id: str) -> AlarmState:
        e = self._entries.get(alarm_id)
        return AlarmState.NORMAL if e is None else e.state

    @staticmethod
    def _order(a: Alarm) -> tuple:
        return (-a.priority, a.raised_t)

    def alarms(self) -> list[Alarm]:
        """Every alarm the monitor has seen, in any state."""
        with self._lock:
            return sorted((e.snapshot() for e in self._entries.values()), key=self._order)

    def listed(self) -> list[Alarm]:
        """What the alarm list shows: every alarm not NORMAL, most urgent first."""
        return [a for a in self.alarms() if a.listed]

    def active(self) -> list[Alarm]:
        """Standing annunciated alarms (UNACK or ACKED), most urgent, then oldest first."""
        return [a for a in self.alarms()
                if a.state in (AlarmState.UNACK, AlarmState.ACKED)]

    def unacknowledged(self) -> list[Alarm]:
        return [a for a in self.alarms()
                if a.state in (AlarmState.UNACK, AlarmState.RTN_UNACK)]

    def most_severe(self) -> Alarm | None:
        act = self.active()
        return act[0] if act else None

    def most_severe_unacknowledged(self) -> Alarm | None:
        """The alarm for the header: the most urgent unacknowledged one, active
        before returned-to-normal, then the oldest."""
        un = sorted(self.unacknowledged(),
                    key=lambda a: (-a.priority, a.state is not AlarmState.UNACK, a.raised_t))
        return un[0] if un else None

    def is_active(self, key: str) -> bool:
        return self.state(key) in (AlarmState.UNACK, AlarmState.ACKED)

    def channel_priority(self, channel: str) -> Priority | None:
        """The highest priority standing on ``channel``, or None."""
        ps = [a.priority for a in self.active() if (a.channel or a.source) == channel]
        return max(ps) if ps else None

    def value_priority(self, channel: str) -> Priority | None:
        """The highest priority standing on ``channel``'s value (a limit, a rate of
        rise), or None. A stale-data alarm is left out: old data is shown with its
        age, never in a process alarm's colour (ISA-101)."""
        ps = [a.priority for a in self.active()
              if (a.channel or a.source) == channel and a.condition != "stale"]
        return max(ps) if ps else None

    @property
    def flood_active(self) -> bool:
        return self.flood.active

    def groups(self) -> list[AlarmGroup]:
        """Listed alarms grouped by source (the view during a flood)."""
        by: dict[str, list[Alarm]] = {}
        for a in self.listed():  # the flood notice is its own group ("alarms")
            by.setdefault(a.source, []).append(a)
        out = [AlarmGroup(src, max(a.priority for a in al), len(al),
                          sum(1 for a in al if not a.acknowledged),
                          tuple(a.key for a in al)) for src, al in by.items()]
        return sorted(out, key=lambda g: (-g.priority, -g.count, g.source))
