"""The operator's (and the control room's) actions on the alarm monitor (no Qt):
acknowledge, comment, shelve and unshelve, out of service and back, and the reset
of a latched set-point.

A mixin of :class:`~app.core.alarms.monitor.AlarmMonitor`: it works on the
monitor's entries under its lock and hands what it did to the monitor's
listeners (``_emit``). An acknowledgement, shelving or unshelving from an OPC UA
client carries its ``origin`` (the client's address) into the archive; a comment
is not a transition and goes to the comment listeners. ISA-18.2 states: see
:mod:`app.core.alarms.model`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Iterable

from app.core.alarms.entry import required_reason
from app.core.alarms.model import Alarm, AlarmEvent, Transition, next_state

log = logging.getLogger("app.core.alarms.monitor")

__all__ = ["OperatorActions"]


def _from(trs: list[Transition], origin: str | None) -> list[Transition]:
    """The transitions with where the user acted from (none given: as they are)."""
    return [dataclasses.replace(tr, origin=origin) for tr in trs] if origin else trs


class OperatorActions:
    """Acknowledge, comment, shelve, out of service and latch reset (mixin)."""

    # ------------------------------------------------------- acknowledgement
    def acknowledge(self, alarm_id: str, t: float, user: str | None = None, *,
                    comment: str | None = None, origin: str | None = None
                    ) -> list[Transition]:
        """Acknowledge one alarm (UNACK → ACKED, RTN_UNACK → NORMAL); anything
        else is left alone and returns []. ``comment`` (kept as the transition's
        reason) and ``origin`` (where the user acted from, e.g. an OPC UA client's
        address) go on record with it."""
        with self._lock:
            trs = _from(self._ack(alarm_id, t, user, comment or None), origin)
        return self._emit(trs)

    def acknowledge_all(self, ids: Iterable[str], t: float, user: str | None = None
                        ) -> list[Transition]:
        with self._lock:
            trs: list[Transition] = []
            for i in list(ids):
                trs += self._ack(i, t, user)
        return self._emit(trs)

    def _ack(self, alarm_id: str, t: float, user: str | None,
             comment: str | None = None) -> list[Transition]:
        e = self._entries.get(alarm_id)
        if e is None:
            return []
        return self._move(e, next_state(e.state, AlarmEvent.ACK, e.active),
                          AlarmEvent.ACK, t, user, comment)

    # -------------------------------------------------------------- comments
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
        log.info("alarm %s comment by %s: %s", alarm_id, user, text)
        self._comment_listeners.call([a], key=lambda a: a.key)
        return a

    def add_comment_listener(self, fn: Callable[[Alarm], None]) -> None:
        """``fn(alarm)`` is called for every comment, from the commenting thread."""
        self._comment_listeners.add(fn)

    def remove_comment_listener(self, fn: Callable[[Alarm], None]) -> None:
        self._comment_listeners.remove(fn)

    # -------------------------------------------------------------- shelving
    def shelve(self, alarm_id: str, t: float, duration_s: float, reason: str,
               user: str | None = None, *, origin: str | None = None) -> list[Transition]:
        """Shelve an alarm for ``duration_s`` (0 < duration ≤ ``max_shelve_s``)
        with a reason; it comes back by itself when the time is up (the monitor's
        ``tick``). Raises ValueError for a bad duration or an empty reason.
        ``origin``: where the user acted from, as for :meth:`acknowledge`."""
        reason = required_reason(reason, "shelving")
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
        return self._emit(_from(trs, origin))

    def unshelve(self, alarm_id: str, t: float, user: str | None = None, *,
                 origin: str | None = None) -> list[Transition]:
        with self._lock:
            trs = self._leave(alarm_id, AlarmEvent.UNSHELVE, t, user)
        return self._emit(_from(trs, origin))

    def _leave(self, alarm_id: str, event: AlarmEvent, t: float, user: str | None,
               reason: str | None = None) -> list[Transition]:
        """Unshelve or return to service (a known alarm only)."""
        e = self._entries.get(alarm_id)
        if e is None:
            return []
        return self._move(e, next_state(e.state, event, e.active), event, t, user, reason)

    # -------------------------------------------------------- out of service
    def set_out_of_service(self, alarm_id: str, on: bool, t: float, reason: str | None = None,
                           user: str | None = None) -> list[Transition]:
        """Take an alarm out of service for maintenance (``on``; a reason is
        required) or put it back (it annunciates again if its condition stands)."""
        with self._lock:
            if not on:
                trs = self._leave(alarm_id, AlarmEvent.RETURN, t, user, reason)
            else:
                reason = required_reason(reason, "out of service")
                e = self._entry(alarm_id)
                new = next_state(e.state, AlarmEvent.REMOVE, e.active)
                trs = []
                if new is not e.state:
                    e.reason = reason
                    trs = self._move(e, new, AlarmEvent.REMOVE, t, user, reason)
        return self._emit(trs)

    # ---------------------------------------------------------------- latches
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
