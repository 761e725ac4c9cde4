"""The history view over a small generated archive."""

from __future__ import annotations

import csv
import time

import numpy as np
import pytest
from PySide6.QtCore import Qt

from app.core.records import Archive
from app.report.sample import write_sample
from app.ui.history_model import HistoryModel, journal_entries
from app.ui.history_view import HistoryView


@pytest.fixture
def recorded(tmp_path):
    a = Archive(tmp_path / "archive.sqlite3")
    run = write_sample(a, time.time() - 120.0)
    assert a.flush()
    yield a, run
    a.close()


@pytest.fixture
def view(qtbot, recorded):
    archive, run = recorded
    model = HistoryModel(archive)
    v = HistoryView(model)
    qtbot.addWidget(v)
    v.resize(1200, 700)
    v.show()
    model.set_range(run.t0 - 1.0, run.t1 + 1.0)
    v.refresh_channels(["gas_lel_pct"])
    with qtbot.waitSignal(model.journal_loaded, timeout=10000):
        model.load()
    yield v
    model.shutdown()


def test_plots_the_recorded_channel(view, recorded):
    _, run = recorded
    x, y = view.plotted("gas_lel_pct")
    assert np.allclose(x, run.telemetry_t)
    assert np.allclose(y, run.gas)
    assert view.plotted("temp_c") is None  # not ticked


def test_ticking_a_channel_adds_its_plot(qtbot, view):
    with qtbot.waitSignal(view.model.series_loaded, timeout=10000):
        view.set_channel_checked("temp_c", True)
    x, y = view.plotted("temp_c")
    assert y[0] == pytest.approx(20.0) and y[-1] == pytest.approx(22.99)


def test_long_range_is_downsampled_with_min_max(qtbot, recorded):
    archive, run = recorded
    model = HistoryModel(archive, max_points=20)
    v = HistoryView(model)
    qtbot.addWidget(v)
    model.set_range(run.t0, run.t1)
    model.set_channels(["gas_lel_pct"])
    with qtbot.waitSignal(model.series_loaded, timeout=10000):
        model.load()
    s = model.series[0]
    assert len(s.t) <= 20 and s.downsampled
    assert s.vmax.max() == pytest.approx(max(run.gas))  # the plume's peak survives
    assert s.vmin.min() == pytest.approx(min(run.gas))
    model.shutdown()


def test_journal_lists_alarms_and_events(view, recorded):
    _, run = recorded
    rows = [[view.journal.item(r, c).text() for c in range(4)]
            for r in range(view.journal.rowCount())]
    texts = [r[3] for r in rows]
    assert any("Gas high: NORMAL → UNACK" in t for t in texts)
    assert any("Gas high: UNACK → ACKED by ann" in t for t in texts)
    assert any("SHELVED by bob (sensor maintenance)" in t for t in texts)
    assert any(r[1] == "patrol" and "patrol started" in r[3] for r in rows)
    assert ["command", "ann", "start_patrol — done"] in [r[1:] for r in rows]
    times = [e.t for e in view.model.journal]
    assert times == sorted(times)


def test_clicking_an_alarm_moves_the_cursor_to_its_moment(qtbot, view, recorded):
    _, run = recorded
    row = next(i for i, e in enumerate(view.model.journal) if "→ ACKED" in e.text)
    assert view.cursor_position() is None
    rect = view.journal.visualRect(view.journal.model().index(row, 3))
    qtbot.mouseClick(view.journal.viewport(), Qt.MouseButton.LeftButton,
                     pos=rect.center())
    assert view.cursor_position() == pytest.approx(run.alarm_t["acked"])
    assert view.model.cursor == pytest.approx(run.alarm_t["acked"])


def test_export_writes_the_visible_range(view, recorded, tmp_path):
    _, run = recorded
    plot = view._plot_items["gas_lel_pct"]
    a, b = run.t0 + 5.0, run.t0 + 12.0
    plot.setXRange(a, b, padding=0)
    path = view.export_visible(str(tmp_path / "visible.csv"))
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    ts = [float(r["t"]) for r in rows]
    expect = [t for t in run.telemetry_t if a <= t <= b]
    assert len(rows) == len(expect) and min(ts) >= a - 1e-3 and max(ts) <= b + 1e-3
    assert list(rows[0].keys())[-1] == "gas_lel_pct"


def test_export_of_the_chosen_range_and_presets(view, recorded, tmp_path):
    _, run = recorded
    path = view.export_chosen(str(tmp_path / "all.csv"))  # from/to = the loaded range
    with open(path, newline="") as f:
        assert len(list(csv.DictReader(f))) == len(run.telemetry_t)
    t0, t1 = view.model.apply_preset("Last hour")
    assert t1 == pytest.approx(view.model.recorded_range()[1])
    assert t1 - t0 == pytest.approx(3600.0)


def test_bad_range_is_refused_with_a_message(view):
    view.from_edit.setDateTime(view.to_edit.dateTime().addSecs(60))
    view.apply_range()
    assert "must end after it starts" in view.last_error


def test_journal_entries_merge_in_time_order():
    tr = [{"t": 5.0, "alarm": "a", "text": "A", "from_state": "NORMAL", "to_state": "UNACK",
           "priority": "HIGH", "source": "x"}]
    ev = [{"t": 1.0, "kind": "link", "data": {"state": "lost", "level": "warning"}},
          {"t": 7.0, "kind": "fws_teb", "data": {"turning_in_place": False, "poses": []}},
          {"t": 9.0, "kind": "robot", "data": "not json {"}]
    out = journal_entries(tr, ev)  # a 4WS robot's TEB plan record is map data, not listed
    assert [e.t for e in out] == [1.0, 5.0, 9.0]
    assert out[0].text == "lost" and out[1].severity == "HIGH"
    assert out[2].text == "not json {"


def test_preset_box_says_what_is_shown(qtbot, view, recorded):
    _, run = recorded
    assert view.preset.currentText() == "From / to"  # the fixture set its own range
    with qtbot.waitSignal(view.model.series_loaded, timeout=10000):
        view.select_preset("Last shift (8 h)")
    assert view.preset.currentText() == "Last shift (8 h)"
    assert view.model.t1 - view.model.t0 == pytest.approx(8 * 3600.0)
    assert view.model.t1 == pytest.approx(run.t1)
    view.model.set_range(run.t0, run.t1)
    assert view.preset.currentText() == "From / to"
