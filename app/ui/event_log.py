"""The event log under the alarm list: one line per event (time, level, source,
text), newest last, in the desk's language.

Alarm transitions, operator and control-room commands, robot and link events
reach it through :meth:`EventLog.add`. It keeps its newest lines only (see
``EVENT_LOG_LINES``); everything in it is also in the archive and the log file.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from datetime import datetime

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QPlainTextEdit, QWidget

from app.core.i18n import QT_TRANSLATE_NOOP, translate

__all__ = ["EVENT_LOG_LINES", "EventLog", "clock_text", "source_text"]

# The event log keeps its newest lines only: each line of a QPlainTextEdit costs about
# 7 KiB once laid out (measured with PySide6 6.x, offscreen), so 2000 lines were 15 MB
# that a desk left running for days grew into. Alarm transitions, commands and robot
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


class EventLog(QPlainTextEdit):
    """A read-only log of the newest ``max_lines`` events."""

    def __init__(self, parent: QWidget | None = None, *,
                 max_lines: int = EVENT_LOG_LINES) -> None:
        super().__init__(parent)
        self.setReadOnly(True)
        self.setMaximumBlockCount(max_lines)
        self.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self._clock: Callable[[], float] = time.time

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
        self.appendPlainText(f"{stamp}  {mark:<5}  {source:<6}  {text}")

    def lines(self) -> list[str]:
        return self.toPlainText().splitlines()
