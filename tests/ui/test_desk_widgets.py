import numpy as np
import pytest
from PySide6.QtGui import QColor

from app.widgets import ImageView, OverlayRect, OverlayText, PlotStrip, StatusLamp, ValueTile

pytestmark = pytest.mark.gui


def _events(kind, widget):
    """(list, filter): the list collects the objects that receive events of ``kind``
    on ``widget`` while the filter is installed on it."""
    from PySide6.QtCore import QObject

    seen = []

    class Count(QObject):
        def eventFilter(self, obj, ev):  # noqa: N802 - Qt's name
            if ev.type() == kind:
                seen.append(obj)
            return False

    counter = Count()
    widget.installEventFilter(counter)
    return seen, counter


def test_plot_strip_pulls_dirty_channels_on_its_timer(qtbot):
    now = 1_000_000.0
    strip = PlotStrip(refresh_hz=20, window_s=60, clock=lambda: now)
    qtbot.addWidget(strip)
    strip.add_channel("a", "A", "u")
    strip.add_channel("b", "B")
    asked = []

    def source(key, seconds):
        asked.append((key, seconds))
        t = np.arange(10, dtype=float) + now - 10
        return t, t * 0 + (1.0 if key == "a" else 2.0)

    strip.set_source(source)
    qtbot.waitUntil(lambda: strip.curve("a").getData()[0] is not None
                    and len(strip.curve("a").getData()[0]) == 10, timeout=2000)
    assert {k for k, _ in asked} == {"a", "b"}
    n = len(asked)
    strip.refresh()  # nothing dirty: the source is not asked again
    assert len(asked) == n
    strip.mark_dirty("b")
    strip.refresh()
    assert asked[-1] == ("b", 60.0)
    strip.set_window(600)
    assert strip.window_s() == 600
    assert asked[-1][1] == 600
    lo, hi = strip.plot_item("a").viewRange()[0]
    assert hi == pytest.approx(now) and lo == pytest.approx(now - 600)


def test_plot_strip_limit_lines_stay_in_view(qtbot):
    strip = PlotStrip(clock=lambda: 100.0)
    qtbot.addWidget(strip)
    strip.add_channel("gas", "Gas", "%")
    strip.set_limit("gas", "high 10", 10.0)
    strip.set_source(lambda k, s: (np.array([90.0, 99.0]), np.array([0.5, 1.0])))
    strip.refresh()
    assert strip.limit_lines("gas") == {"high 10": 10.0}
    ylo, yhi = strip.plot_item("gas").viewRange()[1]
    assert ylo <= 0.5 and yhi >= 10.0
    strip.set_limit("gas", "high 10", None)
    assert strip.limit_lines("gas") == {}
    with pytest.raises(ValueError):
        strip.add_channel("gas", "again")


def test_value_tile_shows_value_and_alarm_level(qtbot):
    tile = ValueTile("Temp", "°C", fmt="{:.1f}")
    qtbot.addWidget(tile)
    assert tile.value_text() == "—"
    tile.set_value(21.345)
    assert tile.value_text() == "21.3"
    tile.set_value(float("nan"))
    assert tile.value_text() == "—"
    tile.set_alarm("high")
    assert tile.alarm_level() == "high" and tile.property("alarm") == "high"
    tile.set_alarm(None)
    assert tile.alarm_level() == ""


def test_status_lamp(qtbot):
    lamp = StatusLamp("x")
    qtbot.addWidget(lamp)
    lamp.set_status("lost", "#ff0000")
    assert lamp.text() == "lost" and lamp.color() == QColor("#ff0000")
    lamp.set_status("ok")
    assert lamp.color() is None
    lamp.grab()


def test_image_view_scales_with_aspect_and_rejects_bad_images(qtbot):
    view = ImageView()
    qtbot.addWidget(view)
    view.resize(400, 400)
    img = np.zeros((100, 200, 3), np.uint8)
    view.set_image(img)
    assert view.image_size() == (200, 100)
    r = view.target_rect()
    assert r.width() == pytest.approx(400) and r.height() == pytest.approx(200)
    assert r.y() == pytest.approx(100)
    view.set_overlays([OverlayRect(10, 10, 50, 20, label="dial"), OverlayText(5, 90, "hi")])
    view.set_caption("STALE")
    assert not view.grab().isNull()
    view.set_image(np.zeros((10, 10), np.uint8))  # grey is fine
    with pytest.raises(ValueError):
        view.set_image(np.zeros((10, 10, 4), np.uint8))
    with pytest.raises(ValueError):
        view.set_image(np.zeros((10, 10, 3), np.float32))
    view.set_image(None)
    assert view.image_size() is None


def test_plot_strip_refreshes_less_often_for_long_windows_and_labels_time_once(qtbot):
    from app.widgets.plot_strip import PlotStrip

    ps = PlotStrip(refresh_hz=5, window_s=60)
    qtbot.addWidget(ps)
    for k in ("a", "b", "c"):
        ps.add_channel(k, k)
    assert ps.refresh_interval_ms() == 200
    ps.set_window(600)  # 10 min: moves a pixel in about a second
    assert ps.refresh_interval_ms() == 1000
    ps.set_window(3600)
    assert ps.refresh_interval_ms() == 2000
    ps.set_window(60)
    assert ps.refresh_interval_ms() == 200
    shown = [ps.plot_item(k).getAxis("bottom").style["showValues"] for k in ("a", "b", "c")]
    assert shown == [False, False, True]


