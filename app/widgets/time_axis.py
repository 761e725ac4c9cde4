"""SlidingTimeAxis: a time-of-day axis whose ticks, labels and grid slide with a
moving window instead of being worked out again at every step.

A live plot's window ends at "now", so its time range changes at every refresh.
pyqtgraph's axis then throws its drawing away, works out the tick values, label
texts and positions anew, records them in a QPicture and replays it (the grid
lines across the plot are the axis's ticks): the largest part of a plot redraw.
Between two refreshes the window only slides, so the same ticks stand a few
pixels further left. This axis works its ticks and labels out once and, while
the window keeps its span and the axis its size and no tick enters or leaves the
window, draws the same lines and labels moved by the slide, straight onto the
plot. It works them out anew when a tick would enter or leave (every tick
spacing, e.g. every 1 to 5 min for a 10 min window), when the span or size
changes, or when pyqtgraph invalidates its drawing (style, pen, grid, resize). A
label is shown when it fits inside the axis whole, as pyqtgraph shows it.
"""

from __future__ import annotations

import math

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QPointF
from PySide6.QtGui import QPainter, QPicture

__all__ = ["SlidingTimeAxis"]


class SlidingTimeAxis(pg.DateAxisItem):
    """A DateAxisItem for a sliding window (see the module docstring)."""

    def __init__(self, orientation: str = "bottom", **kw) -> None:
        super().__init__(orientation=orientation, **kw)
        self.enableAutoSIPrefix(False)  # seconds since the epoch: no SI prefix
        self._ticks: list | None = None  # (pen, p1, p2) of each tick and grid line
        self._drawn_lo = 0.0
        self._drawn_key: tuple = ()
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
        if getattr(self, "_all_labels", False):  # see _work_out
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
        # the span to a millisecond: epoch-second floats jitter in their last bits
        return (round(hi - lo, 3), geo.width(), geo.height(), rect.width(), rect.height(), dpr)

    def _slides(self, key: tuple) -> bool:
        if self._ticks is None or self.picture is None or key != self._drawn_key:
            return False
        lo, hi = self.range
        return (self._valid_lo[0] < lo <= self._valid_lo[1]
                and self._valid_hi[0] <= hi < self._valid_hi[1])

    def _work_out(self, key: tuple) -> None:
        picture = QPicture()  # a painter for the font metrics, as pyqtgraph uses
        painter = QPainter(picture)
        try:
            if self.style["tickFont"]:
                painter.setFont(self.style["tickFont"])
            self._levels = []
            self._all_labels = True  # keep labels that do not fit yet: they may later
            try:
                specs = self.generateDrawSpecs(painter)
            finally:
                self._all_labels = False
        finally:
            painter.end()
        self._axis_line, self._ticks, self._texts = specs if specs is not None else (None, [], [])
        self._drawn_key = key
        self._drawn_lo = self.range[0]
        self.picture = picture  # pyqtgraph sets it to None when this is out of date
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
            self._work_out(key)
        span = self.range[1] - self.range[0]
        geo = self.geometry()
        along = geo.width() if self.orientation in ("top", "bottom") else geo.height()
        shift = (self._drawn_lo - self.range[0]) * along / span if span else 0.0
        across = self.orientation in ("top", "bottom")
        slide = QPointF(shift, 0.0) if across else QPointF(0.0, -shift)
        p.save()
        p.setRenderHint(QPainter.RenderHint.Antialiasing, False)
        if self._axis_line is not None:
            pen, p1, p2 = self._axis_line
            p.setPen(pen)
            p.drawLine(p1, p2)
        for pen, p1, p2 in self._ticks:
            p.setPen(pen)
            p.drawLine(p1 + slide, p2 + slide)
        p.setRenderHint(QPainter.RenderHint.TextAntialiasing, True)
        if self.style["tickFont"] is not None:
            p.setFont(self.style["tickFont"])
        p.setPen(self.textPen())
        rect = self.boundingRect()
        for box, flags, text in self._texts:
            box = box.translated(slide)
            if rect & box == box:  # pyqtgraph's rule: a label is shown whole or not
                p.drawText(box, int(flags), text)
        p.restore()
