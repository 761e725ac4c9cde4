"""Whether the operator's e-stop reached the robot.

Pressing EMERGENCY STOP is not the same as the robot stopping. The desk says
what happened, in the operator's words:

- the link is up and the robot acknowledges the command (its ack names the
  command's frame sequence number): "E-stop sent 15:17:21, acknowledged by the
  robot at 15:17:21";
- the link is down when the button is pressed, drops before the ack, the robot
  refuses the command, or no ack comes within ``ack_timeout_s``: "E-STOP NOT
  DELIVERED — …: use the robot's own stop", raised as an alarm.

:class:`EstopDelivery` only keeps the book (no Qt, no sockets); the window
feeds it the press, the link's acks and state, and a clock tick, and shows the
:class:`EstopReport` it returns. The alarm (``ALARM_ID``) returns to normal
when a later e-stop is acknowledged or the robot reports its e-stop engaged.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from app.core.i18n import QT_TRANSLATE_NOOP, translate

__all__ = ["ALARM_ID", "EstopDelivery", "EstopReport", "NOT_DELIVERED", "clock_text"]

ALARM_ID = "desk.estop_not_delivered"
NOT_DELIVERED = QT_TRANSLATE_NOOP("Estop", "E-STOP NOT DELIVERED")
OWN_STOP = QT_TRANSLATE_NOOP("Estop", "use the robot's own stop")


def clock_text(wall_s: float) -> str:
    """``HH:MM:SS`` of a wall-clock time, in the desk's local time."""
    return datetime.fromtimestamp(wall_s).strftime("%H:%M:%S")


@dataclass(frozen=True)
class EstopReport:
    """What to tell the operator. ``status``: sent (waiting for the ack),
    acknowledged, or not_delivered; ``alarm``: the not-delivered alarm is
    active (True), returns to normal (False), or is left as it is (None)."""

    status: str
    text: str
    alarm: bool | None

    @property
    def delivered(self) -> bool:
        return self.status == "acknowledged"


@dataclass
class _Pending:
    seq: int | None
    sent_wall: float
    sent_mono: float


class EstopDelivery:
    """The book of e-stops sent and acknowledged (one pending at a time: a
    second press while waiting replaces the first, whose ack still counts)."""

    def __init__(self, ack_timeout_s: float = 2.0) -> None:
        self.ack_timeout_s = float(ack_timeout_s)
        self.pending: _Pending | None = None
        # e-stops still unanswered (replaced or late): sequence number -> time sent
        self._earlier: dict[int, float] = {}
        self.last: EstopReport | None = None
        self.sent = 0
        self.acknowledged = 0
        self.not_delivered = 0

    # ------------------------------------------------------------ inputs
    def press(self, link_up: bool, seq: int | None, wall_s: float,
              mono_s: float) -> EstopReport:
        """The operator pressed e-stop; ``link_up``: the link was connected and the
        command went to it (``seq``: its frame sequence number, when known)."""
        if not link_up:
            self.pending = None
            return self._not_delivered(translate("Estop", "link down"))
        self._set_aside()
        self.pending = _Pending(seq, wall_s, mono_s)
        self.sent += 1
        return self._report("sent", translate(
            "Estop", "E-stop sent {time} — waiting for the robot's acknowledgement").format(
            time=clock_text(wall_s)), None)

    def on_ack(self, cmd_seq: int, ok: bool, reason: str, wall_s: float) -> EstopReport | None:
        """The robot's answer to a command; None when it is not about an e-stop."""
        p = self.pending
        ours = p is not None and (p.seq is None or p.seq == cmd_seq)
        if not ours and cmd_seq not in self._earlier:
            return None
        sent = self._earlier.pop(cmd_seq, wall_s)
        if ours and p is not None:
            sent = p.sent_wall
            self.pending = None
        if not ok:
            return self._not_delivered(translate("Estop", "refused by the robot ({why})").format(
                why=reason or translate("Estop", "no reason given")))
        self.acknowledged += 1
        return self._report("acknowledged", translate(
            "Estop", "E-stop sent {sent}, acknowledged by the robot at {acked}").format(
            sent=clock_text(sent), acked=clock_text(wall_s)), False)

    def on_link_down(self) -> EstopReport | None:
        """The link dropped: an e-stop still waiting for its ack was not delivered."""
        if self.pending is None:
            return None
        self.pending = None  # its ack cannot come on this connection
        return self._not_delivered(translate("Estop", "link lost before the robot acknowledged"))

    def on_robot_estop(self) -> EstopReport | None:
        """The robot reports its e-stop engaged: whatever stopped it, it is stopped."""
        if self.last is None or self.last.status != "not_delivered":
            return None
        return self._report("not_delivered", self.last.text + translate(
            "Estop", " (the robot now reports its e-stop engaged)"), False)

    def tick(self, mono_s: float) -> EstopReport | None:
        """Call now and then: an ack that did not come in time means not delivered."""
        p = self.pending
        if p is None or mono_s - p.sent_mono < self.ack_timeout_s:
            return None
        self._set_aside()  # a late ack still counts
        return self._not_delivered(translate(
            "Estop", "no acknowledgement from the robot within {s} s").format(
            s=f"{self.ack_timeout_s:g}"))

    # ------------------------------------------------------------ internals
    def _set_aside(self) -> None:
        p = self.pending
        if p is not None and p.seq is not None:
            self._earlier[p.seq] = p.sent_wall
            while len(self._earlier) > 16:  # keep the book small
                self._earlier.pop(next(iter(self._earlier)))
        self.pending = None

    def _not_delivered(self, why: str) -> EstopReport:
        self.not_delivered += 1
        return self._report("not_delivered", f"{translate('Estop', NOT_DELIVERED)} — {why}: "
                                             f"{translate('Estop', OWN_STOP)}", True)

    def _report(self, status: str, text: str, alarm: bool | None) -> EstopReport:
        self.last = EstopReport(status, text, alarm)
        return self.last
