"""The desk's other windows and dialogs in zh_CN: alarm settings, shelve and out of
service, history and replay (over a recorded sample patrol), calibration."""

from __future__ import annotations

import time

import numpy as np
import pytest
from PySide6.QtWidgets import QMainWindow

from app.core.records import Archive
from app.core.records.paths import default_archive_path
from app.report.sample import write_sample
from tests.ui.fakes import FakeLink

from .untranslated import find_untranslated, visible_texts

pytestmark = pytest.mark.gui


def _assert_translated(widget) -> None:
    texts = visible_texts(widget)
    assert texts, f"nothing visible in {widget!r}"
    left = find_untranslated(widget)
    assert not left, f"{len(left)} untranslated:\n" + "\n".join(left)


@pytest.fixture
def zh_window(zh, qtbot):
    from app.ui.main_window import MainWindow

    link = FakeLink()
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.show()
    link.set_state("connected")
    return win, link


def test_alarm_settings_dialog(zh_window, qtbot):
    from app.ui.alarm_dialogs import AlarmSettingsDialog

    win, _ = zh_window
    dlg = AlarmSettingsDialog(win.telemetry_model.alarm_config, win)
    qtbot.addWidget(dlg)
    _assert_translated(dlg)
    # the source column names still address the cells (tests, scripts)
    dlg.set_cell("temp_c", "High", "40")
    dlg.set_cell("temp_c", "Priority", "EMERGENCY")
    assert dlg.config() is not None


def test_shelve_and_out_of_service_dialogs_on_a_raised_alarm(zh_window, qtbot):
    from app.ui.alarm_dialogs import OutOfServiceDialog, ShelveDialog

    win, link = zh_window
    link.send_telemetry(gas_lel_pct=40.0)
    qtbot.waitUntil(lambda: bool(win.telemetry_model.monitor.active()), timeout=5000)
    _assert_translated(win)  # the alarm row, banner and log in Chinese
    alarm = win.telemetry_model.monitor.active()[0]
    assert "燃气" in alarm.text or "上限" in alarm.text or "高于" in alarm.text
    for dlg in (ShelveDialog(alarm, 8 * 3600.0, win), OutOfServiceDialog(alarm, win)):
        qtbot.addWidget(dlg)
        _assert_translated(dlg)


@pytest.fixture
def review(zh, qtbot, tmp_path):
    from app.ui.history_window import install_review_menu
    from app.ui.main_window import MainWindow

    a = Archive(default_archive_path(tmp_path))
    write_sample(a, time.time() - 200.0)
    a.close()
    win = QMainWindow()
    win.data_dir = str(tmp_path)
    qtbot.addWidget(win)
    rv = install_review_menu(win, replay_window=MainWindow)
    yield rv
    for w in rv.history_windows + rv.replay_windows:
        w.close()
    rv.close_archive()


def test_history_window(review, qtbot):
    review.history_action.trigger()
    hw = review.history_windows[-1]
    qtbot.waitUntil(lambda: not hw.model.busy and len(hw.model.series) > 0, timeout=10000)
    _assert_translated(hw)


def test_replay_window(review, qtbot):
    rw = review.open_replay()
    rw.link.play()
    rw.link.step(3.0)
    qtbot.waitUntil(lambda: rw.telemetry_model.samples > 0, timeout=5000)
    assert "回放" in rw.windowTitle() and "回放" in rw.banner_text()
    _assert_translated(rw)


def test_calibration_dialog(zh, qtbot):
    from app.ui.calibration_dialog import CalibrationDialog

    img = np.zeros((120, 160, 3), np.uint8)
    dlg = CalibrationDialog(img)
    qtbot.addWidget(dlg)
    _assert_translated(dlg)
