"""ValueTile: a big number with its unit and label, that changes colour when flagged.

The flag is a short level name (e.g. ``"high"``) stored in the Qt property
``alarm``, so a style sheet decides the colour: ``ValueTile[alarm="high"] {...}``.
Without a style sheet, :meth:`set_alarm` also accepts an explicit colour.

A tile whose value is no longer current (:meth:`set_stale` with its age, e.g.
"last known 15:17:21, 40 s ago") is hatched and greyed, says its age under the
number, and shows no alarm colour while stale: an old number must not look like
a live limit alarm (the flag comes back with fresh data).

The number changes many times a second, so its label has a fixed size (that of
the widest number its format gives for values up to a thousand, larger when a
longer one comes): a label whose size may change asks every layout up to the
window to be computed again, and the window repainted, at each new text.
"""

from __future__ import annotations

import math

from PySide6.QtCore import QEvent, Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import QFrame, QLabel, QVBoxLayout, QWidget

from app.widgets.stale import is_stale, paint_hatch, set_stale

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
        self._number = QLabel(self.tr("—"), self)
        self._number.setObjectName("tileValue")
        self._number.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        f = self._number.font()
        f.setPointSizeF(max(f.pointSizeF(), 9.0) * 2.0)
        f.setBold(True)
        self._number.setFont(f)
        self._unit = QLabel(unit, self)
        self._unit.setObjectName("tileUnit")
        self._unit.setAlignment(Qt.AlignmentFlag.AlignRight)
        self._age = QLabel("", self)
        self._age.setObjectName("tileAge")
        self._age.setWordWrap(True)
        self._age.setVisible(False)
        self._color: QColor | None = None
        lay = QVBoxLayout(self)
        lay.setContentsMargins(8, 4, 8, 4)
        lay.setSpacing(0)
        lay.addWidget(self._label)
        lay.addWidget(self._number, 0, Qt.AlignmentFlag.AlignRight)
        self._fit_number(self._fmt.format(-888.888))
        lay.addWidget(self._unit)
        lay.addWidget(self._age)
        self.setProperty("alarm", "")
        self.setProperty("stale", "false")

    def set_value(self, value: float | None) -> None:
        self._value = value
        if value is None or (isinstance(value, float) and not math.isfinite(value)):
            text = self.tr("—")
        else:
            text = self._fmt.format(value)
        if len(text) > self._fits:
            self._fit_number(text)
        self._number.setText(text)

    def _fit_number(self, widest: str) -> None:
        """Fix the number label's size to hold ``widest`` (and anything shorter)."""
        shown = self._number.text()
        self._number.setMinimumSize(0, 0)
        self._number.setMaximumSize(16_777_215, 16_777_215)
        self._number.setText(widest)
        self._number.setFixedSize(self._number.sizeHint())
        self._number.setText(shown)
        self._fits = len(widest)

    def changeEvent(self, ev) -> None:  # noqa: N802 (Qt name)
        super().changeEvent(ev)
        if ev.type() in (QEvent.Type.FontChange, QEvent.Type.StyleChange):
            self._fit_number("8" * getattr(self, "_fits", 6))

    def value(self) -> float | None:
        return self._value

    def value_text(self) -> str:
        return self._number.text()

    def set_label(self, text: str) -> None:
        """The tile's name line, e.g. "Gas" or "Gas · A2" (the gas stage)."""
        self._label.setText(text)

    def label_text(self) -> str:
        return self._label.text()

    def set_unit(self, unit: str) -> None:
        self._unit.setText(unit)

    def set_alarm(self, level: str | None, color: QColor | str | None = None) -> None:
        """Flag the tile with ``level`` (style-sheet driven), or clear it with None."""
        level = level or ""
        if level == self._level and color is None:
            return
        self._level = level
        self._color = QColor(color) if color is not None and level else None
        self._show_flag()

    def alarm_level(self) -> str:
        """The flag set on the tile (kept while stale, but not shown then)."""
        return self._level

    def shown_alarm_level(self) -> str:
        """The flag the tile shows now ("" while stale)."""
        return str(self.property("alarm") or "")

    def set_stale(self, age_text: str | None) -> None:
        """Show the value as no longer current, with ``age_text`` under it; None:
        current again."""
        stale = bool(age_text)
        self._age.setText(age_text or "")
        self._age.setVisible(stale)
        if self.toolTip() != (age_text or ""):  # asked twice a second, mostly the same
            self.setToolTip(age_text or "")
        if stale != is_stale(self):
            set_stale(self, stale)
            self._show_flag()

    def is_stale(self) -> bool:
        return is_stale(self)

    def stale_text(self) -> str:
        return self._age.text() if self.is_stale() else ""

    def _show_flag(self) -> None:
        level = "" if self.is_stale() else self._level
        self.setProperty("alarm", level)
        if self._color is not None and level:
            self.setStyleSheet(f"#ValueTile {{ background-color: {self._color.name()}; }}")
        else:
            self.setStyleSheet("")
        self.style().unpolish(self)
        self.style().polish(self)
        for w in (self._label, self._number, self._unit, self._age):
            w.style().unpolish(w)
            w.style().polish(w)
        self.update()

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt name)
        super().paintEvent(event)
        if self.is_stale():
            paint_hatch(self)
