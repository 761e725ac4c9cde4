"""The window's side of e-stop delivery: a thin Qt adapter over
:class:`app.core.estop.EstopDelivery`.

It feeds the book the operator's press, the robot's acks and the link's state,
runs the acknowledgement timer on the GUI thread, and announces every
:class:`~app.core.estop.EstopReport` as ``reported``; the window shows it (the
control panel's line, the status bar, the event log, the alarm).
"""

from __future__ import annotations

import time

from PySide6.QtCore import QObject, QTimer, Signal

from app.core.estop import EstopDelivery, EstopReport

__all__ = ["EstopReporter"]


class EstopReporter(QObject):
    reported = Signal(object)  # EstopReport

    def __init__(self, parent: QObject | None = None, *, ack_timeout_s: float = 2.0) -> None:
        super().__init__(parent)
        self.book = EstopDelivery(ack_timeout_s)
        self._timer = QTimer(self)
        self._timer.setInterval(200)
        self._timer.timeout.connect(self._tick)

    def pressed(self, link_up: bool, seq: int | None) -> None:
        """The e-stop went to the link (``link_up``) as frame ``seq``, or could not."""
        self._emit(self.book.press(link_up, seq, time.time(), time.monotonic()))
        if self.book.pending is not None:
            self._timer.start()

    def on_ack(self, cmd_seq: int, ok: bool, reason: str) -> None:
        self._emit(self.book.on_ack(cmd_seq, ok, reason, time.time()))

    def on_link_state(self, state: str) -> None:
        if state != "connected":
            self._emit(self.book.on_link_down())

    def on_robot_estop(self) -> None:
        self._emit(self.book.on_robot_estop())

    def _tick(self) -> None:
        self._emit(self.book.tick(time.monotonic()))
        if self.book.pending is None:
            self._timer.stop()

    def _emit(self, report: EstopReport | None) -> None:
        if report is not None:
            self.reported.emit(report)
