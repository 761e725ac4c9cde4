"""The tank-wall view, offscreen: the window shows it (and hides the patrol
robot's tabs) once a climber describes its wall; coverage, thickness colours,
the robot and the thin-wall alarm follow the link's messages; its buttons are
intents."""

from __future__ import annotations

import numpy as np
from PySide6.QtGui import QColor

from app.comm import wall_protocol as W


def _wall():
    blocked = np.zeros((8, 24), bool)
    blocked[3:5, 10:13] = True
    labels = np.where(blocked, -1, (np.arange(24)[None, :] >= 12).astype(int) + 0 * blocked)
    path = [(r, c) for c in range(24) for r in (range(8) if c % 2 == 0 else range(7, -1, -1))
            if not blocked[r, c]]
    return W.WallInfo.build("tank-A", 0.1, blocked, labels, [0, 1], path, 10.0, 8.0)


def _pixel(view, row: int, col: int) -> QColor:
    """The colour drawn in a cell, off its centre (where the plan's line runs)."""
    img = view.grab().toImage()
    pt = view.to_widget((col + 0.2) * 0.1, (row + 0.2) * 0.1)
    return QColor(img.pixel(int(pt.x()), int(pt.y())))


def test_wall_tab_appears_for_a_climber_and_shows_coverage_heat_and_alarm(window, link,
                                                                         qtbot):
    win = window
    panel = win.wall_panel
    tab = win.views.indexOf(panel)
    assert not win.views.isTabVisible(tab)
    link.set_state("connected")
    link.wall_received.emit(_wall())
    qtbot.waitUntil(lambda: win.views.isTabVisible(tab) and win.views.currentIndex() == tab)
    assert not win.views.isTabVisible(win.views.indexOf(win.video_panel))
    assert not win.views.isTabVisible(win.views.indexOf(win.meter_panel))
    view = panel.view
    qtbot.waitUntil(lambda: view.redraws >= 1)
    blocked_px = _pixel(view, 3, 11)
    assert blocked_px.red() < 90 and blocked_px.green() < 90  # the nozzle, dark

    mask = np.zeros((8, 24), bool)
    mask[:, :6] = True
    link.wall_received.emit(W.CoverageProgress.build(mask, 186, 52, 48, 186, 1))
    link.wall_received.emit(W.ProbeReadings(np.array(
        [[0.05, 0.05, 9.9], [0.15, 0.05, 9.8], [0.35, 0.65, 7.3]], np.float32)))
    link.wall_received.emit(W.WallPose(0.35, 0.45, 1.57, 0.1, 0.0, 0.03))
    qtbot.waitUntil(lambda: panel.coverage_label.text() == "coverage 25.8 %")
    assert panel.repetition_label.text() == "repetition 2.2 %"
    assert panel.state_label.text() == "inspection running"
    assert "7.30 mm (below 8 mm)" in panel.thinnest_label.text()
    assert "x 0.35 m" in panel.thinnest_label.text()

    def drawn():
        good, thin, covered = _pixel(view, 0, 0), _pixel(view, 6, 3), _pixel(view, 7, 5)
        return (good.green() > 150 and good.red() < 120  # 9.9 mm: green
                and thin.red() > 150 and thin.green() < 40  # 7.3 mm, under the limit: red
                and covered.green() > covered.blue())  # covered, not measured
    qtbot.waitUntil(drawn)
    alarms = [a for a in win.pipeline.monitor.active() if a.key.startswith("wall.thin")]
    assert len(alarms) == 1 and "x 0.35 m round, y 0.65 m up" in alarms[0].description

    panel.buttons["pause_inspection"].click()
    assert ("command", "pause_inspection", {}) in link.calls


def test_layers_switch_off_the_heat_map(qtbot):
    from app.core.desk import DeskPipeline
    from app.ui.wall_panel import WallPanel, WallViewModel

    p = DeskPipeline()
    model = WallViewModel(p)
    panel = WallPanel(model)
    qtbot.addWidget(panel)
    panel.resize(600, 300)
    panel.show()
    qtbot.waitExposed(panel)
    p.ingest("wall", _wall())
    p.ingest("wall", W.ProbeReadings(np.array([[0.05, 0.05, 7.0]], np.float32)))
    view = panel.view
    qtbot.waitUntil(lambda: _pixel(view, 0, 0).red() > 150)
    panel.checks["heat"].setChecked(False)
    qtbot.waitUntil(lambda: _pixel(view, 0, 0).red() < 240 and
                    abs(_pixel(view, 0, 0).red() - _pixel(view, 0, 1).red()) < 3)
