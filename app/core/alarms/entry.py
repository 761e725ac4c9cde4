"""What the alarm monitor keeps per alarm, and its listener lists (no Qt).

:class:`Entry` is the monitor's mutable record of one alarm; :meth:`Entry.snapshot`
gives the immutable :class:`~app.core.alarms.model.Alarm` that leaves the monitor.
:class:`Listeners` holds the callables the monitor calls back (transitions,
comments): a listener's failure is logged and counted, never passed on.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

from app.core.alarms.model import Alarm, AlarmState, Priority

log = logging.getLogger("app.core.alarms.monitor")  # the desk's log names the monitor


@dataclass
class Entry:
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


def required_reason(reason: str | None, what: str) -> str:
    """``reason`` stripped; ValueError when there is none (shelving, out of service)."""
    if not isinstance(reason, str) or not reason.strip():
        raise ValueError(f"{what} needs a reason")
    return reason.strip()


class Listeners:
    """Callables called back with one argument; ``errors`` counts those that raised.

    Adding and removing take the owner's lock; :meth:`call` takes a copy under it
    and calls outside it, so a listener may call back into the owner."""

    def __init__(self, lock, what: str) -> None:
        self._lock = lock
        self._fns: list[Callable] = []
        self.what = what  # "alarm listener", "alarm comment listener": for the log
        self.errors = 0

    def add(self, fn: Callable) -> None:
        with self._lock:
            if fn not in self._fns:
                self._fns.append(fn)

    def remove(self, fn: Callable) -> None:
        with self._lock:
            if fn in self._fns:
                self._fns.remove(fn)

    def call(self, items: list, key: Callable[[object], str]) -> None:
        """Each listener with each of ``items`` in turn (``key`` names an item in the log)."""
        if not items:
            return
        with self._lock:
            fns = list(self._fns)
        for item in items:
            for fn in fns:
                try:
                    fn(item)
                except Exception:  # a listener's failure must not stop the alarms
                    self.errors += 1
                    log.exception("%s %r failed on %s", self.what, fn, key(item))
