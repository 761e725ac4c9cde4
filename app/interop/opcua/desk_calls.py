"""The control room's calls as the desk runs them, on the desk's thread: the OPC UA
server (in its own process) has checked the caller's role; here the desk checks that it
holds the robot's control lease, sends the command through its gateway (journaled with
``opcua:<user>``), and acknowledges, comments on, shelves and unshelves its alarms on
its alarm monitor with who and where from (all in the archive).

Each call answers with plain values (they go back over the pipe):

=============  ======================================================================
``command``    ``(outcome, why, seq)``: the journal entry's, or ``("no lease", …)``
``acknowledge``  True when the alarm was acknowledged (False: nothing to acknowledge)
``comment``    the time of the comment (UTC epoch seconds)
``shelve``     ``("shelved", "<n> s")``, ``("already shelved", "")``, ``("out of range",
               why)``
``unshelve``   True when it was shelved
``service``    True when the alarm was taken out of service (``out``) or put back
=============  ======================================================================

An alarm shelved by the control room's OneShotShelve is unshelved here as soon as its
condition clears (:meth:`DeskCalls.end_one_shots`, from the desk's drain).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from app.core.alarms import AlarmState

__all__ = ["DeskCalls"]

log = logging.getLogger(__name__)


class DeskCalls:
    """``pipeline``: the desk pipeline; ``lease_mine()``: whether the desk holds the
    robot's control lease now."""

    def __init__(self, pipeline: Any, lease_mine: Callable[[], bool]) -> None:
        self.pipe = pipeline
        self.lease_mine = lease_mine
        self.one_shot: dict[str, str] = {}  # shelved by OneShotShelve: key -> who

    def run(self, op: str, kw: dict[str, Any]) -> Any:
        fn = {"command": self.command, "acknowledge": self.acknowledge,
              "comment": self.comment, "shelve": self.shelve,
              "unshelve": self.unshelve, "service": self.service}.get(op)
        if fn is None:
            raise ValueError(f"no desk call {op!r}")
        return fn(**kw)

    def command(self, command: str, user: str) -> tuple[str, str, int | None]:
        if not self.lease_mine():
            return "no lease", "the desk does not hold the control lease", None
        gateway = self.pipe.gateway
        entry = gateway.estop(user=user) if command == "estop" else \
            gateway.send(command, {}, user=user)
        return str(entry.outcome), str(entry.why), entry.seq

    def acknowledge(self, key: str, user: str, comment: str, origin: str) -> bool:
        pipe = self.pipe
        return bool(pipe.monitor.acknowledge(key, pipe.alarm_time(), user=user,
                                             comment=comment, origin=origin))

    def comment(self, key: str, user: str, origin: str, text: str) -> float:
        pipe = self.pipe
        t = pipe.alarm_time()
        if pipe.record is not None:
            pipe.record.event("alarm_comment", t, alarm=key, user=user, origin=origin,
                              comment=text)
        pipe.monitor.comment(key, t, text, user=user)
        return t

    def shelve(self, key: str, seconds: float | None, one_shot: bool, user: str,
               origin: str) -> tuple[str, str]:
        monitor = self.pipe.monitor
        a = monitor.get(key)
        if a is not None and a.state is AlarmState.SHELVED:
            return "already shelved", ""
        if seconds is None:  # one-shot: the desk's longest, ended when the alarm clears
            seconds = monitor.max_shelve_s
            reason = "one-shot shelve from the control room (OPC UA), until the alarm clears"
        else:
            reason = "timed shelve from the control room (OPC UA)"
        try:
            trs = monitor.shelve(key, self.pipe.alarm_time(), seconds, reason, user=user,
                                 origin=origin)
        except ValueError as e:  # a duration the desk does not allow
            return "out of range", str(e)
        if not trs:
            return "already shelved", ""
        if one_shot:
            self.one_shot[key] = user
        return "shelved", f"{seconds:.0f} s"

    def unshelve(self, key: str, user: str, origin: str) -> bool:
        pipe = self.pipe
        done = bool(pipe.monitor.unshelve(key, pipe.alarm_time(), user=user, origin=origin))
        if done:
            self.one_shot.pop(key, None)
        return done

    def service(self, key: str, out: bool, user: str, origin: str) -> bool:
        """Take the alarm out of service (``out``) or put it back; False when it is so
        already. The reason names where from (the archive has it with the user)."""
        monitor = self.pipe.monitor
        a = monitor.get(key)
        is_out = a is not None and a.state is AlarmState.OUT_OF_SERVICE
        if is_out == out:
            return False
        reason = (f"disabled from the control room (OPC UA, {origin or 'unknown origin'})"
                  if out else None)
        return bool(monitor.set_out_of_service(key, out, self.pipe.alarm_time(), reason,
                                               user=user))

    def end_one_shots(self) -> None:
        """Unshelve each alarm shelved by OneShotShelve whose condition has cleared;
        forget those no longer shelved."""
        if not self.one_shot:
            return
        monitor = self.pipe.monitor
        for key in list(self.one_shot):
            a = monitor.get(key)
            if a is None or a.state is not AlarmState.SHELVED:
                self.one_shot.pop(key, None)
            elif not a.active:
                self.one_shot.pop(key, None)
                log.info("OPC UA: alarm %s cleared: its one-shot shelving ends", key)
                monitor.unshelve(key, self.pipe.alarm_time())
