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

This module holds the inputs (values, flag words, discrete conditions, the
timers) and the state machine's bookkeeping. The rest of the monitor is in its
mixins: the rules (:mod:`~app.core.alarms.monitor_rules`), the operator's
actions — acknowledge, comment, shelve, out of service, latch reset
(:mod:`~app.core.alarms.monitor_actions`) — and the queries
(:mod:`~app.core.alarms.monitor_queries`). A comment on an alarm is not a
transition: it is kept with the alarm and passed to the comment listeners.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable, Iterable, Mapping

from app.core.alarms.entry import Entry, Listeners
from app.core.alarms.flood import FloodGuard
from app.core.alarms.model import (
    AlarmEvent,
    AlarmState,
    Priority,
    Transition,
    next_state,
)
from app.core.alarms.monitor_actions import OperatorActions
from app.core.alarms.monitor_queries import AlarmGroup, AlarmQueries
from app.core.alarms.monitor_rules import RuleBook
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
from app.core.alarms.setpoints import FaultTracker, GasRule, SetPoint, SetPointTracker
from app.core.i18n import translate

log = logging.getLogger(__name__)

__all__ = ["AlarmGroup", "AlarmMonitor", "FLOOD_ID", "MAX_SHELVE_S"]

FLOOD_ID = "alarm.flood"
MAX_SHELVE_S = 8 * 3600.0  # one shift


class AlarmMonitor(RuleBook, OperatorActions, AlarmQueries):
    """The alarm manager: rules in, ISA-18.2 transitions out."""

    def __init__(self, rules: Iterable[LimitRule] = DEFAULT_LIMITS,
                 flags: Iterable[FlagRule] = (), *, rates: Iterable[RateRule] = (),
                 stale: Iterable[StaleRule] = (), conditions: Iterable[ConditionRule] = (),
                 setpoints: Iterable[SetPoint] = (), gas: Iterable[GasRule] = (),
                 flood_per_minute: int = 10, flood_window_s: float = 60.0,
                 max_shelve_s: float = MAX_SHELVE_S) -> None:
        self._lock = threading.RLock()
        self._listeners = Listeners(self._lock, "alarm listener")
        self._comment_listeners = Listeners(self._lock, "alarm comment listener")
        self.ignored = 0  # non-finite values skipped
        self._entries: dict[str, Entry] = {}
        self._entries: dict[str, Entry] = {}
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


    # ------------------------------------------------------------ listeners
    def add_listener(self, fn: Callable[[Transition], None]) -> None:
        """``fn(transition)`` is called for every transition, from the thread
        that drives the monitor."""
        self._listeners.add(fn)

    def remove_listener(self, fn: Callable[[Transition], None]) -> None:
        self._listeners.remove(fn)

    @property
    def listener_errors(self) -> int:
        """How many times a listener (of transitions or of comments) raised."""
        return self._listeners.errors + self._comment_listeners.errors

    def _emit(self, trs: list[Transition]) -> list[Transition]:
        for tr in trs:  # every transition in the desk's log too
            a = tr.alarm
            log.info("alarm %s %s: %s -> %s (%s%s%s%s) %s", a.key, tr.event.name.lower(),
                     tr.from_state.name, tr.to_state.name, a.priority.name,
                     "" if a.value is None else f", value {a.value}",
                     f", by {tr.user}" if tr.user else "",
                     f", {tr.reason}" if tr.reason else "", a.text)
        self._listeners.call(trs, key=lambda tr: tr.alarm.key)
        return trs

    # ------------------------------------------------------------- entries
    def _entry(self, key: str) -> Entry:
        e = self._entries.get(key)
        if e is None:
            e = self._new_entry(key)
            self._entries[key] = e
        return e

    def _move(self, e: Entry, new: AlarmState, event: AlarmEvent, t: float,
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
            if tr is not None:
                out += self._judged(key, tr.feed(value, t), value, t)
        rt = self._rate_trackers.get(channel)
        if rt is not None:
            flip = rt.feed(value, t)
            out += self._judged(f"{channel}.rate", flip, rt.rate, t)
        out += self._update_setpoints(channel, value, t)
        return out

    def _judged(self, key: str, flip: bool | None, shown: float | None, t: float
                ) -> list[Transition]:
        """After a tracker of ``key`` judged a sample: the alarm shows ``shown`` (the
        value, or the rate of rise) and, if the tracker flipped, raises or clears."""
        e = self._entries.get(key)
        if e is not None:
            e.last_value = shown
        return [] if flip is None else self._condition(key, flip, t, value=shown)

    def _update_setpoints(self, channel: str, value: float, t: float) -> list[Transition]:
        out: list[Transition] = []
        for key, tr in self._setpoints.items():
            if tr.sp.channel == channel:
                out += self._judged(key, tr.feed(value, t), value, t)
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

