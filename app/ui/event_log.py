"""The event log under the alarm list: one line per event (time, level, source,
text), newest last, in the desk's language.

Alarm transitions, operator and control-room commands, robot and link events
reach it through :meth:`EventLog.add`. It keeps its newest lines only (see
``EVENT_LOG_LINES``); everything in it is also in the archive and the log file.

It is a list view over a string model, not a text editor: a QPlainTextEdit keeps
each line laid out, about 7.5 KiB a line (3.8 MB for 500 lines, measured with
PySide6 6.11 offscreen), which a desk grew into over its first minutes of events;
a list row costs about 0.25 KiB, and only the visible rows are ever laid out.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from datetime import datetime

from PySide6.QtCore import QStringListModel, Qt
from PySide6.QtGui import QPainter
from PySide6.QtWidgets import QAbstractItemView, QListView, QWidget

from app.core.i18n import QT_TRANSLATE_NOOP, translate

__all__ = ["EVENT_LOG_LINES", "EventLog", "clock_text", "source_text"]

# The event log keeps its newest lines only. Alarm transitions, commands and robot
# events are also in the archive (the History window shows them) and the log file.
EVENT_LOG_LINES = 500

_LOG_MARKS = {"alarm": QT_TRANSLATE_NOOP("EventLog", "ALARM"),
              "warning": QT_TRANSLATE_NOOP("EventLog", "WARN"),
              "error": QT_TRANSLATE_NOOP("EventLog", "ERROR"),
              "info": QT_TRANSLATE_NOOP("EventLog", "info")}
_LOG_SOURCES = {"desk": QT_TRANSLATE_NOOP("EventLog", "desk"),
                "robot": QT_TRANSLATE_NOOP("EventLog", "robot"),
                "link": QT_TRANSLATE_NOOP("EventLog", "link"),
                "alarm": QT_TRANSLATE_NOOP("EventLog", "alarm"),
                "meter": QT_TRANSLATE_NOOP("EventLog", "meter"),
                "alarms": QT_TRANSLATE_NOOP("EventLog", "alarms"),
                "control": QT_TRANSLATE_NOOP("EventLog", "control"),
                "replay": QT_TRANSLATE_NOOP("EventLog", "replay")}


def source_text(source: str) -> str:
    """An alarm or log source in the desk's language (a channel keeps its key: a tag)."""
    if source in _LOG_SOURCES:
        return translate("EventLog", _LOG_SOURCES[source])
    return source



def clock_text(t: float | None) -> str:
    """Local time of day of a UTC epoch time, for the operator."""
    if t is None or t != t:
        return ""
    return datetime.fromtimestamp(t).strftime("%H:%M:%S")


class _Lines(QStringListModel):
    """The log's lines; a line's tooltip is the line itself (read in full where the
    pane is narrower than the line: rows do not wrap)."""

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if role == Qt.ItemDataRole.ToolTipRole:
            role = Qt.ItemDataRole.DisplayRole
        return super().data(index, role)


class EventLog(QListView):
    """A read-only log of the newest ``max_lines`` events, one row each."""

    def __init__(self, parent: QWidget | None = None, *,
                 max_lines: int = EVENT_LOG_LINES) -> None:
        super().__init__(parent)
        if max_lines < 1:
            raise ValueError(f"max_lines must be >= 1, got {max_lines}")
        self.max_lines = int(max_lines)
        self._model = _Lines(self)
        self.setModel(self._model)
        self.setObjectName("eventLog")
        self.setUniformItemSizes(True)  # rows are laid out only as they are shown
        self.setWordWrap(False)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionMode(QAbstractItemView.SelectionMode.NoSelection)
        self.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self._placeholder = ""
        self._clock: Callable[[], float] = time.time
        # as a text log: while at the end, stay at the end as lines come (the view
        # lays new rows out later, so the scroll range grows after add returns)
        self._follow = True
        self.verticalScrollBar().rangeChanged.connect(self._keep_end)

    def set_clock(self, clock: Callable[[], float]) -> None:
        """Where a line without its own time gets its stamp (default: the wall
        clock; a replay: its position in the recording)."""
        self._clock = clock

    def add(self, level: str, source: str, text: str, t: float | None = None) -> None:
        """One line: ``level`` alarm / warning / error / info, ``source`` a known
        source (desk, robot, link, …; shown translated) or any other name."""
        stamp = clock_text(self._clock() if t is None else t)
        mark = translate("EventLog", _LOG_MARKS.get(level, _LOG_MARKS["info"]))
        source = translate("EventLog", _LOG_SOURCES.get(source, source))
        bar = self.verticalScrollBar()
        self._follow = bar.value() >= bar.maximum()
        m = self._model
        n = m.rowCount()
        m.insertRows(n, 1)
        m.setData(m.index(n), f"{stamp}  {mark:<5}  {source:<6}  {text}")
        if n + 1 > self.max_lines:
            m.removeRows(0, n + 1 - self.max_lines)
        if self._follow:
            self.scrollToBottom()

    def _keep_end(self, _lo: int, hi: int) -> None:
        if self._follow:
            self.verticalScrollBar().setValue(hi)

    def lines(self) -> list[str]:
        return self._model.stringList()

    def line_count(self) -> int:
        return self._model.rowCount()

    def toPlainText(self) -> str:  # noqa: N802 - the text editor's name, kept for callers
        return "\n".join(self.lines())

    def clear(self) -> None:
        self._model.setStringList([])

    def setPlaceholderText(self, text: str) -> None:  # noqa: N802 - as QPlainTextEdit's
        """Text shown, dimmed, while the log is empty."""
        self._placeholder = text
        self.viewport().update()

    def placeholderText(self) -> str:  # noqa: N802
        return self._placeholder

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().paintEvent(event)
        if self._placeholder and not self._model.rowCount():
            p = QPainter(self.viewport())
            p.setPen(self.palette().placeholderText().color())
            p.drawText(self.viewport().rect().adjusted(4, 2, -4, -2),
                       Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop,
                       self._placeholder)
            p.end()
