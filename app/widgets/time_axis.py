"""SlidingTimeAxis: a time-of-day axis whose ticks, labels and grid slide with a
moving window instead of being drawn again at every step.

A live plot's window ends at "now", so its time range changes at every refresh.
pyqtgraph's axis then throws its drawing away and generates and replays it anew
(tick values, label text, and the grid lines across the plot): the largest part
of a plot redraw. Between two refreshes the window only slides, so the same
ticks stand a few pixels further left. This axis draws its ticks, labels and
grid once into a pixmap and, while the window keeps its span and the axis its
size and no tick enters or leaves the window, paints that pixmap shifted by the
slide. It draws anew when a tick would enter or leave (every finest tick
spacing, e.g. every 10 to 30 s for a 10 min window), when the span or size
changes, or when pyqtgraph invalidates its drawing (style, pen, grid, resize).
The axis line (it spans the whole width) and the labels (few; text drawn onto a
clear pixmap would come out heavier) are drawn directly at each paint, the labels
shifted with the ticks.
"""

from __future__ import annotations

import math

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QPointF, Qt
from PySide6.QtGui import QPainter, QPen, QPixmap

__all__ = ["SlidingTimeAxis"]


class SlidingTimeAxis(pg.DateAxisItem):
    """A DateAxisItem for a sliding window (see the module docstring)."""

    def __init__(self, orientation: str = "bottom", **kw) -> None:
        super().__init__(orientation=orientation, **kw)
        self.enableAutoSIPrefix(False)  # seconds since the epoch: no SI prefix
        self._sheet: QPixmap | None = None
        self._sheet_lo = 0.0
        self._sheet_origin = QPointF()
        self._sheet_key: tuple = ()
        self._valid_lo = (0.0, 0.0)  # the window's start may lie in (a, b]
        self._valid_hi = (0.0, 0.0)  # the window's end may lie in [a, b)
        self._axis_line: tuple | None = None
        self._texts: list = []  # every label of the drawn ticks, shown if it fits
        self._all_labels = False
        self._levels: list = []
        self.rebuilds = 0  # how often ticks, labels and grid were drawn anew

    # pyqtgraph resets ``self.picture`` whenever its drawing is out of date; a
    # range change alone is handled here (a slide keeps the drawing)
    def setRange(self, mn: float, mx: float) -> None:
        if not (math.isfinite(mn) and math.isfinite(mx)):
            raise ValueError(f"Not setting range to [{mn}, {mx}]")
        if [mn, mx] == getattr(self, "range", None):
            return
        self.range = [mn, mx]
        self.update()

    def boundingRect(self):
        br = super().boundingRect()
        if getattr(self, "_all_labels", False):  # see _draw_sheet
            if self.orientation in ("top", "bottom"):
                return br.adjusted(-br.width(), 0, br.width(), 0)
            return br.adjusted(0, -br.height(), 0, br.height())
        return br

    def tickValues(self, minVal, maxVal, size):
        levels = super().tickValues(minVal, maxVal, size)
        self._levels = levels
        return levels

    def _key(self, widget) -> tuple:
        geo = self.geometry()
        dpr = widget.devicePixelRatioF() if widget is not None else 1.0
        lo, hi = self.range
        rect = self.boundingRect()
        return (round(hi - lo, 6), geo.width(), geo.height(), rect.width(), rect.height(), dpr)

    def _slides(self, key: tuple) -> bool:
        if self._sheet is None or self.picture is None or key != self._sheet_key:
            return False
        lo, hi = self.range
        return (self._valid_lo[0] < lo <= self._valid_lo[1]
                and self._valid_hi[0] <= hi < self._valid_hi[1])

    def _draw_sheet(self, key: tuple) -> None:
        rect = self.boundingRect()
        dpr = key[-1]
        # whole pixels, a pixel to spare on each side: the lines land where
        # pyqtgraph would draw them straight onto the plot
        origin = QPointF(math.floor(rect.left()) - 1, math.floor(rect.top()) - 1)
        sheet = QPixmap(max(1, math.ceil((rect.right() + 1 - origin.x()) * dpr)),
                        max(1, math.ceil((rect.bottom() + 1 - origin.y()) * dpr)))
        sheet.setDevicePixelRatio(dpr)
        sheet.fill(Qt.GlobalColor.transparent)
        painter = QPainter(sheet)
        try:
            painter.translate(-origin)
            if self.style["tickFont"]:
                painter.setFont(self.style["tickFont"])
            self._levels = []
            self._all_labels = True  # keep labels that do not fit yet: they may later
            try:
                specs = self.generateDrawSpecs(painter)
            finally:
                self._all_labels = False
            if specs is not None:
                axis, ticks, texts = specs
                self._axis_line = axis
                self._texts = texts
                self.drawPicture(painter, (QPen(Qt.PenStyle.NoPen), axis[1], axis[2]),
                                 ticks, [])
            else:
                self._axis_line = None
                self._texts = []
        finally:
            painter.end()
        self._sheet = sheet
        self._sheet_origin = origin
        self._sheet_key = key
        self._sheet_lo = self.range[0]
        self.picture = sheet  # pyqtgraph sets it to None when this is out of date
        self.rebuilds += 1
        self._set_validity()

    def _set_validity(self) -> None:
        """The window may slide while the same ticks lie inside it: its start not
        past the first tick nor back to the one before, its end likewise."""
        lo, hi = self.range
        values = sorted({v for _, vals in self._levels for v in vals if lo <= v <= hi})
        spacings = [s for s, vals in self._levels if len(vals)]
        if not values or not spacings:
            self._valid_lo = self._valid_hi = (0.0, 0.0)  # draw anew each time
            return
        # the ticks actually drawn may be sparser than a level's nominal spacing
        # (labels that would crowd are skipped): the smallest gap is the step
        gaps = np.diff(values).tolist()
        step = min(gaps) if gaps else min(spacings)
        self._valid_lo = (values[0] - step, values[0])
        self._valid_hi = (values[-1], values[-1] + step)

    def paint(self, p, opt, widget) -> None:
        key = self._key(widget)
        if not self._slides(key):
            self._draw_sheet(key)
        rect = self.boundingRect()
        span = self.range[1] - self.range[0]
        geo = self.geometry()
        along = geo.width() if self.orientation in ("top", "bottom") else geo.height()
        shift = (self._sheet_lo - self.range[0]) * along / span if span else 0.0
        p.save()
        p.setRenderHint(QPainter.RenderHint.Antialiasing, False)
        # the same ticks lie inside the window while it slides: nothing to clip
        if self.orientation in ("top", "bottom"):
            step, slide = QPointF(round(shift), 0.0), QPointF(shift, 0.0)
        else:
            step, slide = QPointF(0.0, -round(shift)), QPointF(0.0, -shift)
        p.drawPixmap(self._sheet_origin + step, self._sheet)
        # labels are drawn straight onto the plot (text drawn onto a clear pixmap
        # and laid over the plot comes out heavier); the axis line spans the width
        p.setRenderHint(QPainter.RenderHint.TextAntialiasing, True)
        if self.style["tickFont"] is not None:
            p.setFont(self.style["tickFont"])
        p.setPen(self.textPen())
        for box, flags, text in self._texts:
            box = box.translated(slide)
            if rect & box == box:  # pyqtgraph's rule: a label is shown whole or not
                p.drawText(box, int(flags), text)
        if self._axis_line is not None:
            pen, p1, p2 = self._axis_line
            p.setPen(pen)
            p.drawLine(p1, p2)
        p.restore()
