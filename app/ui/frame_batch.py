"""Coalesced: a slot that shows only the newest of the messages that came together.

The link's thread hands messages to the GUI thread as queued calls; when the
desk's process was not scheduled for a while (a loaded machine), or the robot
sends in bursts, several telemetry samples, poses and frames wait in the queue
and are delivered in one pass of the event loop. Every message still goes
through the desk pipeline (series, alarms, archive: nothing is dropped there),
but a view needs to show only the newest: a ``Coalesced(fn)`` slot keeps the
arguments of its latest call and calls ``fn`` with them once, from a zero-time
timer that runs after the queued messages of that pass (``interval_ms`` > 0
waits longer). Views of values (tiles, the status bar's pose) update once per
pass instead of once per message; the counts say how many calls were saved.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, QTimer

__all__ = ["Coalesced"]


class Coalesced(QObject):
    def __init__(self, fn: Callable[..., Any], parent: QObject | None = None, *,
                 interval_ms: int = 0) -> None:
        super().__init__(parent)
        self._fn = fn
        self._args: tuple | None = None
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(max(0, int(interval_ms)))
        self._timer.timeout.connect(self.flush)
        self.received = 0  # calls of the slot
        self.shown = 0  # calls of ``fn``

    def __call__(self, *args: Any) -> None:
        self._args = args
        self.received += 1
        if not self._timer.isActive():
            self._timer.start()

    take = __call__  # a plain method to connect a signal to

    @property
    def pending(self) -> bool:
        return self._args is not None

    def flush(self) -> None:
        """Call ``fn`` with the newest arguments now (nothing when none waits)."""
        self._timer.stop()
        if self._args is None:
            return
        args, self._args = self._args, None
        self.shown += 1
        self._fn(*args)
