"""Python's cyclic garbage collector runs on the GUI thread only (the window's and the
headless desk's: the thread of the Qt application's event loop).

The collector starts itself in whichever thread happens to allocate when its
counts pass the thresholds: the archive writer, a thread-pool job, the link
thread. A window, a model or a plot item owned by Python (no Qt parent) and
caught in a reference cycle is deleted by that collection, on that thread: its
C++ destructor (timers, connections, scene items, child widgets) runs there
while the GUI thread paints, delivers events or fires timers on the same
objects — a segmentation fault inside the event loop, rarely, at any time.
(Shiboken lets go of the GIL while it runs a C++ destructor, so the GUI thread
really does run beside it.)

:func:`collect_on_gui_thread` turns automatic collection off and has a timer on
the GUI thread do the same work: every ``interval_ms`` it collects the oldest
generation whose count passed its threshold, as CPython would have
(``gc.get_threshold``). No other thread ever collects, so every such object dies
on the GUI thread, between two events.

What the collector cannot see: a Qt connection holds its slot (a lambda, a
closure, a partial) from C++. A slot on a longer-lived sender (a link, a model)
that refers to a window keeps the window, and all it refers to, alive for the
sender's life; if the slot refers to the sender too, for ever.
:func:`connect_for_life` connects such slots and undoes them when their owner
is deleted; the slots should hold the owner weakly (``weakref.ref``) so that an
owner with no parent can still go with its last Python reference.
"""

from __future__ import annotations

import functools
import gc
from typing import Any

from PySide6.QtCore import QCoreApplication, QObject, QThread, QTimer

__all__ = ["GuiCollector", "collect_on_gui_thread", "connect_for_life", "disconnect_all"]


class GuiCollector(QObject):
    """Automatic collection off; :meth:`collect_due` on a GUI-thread timer."""

    def __init__(self, parent: QObject | None = None, *, interval_ms: int = 100) -> None:
        super().__init__(parent)
        if QThread.currentThread() is not QCoreApplication.instance().thread():
            raise RuntimeError("the garbage collector's timer must run on the GUI thread")
        self.thresholds = gc.get_threshold()
        self.collections = [0, 0, 0]  # by generation
        gc.disable()
        self._timer = QTimer(self)
        self._timer.setInterval(int(interval_ms))
        self._timer.timeout.connect(self.collect_due)
        self._timer.start()

    def collect_due(self) -> int:
        """Collect the oldest generation whose count passed its threshold (none when
        the youngest's did not); returns how many objects were unreachable."""
        counts = gc.get_count()
        if counts[0] <= self.thresholds[0]:
            return 0
        gen = max(i for i in range(3) if counts[i] > self.thresholds[i])
        self.collections[gen] += 1
        return gc.collect(gen)

    def stop(self) -> None:
        """Back to automatic collection (the timer stops)."""
        self._timer.stop()
        gc.enable()


def collect_on_gui_thread(app: QCoreApplication | None = None, *,
                          interval_ms: int = 100) -> GuiCollector:
    """The application's collector (made once, a child of ``app``; call on the GUI
    thread once the application exists)."""
    app = app or QCoreApplication.instance()
    if app is None:
        raise RuntimeError("no Qt application yet")
    found = app.findChild(GuiCollector)
    if found is not None:
        gc.disable()
        found._timer.start()
        return found
    return GuiCollector(app, interval_ms=interval_ms)


def disconnect_all(links: list[tuple[Any, Any]], *_: Any) -> None:
    """Undo each ``(signal, slot)`` connection of ``links`` (those whose sender is
    gone already are skipped) and empty the list."""
    for signal, slot in links:
        try:
            signal.disconnect(slot)
        except (RuntimeError, TypeError):  # already gone with its sender
            pass
    links.clear()


def connect_for_life(owner: QObject, pairs: list[tuple[Any, Any]]) -> list[tuple[Any, Any]]:
    """Connect each ``(signal, slot)`` of ``pairs``; all are undone when ``owner`` is
    deleted. Returns the list of connections (for :func:`disconnect_all` earlier)."""
    links: list[tuple[Any, Any]] = []
    for signal, slot in pairs:
        signal.connect(slot)
        links.append((signal, slot))
    owner.destroyed.connect(functools.partial(disconnect_all, links))
    return links
