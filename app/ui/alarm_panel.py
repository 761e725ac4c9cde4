"""Alarm panel: the list of alarms (a row per alarm; greyed when it clears) and
the event log (robot events, link state changes, command answers)."""

from __future__ import annotations

import time
from datetime import datetime

from PySide6.QtCore import Qt
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPlainTextEdit,
    QPushButton,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.alarms import Alarm
from app.ui import theme

COLUMNS = ("Time", "Priority", "Source", "Condition", "Value", "Limit", "State")
MAX_CLEARED_ROWS = 200


def clock_text(t: float | None) -> str:
    """Local time of day of a UTC epoch time, for the operator."""
    if t is None:
        return ""
    return datetime.fromtimestamp(t).strftime("%H:%M:%S")


class AlarmPanel(QWidget):
    def __init__(self, parent: QWidget | None = None, *, max_log_lines: int = 2000) -> None:
        super().__init__(parent)
        self.table = QTableWidget(0, len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        hh = self.table.horizontalHeader()
        hh.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        hh.setStretchLastSection(True)
        self.count_label = QLabel("no active alarms", self)
        self.remove_button = QPushButton("Remove cleared  (Ctrl+L)", self)
        self.remove_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.remove_button.clicked.connect(self.remove_cleared)

        self.log = QPlainTextEdit(self)
        self.log.setReadOnly(True)
        self.log.setMaximumBlockCount(max_log_lines)
        self.log.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.log.setPlaceholderText("event log")

        left = QWidget(self)
        ll = QVBoxLayout(left)
        ll.setContentsMargins(0, 0, 0, 0)
        head = QHBoxLayout()
        head.addWidget(self.count_label, 1)
        head.addWidget(self.remove_button)
        ll.addLayout(head)
        ll.addWidget(self.table, 1)
        right = QWidget(self)
        rl = QVBoxLayout(right)
        rl.setContentsMargins(0, 0, 0, 0)
        rl.addWidget(QLabel("Event log", self))
        rl.addWidget(self.log, 1)
        split = QSplitter(Qt.Orientation.Horizontal, self)
        split.addWidget(left)
        split.addWidget(right)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(split)

    # --------------------------------------------------------------- alarms
    def _row_of(self, key: str) -> int:
        for r in range(self.table.rowCount()):
            item = self.table.item(r, 0)
            if item is not None and item.data(Qt.ItemDataRole.UserRole) == key \
                    and self.table.item(r, 6).text() == "ACTIVE":
                return r
        return -1

    def add_alarm(self, alarm: Alarm) -> None:
        """A new alarm: a row at the top, coloured by priority."""
        if self._row_of(alarm.key) >= 0:
            self.update_alarm(alarm)
            return
        self.table.insertRow(0)
        unit = f" {alarm.unit}" if alarm.unit else ""
        cells = (clock_text(alarm.raised_t), alarm.priority.name, alarm.label or alarm.source,
                 alarm.condition, self._value_text(alarm),
                 "" if alarm.limit is None else f"{alarm.limit:g}{unit}", "ACTIVE")
        for c, text in enumerate(cells):
            item = QTableWidgetItem(text)
            item.setData(Qt.ItemDataRole.UserRole, alarm.key)
            item.setToolTip(alarm.text)
            self.table.setItem(0, c, item)
        color = theme.color_of(alarm.priority)
        if color:
            pri = self.table.item(0, 1)
            pri.setBackground(QBrush(QColor(color)))
            pri.setForeground(QBrush(QColor(theme.LEVEL_TEXT[theme.level_of(alarm.priority)])))
        self._update_count()

    def update_alarm(self, alarm: Alarm) -> None:
        r = self._row_of(alarm.key)
        if r >= 0:
            self.table.item(r, 4).setText(self._value_text(alarm))

    def clear_alarm(self, alarm: Alarm) -> None:
        """The alarm returned to normal: its row stays, greyed, until removed."""
        r = self._row_of(alarm.key)
        if r < 0:
            return
        self.table.item(r, 6).setText(f"cleared {clock_text(alarm.cleared_t or time.time())}")
        self.table.item(r, 4).setText(self._value_text(alarm))
        grey = QBrush(QColor(theme.TEXT_DIM))
        for c in range(self.table.columnCount()):
            item = self.table.item(r, c)
            item.setForeground(grey)
            item.setBackground(QBrush())
        self._prune()
        self._update_count()

    @staticmethod
    def _value_text(alarm: Alarm) -> str:
        if alarm.limit is None:
            return "set" if alarm.active else "clear"
        v = alarm.last_value if alarm.last_value is not None else alarm.value
        unit = f" {alarm.unit}" if alarm.unit else ""
        return f"{v:.2f}{unit}"

    def remove_cleared(self) -> None:
        for r in reversed(range(self.table.rowCount())):
            if self.table.item(r, 6).text() != "ACTIVE":
                self.table.removeRow(r)
        self._update_count()

    def _prune(self) -> None:
        cleared = [r for r in range(self.table.rowCount())
                   if self.table.item(r, 6).text() != "ACTIVE"]
        for r in reversed(cleared[MAX_CLEARED_ROWS:]):
            self.table.removeRow(r)

    def active_count(self) -> int:
        return sum(1 for r in range(self.table.rowCount())
                   if self.table.item(r, 6).text() == "ACTIVE")

    def rows(self) -> list[dict[str, str]]:
        """The table as text, top row first (for tests and export)."""
        return [{name: self.table.item(r, c).text() for c, name in enumerate(COLUMNS)}
                | {"key": self.table.item(r, 0).data(Qt.ItemDataRole.UserRole)}
                for r in range(self.table.rowCount())]

    def _update_count(self) -> None:
        n = self.active_count()
        self.count_label.setText("no active alarms" if n == 0 else
                                 f"{n} active alarm{'s' if n != 1 else ''}")

    # --------------------------------------------------------------- log
    def add_log(self, level: str, source: str, text: str, t: float | None = None) -> None:
        stamp = clock_text(time.time() if t is None else t)
        mark = {"alarm": "ALARM", "warning": "WARN", "error": "ERROR"}.get(level, "info")
        self.log.appendPlainText(f"{stamp}  {mark:<5}  {source:<6}  {text}")

    def log_lines(self) -> list[str]:
        return self.log.toPlainText().splitlines()
