"""The Review menu: history, replay and report windows over the desk's archive."""

from __future__ import annotations

import gc
import time
import weakref

import pytest
from PySide6.QtWidgets import QMainWindow

from app.core.records import Archive
from app.core.records.paths import default_archive_path
from app.report.sample import write_sample
from app.ui.history_window import install_review_menu
from app.ui.main_window import MainWindow


@pytest.fixture
def desk(qtbot, tmp_path):
    a = Archive(default_archive_path(tmp_path))
    run = write_sample(a, time.time() - 200.0)
    a.close()
    win = QMainWindow()
    win.data_dir = str(tmp_path)
    qtbot.addWidget(win)
    review = install_review_menu(win, replay_window=MainWindow)
    yield win, review, run
    for w in review.history_windows + review.replay_windows:
        w.close()
    review.close_archive()


def test_menu_names_its_keys(desk):
    win, review, _ = desk
    keys = {a.text(): a.shortcut().toString() for a in
            (review.history_action, review.replay_action, review.report_action)}
    assert keys == {"History…": "Ctrl+H", "Replay the last hour…": "Ctrl+Shift+P",
                    "Patrol report (last 24 h)…": "Ctrl+Shift+E"}
    assert review.history_action in win.actions()


def test_history_opens_on_the_last_hour(qtbot, desk):
    _win, review, run = desk
    review.history_action.trigger()
    hw = review.history_windows[-1]
    qtbot.waitUntil(lambda: not hw.model.busy and len(hw.model.series) > 0, timeout=10000)
    assert hw.model.t1 == pytest.approx(run.t1)  # the end of the recording
    assert hw.model.t1 - hw.model.t0 == pytest.approx(3600.0)
    assert hw.view.plotted(hw.model.channels[0]) is not None
    assert hw.view.journal.rowCount() > 0


def test_closed_history_and_replay_windows_are_deleted_and_forgotten(qtbot, desk):
    _win, review, _run = desk
    hw, rw = review.open_history(), review.open_replay()
    rw.link.play()
    model = hw.model
    qtbot.waitUntil(lambda: not model.busy, timeout=10000)
    assert review.history_windows == [hw] and review.replay_windows == [rw]
    history, replay = weakref.ref(hw), weakref.ref(rw)
    hw.close()
    rw.close()
    del hw, rw
    qtbot.waitUntil(lambda: review.history_windows == [] == review.replay_windows,
                    timeout=10000)  # deleted, and gone from the lists
    gc.collect()
    assert history() is None
    assert replay() is None  # its link held it (connections to its closures)


def test_replay_opens_a_view_only_desk(qtbot, desk):
    _win, review, run = desk
    rw = review.open_replay()
    link = rw.link
    assert link.clock.t1 == pytest.approx(run.t1)
    cp = rw.control_panel
    assert rw.replay_mode and cp.estop_button.isHidden() and cp.drive_box.isHidden()
    assert not cp.estop_button.isEnabled() and not cp.replay_label.isHidden()
    link.play()
    link.step(3.0)
    assert rw.telemetry_model.samples > 0


def test_report_is_written_off_the_gui_thread(qtbot, desk, tmp_path):
    _win, review, run = desk
    out = tmp_path / "r.html"
    with qtbot.waitSignal(review.report_written, timeout=20000):
        assert review.ask_report(str(out))
    html = out.read_text(encoding="utf-8")
    assert "PG-102" in html and "0.910 MPa" in html


def test_without_an_archive_it_says_so(qtbot, tmp_path):
    win = QMainWindow()
    win.data_dir = str(tmp_path / "none")
    qtbot.addWidget(win)
    review = install_review_menu(win, replay_window=MainWindow)
    assert review.open_history() is None
    assert "no archive" in win.statusBar().currentMessage()


def test_the_desk_window_has_the_review_menu(window):
    titles = [a.text() for a in window.menuBar().actions()]
    assert "Re&view" in titles
    assert window.review.history_action in window.actions()
    assert window.review.report_action.shortcut().toString() == "Ctrl+Shift+E"
