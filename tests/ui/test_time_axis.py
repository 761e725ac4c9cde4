"""The plots' time axis slides its drawn ticks, labels and grid with the window
instead of drawing them anew at every refresh, and still shows what pyqtgraph's
own axis would show for the same window."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtGui import QImage
from PySide6.QtWidgets import QApplication

from app.widgets import PlotStrip
from app.widgets.time_axis import SlidingTimeAxis

T0 = 1_800_000_000.0  # a whole minute


def _strip(qtbot, clock: dict, *, keys=("a", "b")) -> PlotStrip:
    strip = PlotStrip(window_s=600, clock=lambda: clock["t"])
    qtbot.addWidget(strip)
    strip.resize(900, 500)
    for k in keys:
        strip.add_channel(k, k, "%")
    strip.set_source(lambda k, s: (np.array([clock["t"] - 500, clock["t"] - 10]),
                                   np.array([1.0, 2.0])))
    strip.show()
    qtbot.waitExposed(strip)
    return strip


def _pyqtgraph_axes(strip: PlotStrip) -> None:
    """pyqtgraph's own time axis, set up as the strip sets up its own."""
    keys = strip.channels()
    for i, key in enumerate(keys):
        plot = strip.plot_item(key)
        plot.setAxisItems({"bottom": pg.DateAxisItem(orientation="bottom")})
        plot.updateGrid()
        plot.getAxis("bottom").setStyle(showValues=i == len(keys) - 1)


