"""ValueTile: a big number with its unit and label, that changes colour when flagged.

The flag is a short level name (e.g. ``"high"``) stored in the Qt property
``alarm``, so a style sheet decides the colour: ``ValueTile[alarm="high"] {...}``.
Without a style sheet, :meth:`set_alarm` also accepts an explicit colour.
"""

from __future__ import annotations

import math

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import QFrame, QLabel, QVBoxLayout, QWidget

__all__ = ["ValueTile"]


class ValueTile(QFrame):
    def __init__(self, label: str, unit: str = "", parent: QWidget | None = None, *,
                 fmt: str = "{:.1f}") -> None:
        super().__init__(parent)
        self.setObjectName("ValueTile")
        self.setFrameShape(QFrame.Shape.StyledPanel)
        self._fmt = fmt
        self._value: float | None = None
        self._level = ""
        self._label = QLabel(label, self)
        self._label.setObjectName("tileLabel")
        self._number = QLabel("—", self)
        self._number.setObjectName("tileValue")
        self._number.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        f = self._number.font()
        f.setPointSizeF(max(f.pointSizeF(), 9.0) * 2.0)
        f.setBold(True)
        self._number.setFont(f)
        self._unit = QLabel(unit, self)
        self._unit.setObjectName("tileUnit")
        self._unit.setAlignment(Qt.AlignmentFlag.AlignRight)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(8, 4, 8, 4)
        lay.setSpacing(0)
        lay.addWidget(self._label)
        lay.addWidget(self._number)
        lay.addWidget(self._unit)
        self.setProperty("alarm", "")

    def set_value(self, value: float | None) -> None:
        self._value = value
        if value is None or (isinstance(value, float) and not math.isfinite(value)):
            self._number.setText("—")
        else:
            self._number.setText(self._fmt.format(value))

    def value(self) -> float | None:
        return self._value

    def value_text(self) -> str:
        return self._number.text()

    def set_unit(self, unit: str) -> None:
        self._unit.setText(unit)

    def set_alarm(self, level: str | None, color: QColor | str | None = None) -> None:
        """Flag the tile with ``level`` (style-sheet driven), or clear it with None."""
        level = level or ""
        if level == self._level and color is None:
            return
        self._level = level
        self.setProperty("alarm", level)
        if color is not None and level:
            self.setStyleSheet(f"#ValueTile {{ background-color: {QColor(color).name()}; }}")
        else:
            self.setStyleSheet("")
        self.style().unpolish(self)
        self.style().polish(self)
        for w in (self._label, self._number, self._unit):
            w.style().unpolish(w)
            w.style().polish(w)
        self.update()

    def alarm_level(self) -> str:
        return self._level
