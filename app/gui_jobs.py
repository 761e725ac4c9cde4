"""Jobs run off the GUI thread for one Qt object, their results handed back on it.

``GuiJobs(owner)`` is a child of ``owner`` with two children of its own, made in
this order: a one-thread ``QThreadPool`` and a carrier object the job emits its
result on. ``start(job, done, failed)`` runs ``job()`` on the pool; ``done(result)``
(or ``failed(exception)``) is then called queued, on the thread ``owner`` lives in
(the GUI thread), between two events.

Why the order matters: a QObject deletes its children in the order they were
made, and a pool's destructor waits for its jobs. Deleted with its owner (a
window closed while a query runs), the pool goes first and waits for the job,
which emits on a carrier that is still there; the carrier goes next, taking the
queued result with it, so nothing is delivered to an owner that is gone and
nothing is emitted on a deleted object from the pool's thread. The carrier has a
parent, so no thread letting go of a Python reference to it can delete it
(app/gui_gc: Qt objects die on the GUI thread).

The callbacks stay on the GUI thread (kept here by a ticket; the pool's thread
sees only the job and the ticket), so the job's thread never holds the last
reference to the owner. A job itself must not hold the owner either: give it the
data it works on.
"""

from __future__ import annotations

import functools
import itertools
import logging
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, Qt, QThreadPool, Signal

__all__ = ["GuiJobs"]

log = logging.getLogger(__name__)


class _Carrier(QObject):
    """Carries a job's outcome from the pool's thread to the owner's (queued)."""

    finished = Signal(int, bool, object)  # ticket, ok, result or exception


def _run(job: Callable[[], Any], ticket: int, carrier: _Carrier) -> None:
    try:
        result = job()
    except Exception as e:  # handed to the GUI thread, never raised in the pool's
        carrier.finished.emit(ticket, False, e)
        return
    carrier.finished.emit(ticket, True, result)


class GuiJobs(QObject):
    """``GuiJobs(owner)``: ``owner``'s own one-thread pool; results come back queued."""

    def __init__(self, owner: QObject) -> None:
        super().__init__(owner)
        self.pool = QThreadPool(self)  # first: deleted first, waiting for its jobs
        self.pool.setMaxThreadCount(1)
        self._carrier = _Carrier(self)  # after: still there while the pool waits
        self._carrier.finished.connect(self._deliver, Qt.ConnectionType.QueuedConnection)
        self._tickets = itertools.count(1)
        self._pending: dict[int, tuple[Any, Any]] = {}  # ticket -> (done, failed)

    def start(self, job: Callable[[], Any], done: Callable[[Any], Any] | None = None,
              failed: Callable[[BaseException], Any] | None = None) -> None:
        """Run ``job()`` on the pool; then ``done(result)`` on this object's thread,
        or ``failed(exception)`` if it raised (logged when ``failed`` is None)."""
        ticket = next(self._tickets)
        self._pending[ticket] = (done, failed)
        self.pool.start(functools.partial(_run, job, ticket, self._carrier))

    def wait(self, timeout_ms: int = -1) -> bool:
        """Wait for the jobs started (their results are delivered later, queued)."""
        return self.pool.waitForDone(timeout_ms)

    @property
    def busy(self) -> bool:
        """A job started whose outcome has not been delivered yet."""
        return bool(self._pending)

    def _deliver(self, ticket: int, ok: bool, value: Any) -> None:
        done, failed = self._pending.pop(ticket, (None, None))
        if ok:
            if done is not None:
                done(value)
        elif failed is not None:
            failed(value)
        else:
            log.error("a background job failed", exc_info=(type(value), value,
                                                           value.__traceback__))
