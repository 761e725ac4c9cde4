"""SteadyLabel: a QLabel for a field whose text changes many times a second.

A QLabel whose size may change asks its layout, and every layout above it up to
the window, to be computed again at each new text; in a status bar that also
rebuilds the bar's own layout (``QStatusBar`` reformats itself), and the window
repaints what moved. A SteadyLabel has a fixed size that only grows, to the
widest text it has been given (or its minimum width): a new text of that size or
less just repaints the label.
"""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QWidget

__all__ = ["SteadyLabel"]


class SteadyLabel(QLabel):
    def __init__(self, text: str = "", parent: QWidget | None = None) -> None:
        super().__init__(text, parent)
        self._min_w = 0
        self._fit()

    def setText(self, text: str) -> None:  # noqa: N802 - Qt's name
        if text == self.text():
            return
        super().setText(text)
        self._fit()

    def setMinimumWidth(self, w: int) -> None:  # noqa: N802 - Qt's name
        """The least width it keeps (it still grows for a longer text)."""
        self._min_w = int(w)
        self._fit()

    def _fit(self) -> None:
        hint = self.sizeHint()
        w = max(hint.width(), self._min_w, self.maximumWidth() if self._fixed() else 0)
        h = max(hint.height(), self.maximumHeight() if self._fixed() else 0)
        if not self._fixed() or w > self.maximumWidth() or h > self.maximumHeight():
            self.setFixedSize(w, h)

    def _fixed(self) -> bool:
        return (self.minimumWidth() == self.maximumWidth()
                and self.minimumHeight() == self.maximumHeight())
