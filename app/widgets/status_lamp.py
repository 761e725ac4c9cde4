"""StatusLamp: a small coloured dot followed by a short text."""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QHBoxLayout, QLabel, QWidget

__all__ = ["StatusLamp"]


class _Dot(QWidget):
    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.color: QColor | None = None
        self.setFixedSize(QSize(14, 14))

    def paintEvent(self, _event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
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

    def set_status(self, text: str, color: QColor | str | None = None) -> None:
        self._label.setText(text)
        self._dot.color = QColor(color) if color is not None else None
        self._dot.update()

    def text(self) -> str:
        return self._label.text()

    def color(self) -> QColor | None:
        return self._dot.color