def test_image_view_paints_the_colours_it_was_given_from_its_own_copy(qtbot):
    """The image is kept converted for fast scaling (RGB32): red stays red and blue
    blue, grey stays grey, and a frame buffer the caller reuses afterwards does not
    change what is shown."""
    view = ImageView()
    qtbot.addWidget(view)
    view.resize(200, 100)
    img = np.zeros((50, 100, 3), np.uint8)
    img[:, :50] = (220, 10, 10)   # left half red
    img[:, 50:] = (10, 10, 220)   # right half blue
    view.set_image(img)
    img[:] = 0  # the caller reuses its buffer
    shot = view.grab().toImage()
    left, right = shot.pixelColor(50, 50), shot.pixelColor(150, 50)
    assert (left.red(), left.blue()) == (220, 10)
    assert (right.red(), right.blue()) == (10, 220)
    view.set_image(np.full((50, 100), 128, np.uint8))
    px = view.grab().toImage().pixelColor(100, 50)
    assert (px.red(), px.green(), px.blue()) == (128, 128, 128)


def test_plot_strip_keeps_its_value_range_while_the_data_fit_it(qtbot):
    """The value axis (its tick labels and grid, cached) is not moved at every
    refresh: data that still fit keep the range; data outside it, or far inside
    it, set a new one that holds data and limits."""
    data = {"y": np.array([1.0, 2.0])}
    strip = PlotStrip(clock=lambda: 100.0)
    qtbot.addWidget(strip)
    strip.add_channel("gas", "Gas", "%")
    strip.set_source(lambda k, s: (np.linspace(98.0, 99.0, len(data["y"])), data["y"]))
    strip.refresh()
    first = strip.plot_item("gas").viewRange()[1]
    assert first[0] < 1.0 and first[1] > 2.0
    data["y"] = np.array([1.1, 1.9, 1.5])
    strip.mark_dirty()
    strip.refresh()
    assert strip.plot_item("gas").viewRange()[1] == pytest.approx(first)
    data["y"] = np.array([1.0, 5.0])  # above the range
    strip.mark_dirty()
    strip.refresh()
    lo, hi = strip.plot_item("gas").viewRange()[1]
    assert lo < 1.0 and hi > 5.0
    data["y"] = np.array([20.0, 20.5])  # far from it: fitted anew, not kept loose
    strip.mark_dirty()
    strip.refresh()
    lo, hi = strip.plot_item("gas").viewRange()[1]
    assert 19.0 < lo < 20.0 and 20.5 < hi < 21.5


def test_value_tile_new_numbers_do_not_lay_out_the_window_again(qtbot):
    """A tile's number changes ten times a second: the label keeps its size, so no
    layout up to the window is computed again; a number wider than planned for
    still shows whole."""
    from PySide6.QtCore import QEvent
    from PySide6.QtWidgets import QApplication, QVBoxLayout, QWidget

    box = QWidget()
    qtbot.addWidget(box)
    tile = ValueTile("Gas", "%LEL", box, fmt="{:.1f}")
    QVBoxLayout(box).addWidget(tile)
    box.show()
    qtbot.waitExposed(box)
    QApplication.processEvents()
    requests, counter = _events(QEvent.Type.LayoutRequest, box)
    for v in (1.0, 22.5, -333.3, 7.0, float("nan")):
        tile.set_value(v)
        QApplication.processEvents()
    assert requests == [] and tile.value_text() == "—"
    tile.set_value(123456.7)
    QApplication.processEvents()
    number = tile.findChild(type(tile._number), "tileValue")
    assert number.width() >= number.fontMetrics().horizontalAdvance("123456.7")
    box.removeEventFilter(counter)


def test_steady_label_new_texts_do_not_lay_out_the_bar_again(qtbot):
    """A status field that changes every second keeps its size (growing only for a
    longer text): new texts reach the screen without a layout request upwards."""
    from PySide6.QtCore import QEvent
    from PySide6.QtWidgets import QApplication, QHBoxLayout, QWidget

    from app.widgets import SteadyLabel

    bar = QWidget()
    qtbot.addWidget(bar)
    label = SteadyLabel("RTT 10 ms", bar)
    QHBoxLayout(bar).addWidget(label)
    bar.show()
    qtbot.waitExposed(bar)
    QApplication.processEvents()
    requests, counter = _events(QEvent.Type.LayoutRequest, bar)
    w0 = label.width()
    for text in ("RTT 9 ms", "RTT 11 ms", "RTT 8 ms"):
        label.setText(text)
        QApplication.processEvents()
    assert requests == [] and label.text() == "RTT 8 ms" and label.width() == w0
    label.setText("RTT — ms (last known 12:00:00, 40 s ago)")  # longer: it grows
    QApplication.processEvents()
    assert label.width() >= label.fontMetrics().horizontalAdvance(label.text())
    label.setText("RTT 7 ms")  # and keeps that width
    QApplication.processEvents()
    assert label.width() > w0
    label.setMinimumWidth(label.width() + 50)
    assert label.width() >= label.minimumWidth() and label.minimumWidth() == label.maximumWidth()
    bar.removeEventFilter(counter)


def test_value_tile_same_freshness_again_changes_nothing(qtbot):
    """The freshness is given to every tile twice a second: the same age text again
    sends no tooltip change (a new one still shows)."""
    from PySide6.QtCore import QEvent

    tile = ValueTile("Temp", "°C")
    qtbot.addWidget(tile)
    changes, counter = _events(QEvent.Type.ToolTipChange, tile)
    tile.set_stale("last known 12:00:00, 4 s ago")
    tile.set_stale("last known 12:00:00, 4 s ago")
    assert len(changes) == 1 and tile.stale_text() == "last known 12:00:00, 4 s ago"
    tile.set_stale("last known 12:00:00, 5 s ago")
    tile.set_stale(None)
    tile.set_stale(None)
    assert len(changes) == 3 and not tile.is_stale() and tile.toolTip() == ""
    tile.removeEventFilter(counter)
