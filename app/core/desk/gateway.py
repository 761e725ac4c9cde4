"""The one door commands leave the desk by, and the journal of every intent.

A view emits an intent (drive, stop, e-stop, a named command); the
:class:`CommandGateway` hands it to a :class:`CommandSender` (the Qt
``RobotLink`` is one) and journals what became of it:

- ``sent``: the sender took it (with its frame sequence number when known);
- ``refused``: it was never offered to a robot (a replay is view-only, or the
  desk has no link);
- ``not delivered``: the link was down, or the sender failed.

The e-stop's delivery is judged by :class:`~app.core.estop.EstopDelivery`
(sent, acknowledged by the robot, or NOT DELIVERED); the gateway feeds it the
press, the acks and link losses. A drive set-point renewed many times a second
is journaled only when it changes (start, new speed or turn, stop).
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from app.core.estop import EstopDelivery, EstopReport

__all__ = ["CommandGateway", "CommandSender", "JournalEntry", "NOT_DELIVERED", "REFUSED",
           "SENT"]

log = logging.getLogger(__name__)

SENT, REFUSED, NOT_DELIVERED = "sent", "refused", "not delivered"


class CommandSender(Protocol):
    """What the gateway needs of a link (RobotLink has it)."""

    def send_command(self, name: str, args: dict | None = None) -> int: ...
    def send_when_connected(self, name: str, args: dict | None = None) -> None:
        """Send a command as soon as the link is (next) connected, once."""
        if self.link_up:
            self.send(name, args)
        else:
            self._on_connect.append((name, dict(args or {})))

    def drive(self, linear_mps: float, angular_rps: float) -> None: ...
    def stop(self) -> None: ...
    def estop(self) -> int: ...
    def reset_estop(self) -> Any: ...


@dataclass(frozen=True)
class JournalEntry:
    t: float  # UTC epoch seconds
    name: str
    args: dict = field(default_factory=dict)
    outcome: str = SENT
    seq: int | None = None
    why: str = ""
    user: str = ""  # who asked, when not the desk's operator (e.g. "opcua:alice")


class CommandGateway:
    """``journal(entry)`` is called for every intent (the pipeline records it)."""

    def __init__(self, sender: CommandSender | None, *, replay: bool = False,
                 journal: Callable[[JournalEntry], None] | None = None,
                 estop_report: Callable[[EstopReport], None] | None = None,
                 clock: Callable[[], float] = time.time,
                 mono: Callable[[], float] = time.monotonic,
                 ack_timeout_s: float = 2.0) -> None:
        self.sender = sender
        self.replay = replay
        self._journal = journal
        self._estop_report = estop_report
        self._clock, self._mono = clock, mono
        self.estop_delivery = EstopDelivery(ack_timeout_s)
        self.link_up = False
        self.entries: deque[JournalEntry] = deque(maxlen=500)
        self.counts = {SENT: 0, REFUSED: 0, NOT_DELIVERED: 0}
        self.errors = 0  # the sender raised
        self._drive_setpoint = (0.0, 0.0)
        self._on_connect: list[tuple[str, dict]] = []

    # ------------------------------------------------------------ intents
    def send(self, name: str, args: dict | None = None, *, user: str = "") -> JournalEntry:
        """A named command (start_patrol, look_at, request_control, ...); ``user``: who
        asked when it is not the desk's operator (journaled with it)."""
        return self._call(name, dict(args or {}), lambda s: s.send_command(name, args or {}),
                          user)

    def send_when_connected(self, name: str, args: dict | None = None) -> None:
        """Send a command as soon as the link is (next) connected, once."""
        if self.link_up:
            self.send(name, args)
        else:
            self._on_connect.append((name, dict(args or {})))

    def drive(self, linear_mps: float, angular_rps: float) -> JournalEntry | None:
        """The teleop set-point; journaled only when it changes."""
        setpoint = (round(float(linear_mps), 3), round(float(angular_rps), 3))
        return self._setpoint(setpoint, lambda s: s.drive(linear_mps, angular_rps))

    def stop(self) -> JournalEntry | None:
        return self._setpoint((0.0, 0.0), lambda s: s.stop())

    def estop(self, *, user: str = "") -> JournalEntry:
        """The e-stop: offered to the link whatever its state (best effort), reported
        delivered only once the robot acknowledges it, NOT DELIVERED when the link is
        down."""
        self._drive_setpoint = (0.0, 0.0)
        entry = self._call("estop", {}, lambda s: s.estop(), user)
        if entry.outcome != REFUSED:
            self._report(self.estop_delivery.press(entry.outcome == SENT, entry.seq,
                                                   self._clock(), self._mono()))
        return entry

    def reset_estop(self) -> JournalEntry:
        return self._call("reset_estop", {}, lambda s: s.reset_estop())

    # ------------------------------------------------------------ what the robot says
    def on_ack(self, cmd_seq: int, ok: bool, reason: str) -> None:
        self._report(self.estop_delivery.on_ack(cmd_seq, ok, reason, self._clock()))

    def on_link_state(self, state: str) -> None:
        self.link_up = state == "connected"
        if self.link_up and self._on_connect:
            waiting, self._on_connect = self._on_connect, []
            for name, args in waiting:
                self.send(name, args)
        if state in ("lost", "reconnecting", "disconnected"):
            self._report(self.estop_delivery.on_link_down())

    def on_robot_estop(self) -> None:
        self._report(self.estop_delivery.on_robot_estop())

    def tick(self) -> None:
        self._report(self.estop_delivery.tick(self._mono()))

    # ------------------------------------------------------------ internals
    def _setpoint(self, setpoint: tuple[float, float], call: Callable) -> JournalEntry | None:
        if self.replay or self.sender is None:
            if setpoint == (0.0, 0.0):
                return None  # nothing moves in a replay: a stop is no refusal
            return self._note("drive", _drive_args(setpoint), REFUSED, None, self._refusal())
        try:
            call(self.sender)
        except Exception as e:  # a failing link must not take the desk down
            log.exception("drive could not be sent")
            self.errors += 1
            return self._note("drive", _drive_args(setpoint), NOT_DELIVERED, None, str(e))
        if setpoint == self._drive_setpoint:
            return None
        self._drive_setpoint = setpoint
        return self._note("drive", _drive_args(setpoint),
                          SENT if self.link_up else NOT_DELIVERED, None,
                          "" if self.link_up else "link down")

    def _call(self, name: str, args: dict, call: Callable, user: str = "") -> JournalEntry:
        if self.replay or self.sender is None:
            return self._note(name, args, REFUSED, None, self._refusal(), user)
        try:
            seq = call(self.sender)
        except Exception as e:  # a failing link must not take the desk down
            log.exception("%s could not be sent", name)
            self.errors += 1
            return self._note(name, args, NOT_DELIVERED, None, f"{type(e).__name__}: {e}",
                              user)
        seq = seq if isinstance(seq, int) and seq >= 0 else None
        if not self.link_up:
            return self._note(name, args, NOT_DELIVERED, seq, "link down", user)
        return self._note(name, args, SENT, seq, "", user)

    def _refusal(self) -> str:
        return "replay is view-only" if self.replay else "no link"

    def _note(self, name: str, args: dict, outcome: str, seq: int | None,
              why: str, user: str = "") -> JournalEntry:
        entry = JournalEntry(self._clock(), name, args, outcome, seq, why, user)
        self.entries.append(entry)
        self.counts[outcome] += 1
        if self._journal is not None:
            self._journal(entry)
        return entry

    def _report(self, report: EstopReport | None) -> None:
        if report is not None and self._estop_report is not None:
            self._estop_report(report)


def _drive_args(setpoint: tuple[float, float]) -> dict[str, Any]:
    return {"linear_mps": setpoint[0], "angular_rps": setpoint[1]}
