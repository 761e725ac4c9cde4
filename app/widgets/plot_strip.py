"""PlotStrip: stacked live time plots, one PlotItem and one curve per channel.

Data is pulled, not pushed per sample: the owner calls :meth:`PlotStrip.mark_dirty`
when new samples exist, and a timer (default 5 Hz) asks the data source for each
dirty channel's window and hands it to the curve with ``setData``. The x axis is
wall-clock time (epoch seconds shown as time of day); the visible window is set
with :meth:`PlotStrip.set_window`. Horizontal dashed lines mark limits.

A redraw is the dearest thing the desk's GUI thread does (three plots of a 10 min
window: about 15 ms of CPU), so it is kept cheap and rare: curves are drawn with
a 1 px pen (Qt's fast path; a 1.5 px line costs about 1.5 ms more per curve); a
long window refreshes only as often as it moves by a fraction of a pixel's worth
of time (``_apply_interval``); and a plot's value axis keeps its range while the
data and limits still fit it well, so its cached tick labels and grid are not
painted again at every refresh (``_fit_y``); the time axis, whose range moves at
every refresh, slides its drawn ticks, labels and grid with the window and draws
them anew only when a tick enters or leaves (:mod:`app.widgets.time_axis`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QGraphicsItem, QVBoxLayout, QWidget

from app.widgets.time_axis import SlidingTimeAxis

__all__ = ["PlotStrip", "DataSource"]

log = logging.getLogger(__name__)

# source(key, seconds) -> (t, y) of the last ``seconds``
DataSource = Callable[[str, float], tuple[np.ndarray, np.ndarray]]


@dataclass
class _Channel:
    key: str
    plot: pg.PlotItem
    curve: pg.PlotDataItem
    lines: dict[str, pg.InfiniteLine]
    limits: dict[str, float]


class PlotStrip(QWidget):
    """Several time plots stacked vertically with a shared, linked time axis."""

    def __init__(self, parent: QWidget | None = None, *, refresh_hz: float = 5.0,
                 window_s: float = 600.0, clock: Callable[[], float] = time.time,
                 curve_color: str = "#303030", limit_color: str = "#8a6d00") -> None:
        super().__init__(parent)
        self._clock = clock
        self._window_s = float(window_s)
        self._source: DataSource | None = None
        self._channels: dict[str, _Channel] = {}
        self._dirty: set[str] = set()
        self._curve_color = curve_color
        self._limit_color = limit_color
        self.refreshes = 0
        self.rejected = 0  # windows from the source whose times and values differ in length

        self._glw = pg.GraphicsLayoutWidget()
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self._glw)

        self._timer = QTimer(self)
        self._base_interval_ms = max(20, int(1000 / refresh_hz))
        self._apply_interval()
        self._timer.timeout.connect(self.refresh)
        self._timer.start()

    # ------------------------------------------------------------ channels
    def set_clock(self, clock: Callable[[], float]) -> None:
        """The time the plots' window ends at (the wall clock live, the replay
        clock in a replay)."""
        self._clock = clock
        self.mark_dirty()

    def add_channel(self, key: str, title: str, unit: str = "",
                    color: str | None = None) -> pg.PlotItem:
        if key in self._channels:
            raise ValueError(f"channel {key!r} already added")
        row = len(self._channels)
        plot = self._glw.addPlot(row=row, col=0, axisItems={
            "bottom": SlidingTimeAxis(orientation="bottom")})
        # painting tick text is the dearest part of a redraw: the value axis is
        # cached as a pixmap until its range changes, and only the lowest plot
        # labels the shared time axis
        plot.getAxis("left").setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        for ch in self._channels.values():
            ch.plot.getAxis("bottom").setStyle(showValues=False)
        plot.setLabel("left", title, units=unit or None)
        # the hidden top axis follows the time range too: without this it would
        # work out an SI prefix and set its (unseen) label's HTML at every refresh
        for side in ("top", "right"):
            plot.getAxis(side).enableAutoSIPrefix(False)
        plot.showGrid(x=True, y=True, alpha=0.25)
        plot.setMenuEnabled(False)
        plot.setMouseEnabled(x=False, y=False)
        plot.hideButtons()
        # the source hands out only the window's samples: no clipping to the view
        # (with it, every slide of the window processed each curve's data again)
        plot.setClipToView(False)
        plot.setDownsampling(ds=1, auto=False, mode="peak")
        # the plots share the time window by each being given the same range
        # (no setXLink: linked ViewBoxes crash PySide6 6.12 at interpreter exit)
        curve = plot.plot(pen=pg.mkPen(color or self._curve_color, width=1))
        self._channels[key] = _Channel(key, plot, curve, {}, {})
        self._dirty.add(key)
        return plot

    def channels(self) -> list[str]:
        return list(self._channels)

    def plot_item(self, key: str) -> pg.PlotItem:
        return self._channels[key].plot

    def curve(self, key: str) -> pg.PlotDataItem:
        return self._channels[key].curve

    def set_limit(self, key: str, name: str, value: float | None) -> None:
        """Draw (or with None remove) a horizontal limit line called ``name``."""
        ch = self._channels[key]
        line = ch.lines.pop(name, None)
        ch.limits.pop(name, None)
        if line is not None:
            ch.plot.removeItem(line)
        if value is None:
            return
        line = pg.InfiniteLine(pos=float(value), angle=0, movable=False,
                               pen=pg.mkPen(self._limit_color, width=1,
                                            style=Qt.PenStyle.DashLine),
                               label=name, labelOpts={"position": 0.01, "anchors": [(0, 0), (0, 0)],
                                                      "color": self._limit_color})
        ch.plot.addItem(line, ignoreBounds=True)
        ch.lines[name] = line
        ch.limits[name] = float(value)
        self._dirty.add(key)

    def limit_lines(self, key: str) -> dict[str, float]:
        return dict(self._channels[key].limits)

    # ------------------------------------------------------------- data
    def set_source(self, source: DataSource) -> None:
        self._source = source
        self.mark_dirty()

    def mark_dirty(self, key: str | None = None) -> None:
        """New data exists for ``key`` (all channels when None); drawn at the next tick."""
        if key is None:
            self._dirty.update(self._channels)
        elif key in self._channels:
            self._dirty.add(key)

    def window_s(self) -> float:
        return self._window_s

    def set_window(self, seconds: float) -> None:
        if seconds <= 0:
            raise ValueError("window must be positive")
        self._window_s = float(seconds)
        self._apply_interval()
        self.mark_dirty()
        self.refresh()

    def set_refresh_hz(self, hz: float) -> None:
        self._base_interval_ms = max(20, int(1000 / hz))
        self._apply_interval()

    def _apply_interval(self) -> None:
        # a long window moves less than a pixel between fast refreshes: 1 s for 10 min,
        # at most 2 s (a 60 min window on a 600 px plot moves a pixel in 6 s)
        slow = 0 if self._window_s <= 120 else min(2000, max(500, int(self._window_s / 0.6)))
        self._timer.setInterval(max(self._base_interval_ms, slow))

    def refresh_interval_ms(self) -> int:
        return self._timer.interval()

    def refresh(self) -> None:
        """Pull the dirty channels from the source and move the time window."""
        now = self._clock()
        if self._source is not None:
            for key in list(self._dirty):
                ch = self._channels[key]
                t, y = self._source(key, self._window_s)
                if len(t) != len(y):
                    self.rejected += 1
                    log.warning("plot %s: %d times but %d values; not drawn", key, len(t), len(y))
                    continue
                # the source may hand out views of a ring buffer: keep a copy
                # peak decimation to about two points per pixel; pyqtgraph's own
                # auto mode shows nothing when a burst has fewer samples than its factor
                ds = max(1, len(t) // max(self._max_points(ch), 1))
                ch.plot.setDownsampling(ds=ds, auto=False, mode="peak")
                ch.curve.setData(np.array(t, dtype=np.float64),
                                 np.array(y, dtype=np.float64))
                self._fit_y(ch, y)
        self._dirty.clear()
        for ch in self._channels.values():
            ch.plot.setXRange(now - self._window_s, now, padding=0)
            # the view's new transform now, not when the scene is painted: there it
            # moves the limit lines and their labels, which asked for a second paint
            # of the whole strip right after the first
            ch.plot.vb.prepareForPaint()
        self.refreshes += 1

    def _max_points(self, ch: _Channel) -> int:
        return max(2 * int(ch.plot.vb.width()), 1000)

    def _fit_y(self, ch: _Channel, y: np.ndarray) -> None:
        """Keep the data and the limit lines in view."""
        vals = list(ch.limits.values())
        if len(y):
            finite = np.asarray(y)[np.isfinite(y)]
            if finite.size:
                vals += [float(finite.min()), float(finite.max())]
        if not vals:
            return
        lo, hi = min(vals), max(vals)
        pad = max((hi - lo) * 0.08, 0.5 if hi == lo else 0.0)
        cur_lo, cur_hi = ch.plot.viewRange()[1]
        if cur_lo <= lo and cur_hi >= hi and cur_hi - cur_lo <= 1.6 * (hi - lo + 2 * pad):
            return  # still fits, not too loosely: the axis is not redrawn
        pad = max((hi - lo) * 0.15, 0.5 if hi == lo else 0.0)  # room to grow a little
        ch.plot.setYRange(lo - pad, hi + pad, padding=0)