def _shot(strip: PlotStrip) -> np.ndarray:
    strip.mark_dirty()
    strip.refresh()
    QApplication.processEvents()
    img = strip.grab().toImage().convertToFormat(QImage.Format.Format_RGB32)
    a = np.frombuffer(img.constBits(), np.uint8).reshape(img.height(), img.bytesPerLine() // 4, 4)
    return a[:, : img.width(), :3].astype(int)


def test_time_axis_is_drawn_anew_only_when_a_tick_enters_or_the_size_changes(qtbot):
    clock = {"t": T0 + 5.0}
    strip = _strip(qtbot, clock, keys=("gas",))
    axis = strip.plot_item("gas").getAxis("bottom")
    assert isinstance(axis, SlidingTimeAxis)
    _shot(strip)  # the first values set the value axis's width: the layout settles
    _shot(strip)
    start = axis.rebuilds
    assert start >= 1
    lo, hi = axis._valid_hi  # the window's end may slide up to the next tick
    assert hi > lo
    for _ in range(5):  # one-second refreshes that bring in no new tick
        clock["t"] += (hi - clock["t"]) / 10
        _shot(strip)
    assert axis.rebuilds == start
    clock["t"] = hi + 0.5  # past the next tick: it must be drawn
    _shot(strip)
    assert axis.rebuilds == start + 1
    strip.refresh()  # the same range again: nothing to draw
    QApplication.processEvents()
    assert axis.rebuilds == start + 1
    strip.resize(700, 500)  # a new size: drawn anew
    _shot(strip)
    assert axis.rebuilds == start + 2


def test_sliding_time_axis_shows_what_pyqtgraph_draws_for_the_same_window(qtbot):
    """Grid lines, tick marks and labels, compared pixel by pixel with pyqtgraph's
    own DateAxisItem over a window sliding 7.3 s at a time through several ticks
    entering and leaving: the same pixels (a few where a curve crosses a grid
    line may blend differently), no line or label missing, moved or extra."""
    clock = {"t": T0 + 3.0}
    new, old = _strip(qtbot, clock), _strip(qtbot, clock)
    _pyqtgraph_axes(old)
    for strip in (new, old, new, old):  # the layouts settle
        _shot(strip)
    axis = new.plot_item("b").getAxis("bottom")
    first = axis.rebuilds
    for step in range(20):
        clock["t"] += 7.3
        a, b = _shot(new), _shot(old)
        assert a.shape == b.shape
        bad = np.argwhere(np.abs(a - b).sum(axis=2) > 6)
        assert len(bad) <= 20, f"step {step}: {len(bad)} pixels differ, e.g. {bad[:5].tolist()}"
    assert axis.rebuilds - first < 10  # 146 s slid: most refreshes only moved it
    assert axis.rebuilds - first >= 1


def test_sliding_the_window_does_not_process_the_curves_again(qtbot):
    """The source hands out only the window's samples, so a slide of the window
    with no new data leaves the curves' drawn data as they were; new data are
    shown whole."""
    clock = {"t": T0}
    strip = _strip(qtbot, clock, keys=("gas",))
    _shot(strip)
    drawn = strip.curve("gas").curve
    calls = []
    orig = drawn.setData
    drawn.setData = lambda *a, **k: (calls.append(1), orig(*a, **k))
    for _ in range(3):
        clock["t"] += 1.0
        strip.refresh()  # not marked dirty: only the window moves
        QApplication.processEvents()
    assert calls == []
    clock["t"] += 1.0
    _shot(strip)  # new data
    assert len(calls) == 1
    assert list(drawn.xData) == [clock["t"] - 500, clock["t"] - 10]


def test_a_window_with_more_values_than_times_is_counted_and_not_drawn(qtbot):
    clock = {"t": T0}
    data = {"y": np.array([1.0, 2.0])}
    strip = _strip(qtbot, clock, keys=("gas",))
    strip.set_source(lambda k, s: (np.array([T0 - 20, T0 - 10]), data["y"]))
    _shot(strip)
    data["y"] = np.array([1.0, 2.0, 3.0])
    _shot(strip)
    assert strip.rejected == 1
    assert list(strip.curve("gas").curve.yData) == [1.0, 2.0]  # the last good window


def test_sliding_the_window_sets_no_axis_label_again(qtbot):
    """Every axis that follows the time range (the shown time axis and the hidden
    top one) keeps its label as it was while the window slides."""
    clock = {"t": T0}
    strip = _strip(qtbot, clock, keys=("gas",))
    _shot(strip)  # the first values set the value axis's width: the layout settles
    _shot(strip)
    calls = []
    for side in ("top", "bottom", "left", "right"):
        label = strip.plot_item("gas").getAxis(side).label
        orig = label.setHtml
        label.setHtml = lambda html, side=side, orig=orig: (calls.append(side), orig(html))
    for _ in range(3):
        clock["t"] += 1.0
        strip.refresh()
        QApplication.processEvents()
    assert calls == []
    strip.plot_item("gas").setLabel("left", "Gas", units="%LEL")  # a real change still shows
    assert set(calls) == {"left"}


def test_a_refresh_that_slides_the_window_paints_the_plots_once(qtbot):
    """Sliding the window used to move the limit lines only when the scene was
    painted, which asked for a second paint of the whole strip right after."""
    from PySide6.QtCore import QEvent, QObject

    clock = {"t": T0 + 5.0}
    strip = _strip(qtbot, clock, keys=("gas", "temp"))
    strip.set_limit("gas", "high", 1.8)
    strip.set_limit("temp", "low", 1.2)
    _shot(strip)
    _shot(strip)

    class Paints(QObject):
        n = 0

        def eventFilter(self, obj, ev):  # noqa: N802 - Qt's name
            if ev.type() == QEvent.Type.Paint:
                self.n += 1
            return False

    paints = Paints()
    strip._glw.viewport().installEventFilter(paints)
    for k in range(3):
        clock["t"] += 1.0
        strip.mark_dirty()
        strip.refresh()
        qtbot.waitUntil(lambda k=k: paints.n >= k + 1, timeout=2000)
        for _ in range(5):  # whatever the paint asked for is delivered too
            QApplication.processEvents()
        assert paints.n == k + 1
    # the limit lines are where their values are in the view that was painted
    vb = strip.plot_item("gas").vb
    line = next(iter(strip._channels["gas"].lines.values()))
    y_px = vb.mapViewToScene(pg.Point(clock["t"] - 100, 1.8)).y()
    assert abs(line.mapToScene(pg.Point(0, 0)).y() - y_px) < 0.5
