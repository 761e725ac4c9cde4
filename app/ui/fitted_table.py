"""A table view whose columns fit their text, measured row by row.

Qt's ``ResizeToContents`` header re-measures every cell of a column (through the
delegate's ``sizeHint``, up to 1000 rows) whenever any cell of it changes, so a
list that announces one changed row a second pays for all its rows. Here each
row's width per column is kept; a change measures only the rows announced
(``dataChanged``), a reset or inserted/removed rows measure them all, and a
column is as wide as its widest kept row or its header, whichever is more (as
``ResizeToContents`` makes it: the delegate's hint, plus one pixel of grid). The
last section may stretch (``setStretchLastSection``): it is then not measured.

A cell's width depends on its column and its text only (the delegate draws plain
text: no icon, no font of its own), and an alarm list repeats its texts (the
priority marks, states, sources and limits), so the widths are also kept by
(column, text): a reset that brings one new row asks the delegate about that row's
new texts only. That memory is forgotten when the font, style, language or
delegate changes, and when it holds more than ``MEMO_MAX`` texts (a list's times
and values are new every day).

``measured`` counts the cells measured by the delegate since it was last set, for
tests and benches.
"""

from __future__ import annotations

from PySide6.QtCore import QEvent, QModelIndex, Qt
from PySide6.QtWidgets import QHeaderView, QTableView

__all__ = ["FittedTableView"]

MEMO_MAX = 4096  # (column, text) widths kept before the memory starts again


class FittedTableView(QTableView):
    """A QTableView whose horizontal header's sections fit their contents, measuring
    only the rows that changed."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._need: list[list[int]] = []  # per row, the width each column's cell wants
        self._head: list[int] = []  # per column, the header's own width
        self._memo: dict[tuple[int, object], int] = {}  # (column, text) -> width
        self.measured = 0
        self.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Fixed)

    # ------------------------------------------------------------- the model
    def setModel(self, model) -> None:  # noqa: N802 - Qt's name
        old = self.model()
        if old is not None:
            for sig, slot in self._hooks(old):
                sig.disconnect(slot)
        super().setModel(model)
        if model is not None:
            for sig, slot in self._hooks(model):
                sig.connect(slot)
        self.fit_all()

    def _hooks(self, model):
        return ((model.modelReset, self.fit_all), (model.layoutChanged, self.fit_all),
                (model.rowsInserted, self.fit_all), (model.rowsRemoved, self.fit_all),
                (model.columnsInserted, self.fit_all), (model.columnsRemoved, self.fit_all),
                (model.headerDataChanged, self.fit_all), (model.dataChanged, self._changed))

    # ------------------------------------------------------------ measuring
    def _fitted_columns(self) -> range:
        model = self.model()
        n = model.columnCount() if model is not None else 0
        if n and self.horizontalHeader().stretchLastSection():
            n -= 1
        return range(n)

    def _measure(self, row: int, col: int) -> int:
        index = self.model().index(row, col)
        key = (col, index.data(Qt.ItemDataRole.DisplayRole))
        width = self._memo.get(key)
        if width is None:
            if len(self._memo) >= MEMO_MAX:
                self._memo.clear()
            self.measured += 1
            width = self._memo[key] = self.sizeHintForIndex(index).width()
        return width

    def forget_widths(self) -> None:
        """Forget the widths kept by text (the font, style or delegate changed)."""
        self._memo.clear()

    def setItemDelegate(self, delegate) -> None:  # noqa: N802 - Qt's name
        super().setItemDelegate(delegate)
        self.forget_widths()

    def fit_all(self, *_args) -> None:
        """Measure every row and the header again (a reset, a font or style change)."""
        model = self.model()
        if model is None:
            return
        cols = self._fitted_columns()
        hh = self.horizontalHeader()
        self._head = [hh.sectionSizeHint(c) for c in cols]
        self._need = [[self._measure(r, c) for c in cols] for r in range(model.rowCount())]
        self._apply(cols)

    def _changed(self, top_left: QModelIndex, bottom_right: QModelIndex, roles=()) -> None:
        rows = range(top_left.row(), bottom_right.row() + 1)
        cols = self._fitted_columns()
        if len(self._need) != self.model().rowCount() or len(self._head) != len(cols):
            self.fit_all()
            return
        first, last = max(top_left.column(), 0), min(bottom_right.column(), len(cols) - 1)
        for r in rows:
            need = self._need[r]
            for c in range(first, last + 1):
                need[c] = self._measure(r, c)
        self._apply(cols)

    def _apply(self, cols: range) -> None:
        hh = self.horizontalHeader()
        grid = 1 if self.showGrid() else 0
        lo, hi = hh.minimumSectionSize(), hh.maximumSectionSize()
        for c in cols:
            want = max([self._head[c]] + [need[c] + grid for need in self._need])
            want = min(max(want, lo), hi)
            if hh.sectionSize(c) != want:
                hh.resizeSection(c, want)

    # -------------------------------------------------------------- events
    def changeEvent(self, event: QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        if event.type() in (QEvent.Type.FontChange, QEvent.Type.StyleChange,
                            QEvent.Type.LanguageChange):  # the header's words change
            self.forget_widths()
            self.fit_all()

    def showEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        self.forget_widths()
        self.fit_all()  # polished now: the style sheet's font and padding apply
