"""StatusLamp: a small coloured dot followed by a short text.

Stale (:meth:`StatusLamp.set_stale`): the dot becomes a hollow grey ring and the
text is greyed, with the age after it; no colour while stale.
"""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QHBoxLayout, QLabel, QWidget

from app.widgets.stale import is_stale, set_stale

__all__ = ["StatusLamp"]


class _Dot(QWidget):
    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.color: QColor | None = None
        self.hollow = False  # stale: an outline only
        self.setFixedSize(QSize(14, 14))

    def paintEvent(self, _event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        if self.hollow:
            p.setPen(QPen(self.palette().mid().color(), 2, Qt.PenStyle.DotLine))
            p.setBrush(Qt.BrushStyle.NoBrush)
        else:
            fill = self.color if self.color is not None else self.palette().mid().color()
            p.setPen(QPen(self.palette().dark().color(), 1))
            p.setBrush(fill)
        p.drawEllipse(self.rect().adjusted(1, 1, -1, -1))


class StatusLamp(QWidget):
    """A dot and a label. ``set_status(text, color)``; no colour = neutral grey."""

    def __init__(self, text: str = "", parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._dot = _Dot(self)
        self._label = QLabel(text, self)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(2, 0, 2, 0)
        lay.setSpacing(4)
        lay.addWidget(self._dot, 0, Qt.AlignmentFlag.AlignVCenter)
        lay.addWidget(self._label, 1)
        self._text = text
        self._age = ""
        self.setProperty("stale", "false")

    def set_status(self, text: str, color: QColor | str | None = None) -> None:
        self._text = text
        self._dot.color = QColor(color) if color is not None else None
        self._show()

    def set_stale(self, age_text: str | None) -> None:
        """Show the status as no longer current, with ``age_text`` after it; None:
        current again."""
        self._age = age_text or ""
        set_stale(self, bool(age_text))
        self._show()

    def is_stale(self) -> bool:
        return is_stale(self)

    def _show(self) -> None:
        self._label.setText(f"{self._text} ({self._age})" if self._age else self._text)
        self._dot.hollow = bool(self._age)
        self._dot.update()

    def text(self) -> str:
        return self._label.text()

    def color(self) -> QColor | None:
        """The dot's colour as shown (None: neutral, or stale)."""
        return None if self._dot.hollow else self._dot.color
