"""What the GUI thread does for each message is no more than the shown views need:
the alarm list announces only changed rows, the camera's figures do not make the
window lay itself out again, and a hidden map works out no uncertainty ellipse."""

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QObject
from PySide6.QtWidgets import QStyledItemDelegate

from app.comm import protocol as P
from app.core.alarms import AlarmMonitor, LimitRule, Priority
from app.ui.alarm_panel import COLUMNS, AlarmPanel

from .fakes import make_frame

pytestmark = pytest.mark.gui

T0 = 1_800_000_000.0


class _Count(QObject):
    """Counts the events of one type delivered to an object."""

    def __init__(self, kind: QEvent.Type) -> None:
        super().__init__()
        self.kind = kind
        self.n = 0

    def eventFilter(self, _obj, ev):  # noqa: N802 - Qt's name
        if ev.type() == self.kind:
            self.n += 1
        return False


def test_alarm_list_refresh_announces_changed_rows_and_does_not_reset(qtbot):
    mon = AlarmMonitor([LimitRule("temp_c", high=45.0, unit="°C", label="Temperature"),
                        LimitRule("gas_lel_pct", high=10.0, unit="%LEL", label="Gas",
                                  priority=Priority.HIGH)])
    panel = AlarmPanel(mon, user="ana", clock=lambda: T0)
    mon.add_listener(panel.on_transition)
    qtbot.addWidget(panel)
    panel.show()
    mon.update_many({"temp_c": 50.0, "gas_lel_pct": 12.0}, T0)
    assert panel.model.rowCount() == 2
    resets, changed = [], []
    panel.model.modelReset.connect(lambda: resets.append(1))
    panel.model.dataChanged.connect(lambda a, b, *_: changed.append((a.row(), b.row())))
    panel.select_row(0)
    selected = panel.selected_keys()

    panel.refresh()  # the once-a-second refresh with nothing changed: nothing announced
    panel.refresh()
    assert resets == [] and changed == []

    mon.update_many({"temp_c": 51.5, "gas_lel_pct": 12.0}, T0 + 1)  # a value moves
    panel.refresh()
    assert resets == []
    row = next(r for r in range(2) if panel.model.keys_at(r)[0].startswith("temp_c"))
    assert changed == [(row, row)]
    assert "51.50" in " ".join(panel.model.cells(row))
    assert panel.selected_keys() == selected  # the selection is kept

    mon.update_many({"temp_c": 20.0, "gas_lel_pct": 12.0}, T0 + 2)  # a row's state changes
    panel.refresh()
    assert resets == [] or panel.model.rowCount() != 2
    mon.acknowledge_all(panel.visible_keys(), T0 + 3, user="ana")
    panel.refresh()  # the cleared, acknowledged alarm leaves the list: a reset
    assert panel.model.rowCount() == 1 and resets
    assert panel.model.keys_at(0)[0].startswith("gas_lel_pct")


def test_camera_frames_do_not_lay_the_window_out_again(qtbot, window, link):
    vp = window.video_panel
    for i in range(1000, 1005):  # the figures' widest text so far
        link.frame_decoded.emit(make_frame(i, latency_ms=55.0 + i % 3))
    qtbot.wait(50)
    layouts = _Count(QEvent.Type.LayoutRequest)
    vp.installEventFilter(layouts)
    for i in range(1005, 1040):
        link.frame_decoded.emit(make_frame(i, latency_ms=55.0 + i % 3))
        qtbot.wait(1)
    qtbot.wait(50)
    vp.removeEventFilter(layouts)
    assert vp.frame_label.text().startswith("frame 1039")
    assert layouts.n == 0


def _quality_pose(x, y, th):
    return P.Pose.unpack(P.Pose(x, y, th, 0.0, 0.0, 0.04, 0.0, 0.01, 1e-4, 0.9, 0.03,
                                P.Pose.STATUS_TRACKING).pack())


def test_hidden_map_works_out_no_uncertainty_ellipse_until_drawn(qtbot, window, link,
                                                                  monkeypatch):
    import app.ui.map_model as mm

    made = []
    real = mm.covariance_ellipse
    monkeypatch.setattr(mm, "covariance_ellipse", lambda *a, **k: made.append(1) or real(*a, **k))
    window.views.setCurrentWidget(window.video_panel)
    for i in range(20):
        link.pose_received.emit(_quality_pose(1.0 + 0.1 * i, 2.0, 0.0))
    window.map_model.flush()
    assert made == []
    panel = window.map_panel
    window.views.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: len(panel.view.polyline("uncertainty")) > 0, timeout=2000)
    assert len(made) == 1
    e = panel.view.polyline("uncertainty")
    assert np.mean(e[:, 0]) == pytest.approx(2.9, abs=0.05)  # around the latest pose


def test_a_burst_of_telemetry_shows_the_newest_sample_once(qtbot, window, link, monkeypatch):
    """Samples delivered in one pass of the event loop (a backlog after the desk was
    not scheduled) all reach the series and the alarms; the tiles show the newest."""
    tile = window.data_panel.tiles["temp_c"]
    shown = []
    real = tile.set_value
    monkeypatch.setattr(tile, "set_value", lambda v: shown.append(v) or real(v))
    for i in range(10):
        link.send_telemetry(temp_c=20.0 + i)
    assert len(window.telemetry_model.series("temp_c")) == 10
    qtbot.waitUntil(lambda: tile.value_text() == "29.0", timeout=2000)
    assert shown == [29.0]


