"""The "stale" look: a value that is shown but no longer current.

After ISA-101, stale data is greyed and outlined (or hatched), never drawn in an
alarm colour: colour stays reserved for abnormal process states. Any widget can
carry the look: :func:`set_stale` sets the dynamic property ``stale`` that the
style sheet draws (``QLabel[stale="true"] {...}``), and re-polishes the widget and
its children so the change shows at once. :func:`paint_hatch` is the hatching a
widget that paints itself adds on top.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtGui import QBrush, QColor, QPainter
from PySide6.QtWidgets import QWidget

__all__ = ["HATCH_COLOR", "is_stale", "paint_hatch", "set_stale"]

HATCH_COLOR = "#b4b4b4"  # a grey a shade darker than the panels


def set_stale(widget: QWidget, stale: bool) -> bool:
    """Give ``widget`` the stale look (or take it away); True when it changed."""
    want = "true" if stale else "false"
    if widget.property("stale") == want:
        return False
    widget.setProperty("stale", want)
    for w in (widget, *widget.findChildren(QWidget)):
        w.style().unpolish(w)
        w.style().polish(w)
    widget.update()
    return True


def is_stale(widget: QWidget) -> bool:
    return widget.property("stale") == "true"


def paint_hatch(widget: QWidget, color: QColor | str = HATCH_COLOR) -> None:
    """Diagonal hatching over ``widget`` (call from its paintEvent)."""
    p = QPainter(widget)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(QBrush(QColor(color), Qt.BrushStyle.BDiagPattern))
    p.drawRect(widget.rect())
    p.end()