def test_a_burst_of_poses_shows_the_newest_pose_once(qtbot, window, link, monkeypatch):
    label = window.pose_label
    link.pose_received.emit(P.Pose(0.0, 2.0, 0.0))
    qtbot.waitUntil(lambda: label.text().startswith("x 0.00 m"), timeout=2000)
    texts = []
    real = label.setText
    monkeypatch.setattr(label, "setText", lambda t: texts.append(t) or real(t))
    for i in range(1, 11):
        link.pose_received.emit(P.Pose(float(i), 2.0, 0.0))
    qtbot.waitUntil(lambda: label.text().startswith("x 10.00 m"), timeout=2000)
    assert set(texts) == {label.text()}  # no pose but the newest was put in the label


class _Measuring(QStyledItemDelegate):
    """The table's delegate, noting the rows whose cells the view measures."""

    def __init__(self, parent) -> None:
        super().__init__(parent)
        self.rows: list[int] = []

    def sizeHint(self, option, index):  # noqa: N802 - Qt's name
        self.rows.append(index.row())
        return super().sizeHint(option, index)


def test_alarm_list_refresh_measures_only_the_changed_row_and_columns_fit(qtbot):
    keys = ("temp_c", "humidity_pct", "gas_lel_pct", "noise_db")
    mon = AlarmMonitor([LimitRule(k, high=10.0, unit="u", label=k) for k in keys])
    panel = AlarmPanel(mon, user="ana", clock=lambda: T0)
    mon.add_listener(panel.on_transition)
    qtbot.addWidget(panel)
    panel.resize(1200, 500)
    panel.show()
    mon.update_many({k: 11.0 for k in keys}, T0)
    qtbot.wait(20)
    assert panel.model.rowCount() == len(keys)
    table, hh = panel.table, panel.table.horizontalHeader()
    delegate = _Measuring(table)
    table.setItemDelegate(delegate)
    value_col = COLUMNS.index("Value")

    def fits() -> bool:  # every cell's text fits its column (the last one stretches)
        return all(hh.sectionSize(c) >= table.sizeHintForIndex(panel.model.index(r, c)).width()
                   for r in range(panel.model.rowCount()) for c in range(len(COLUMNS) - 1))

    row = next(r for r in range(len(keys)) if panel.model.keys_at(r)[0].startswith("temp_c"))
    delegate.rows.clear()
    mon.update_many({"temp_c": 12.5}, T0 + 1)  # one value moves, no wider
    panel.refresh()
    qtbot.wait(20)
    assert set(delegate.rows) <= {row}  # the other rows are not measured again
    assert panel.model.rowCount() == len(keys)

    narrow = hh.sectionSize(value_col)
    mon.update_many({"temp_c": 123456789.25}, T0 + 2)  # a wider value: its column widens
    panel.refresh()
    qtbot.wait(20)
    assert hh.sectionSize(value_col) > narrow and fits()
    mon.update_many({"temp_c": 12.5}, T0 + 3)  # and narrows again when it is gone
    panel.refresh()
    qtbot.wait(20)
    assert hh.sectionSize(value_col) == narrow and fits()


def test_a_new_alarm_row_asks_the_delegate_only_about_texts_not_seen_before(qtbot):
    keys = [f"sensor_{i}" for i in range(40)]
    mon = AlarmMonitor([LimitRule(k, high=10.0, unit="u", label="Probe") for k in keys])
    panel = AlarmPanel(mon, user="ana", clock=lambda: T0)
    mon.add_listener(panel.on_transition)
    qtbot.addWidget(panel)
    panel.resize(1200, 500)
    panel.show()
    mon.update_many({k: 11.0 for k in keys[:39]}, T0)
    panel.refresh()
    qtbot.wait(20)
    table, hh = panel.table, panel.table.horizontalHeader()
    rows_before = panel.model.rowCount()
    assert rows_before >= 39
    table.measured = 0
    mon.update_many({keys[39]: 11.0}, T0)  # one more alarm, same time, same texts
    panel.refresh()
    qtbot.wait(20)
    assert panel.model.rowCount() == rows_before + 1
    # the list was reset (a new row), yet its 40 rows' cells were not all measured again:
    # only the texts no other row had (the new row's source)
    assert table.measured <= 2
    fits = all(hh.sectionSize(c) >= table.sizeHintForIndex(panel.model.index(r, c)).width()
               for r in range(rows_before + 1) for c in range(len(COLUMNS) - 1))
    assert fits
    font = table.font()  # a larger font: every width is measured again and still fits
    font.setPointSize(font.pointSize() + 6)
    table.setFont(font)
    qtbot.wait(20)
    assert all(hh.sectionSize(c) >= table.sizeHintForIndex(panel.model.index(r, c)).width()
               for r in range(rows_before + 1) for c in range(len(COLUMNS) - 1))
