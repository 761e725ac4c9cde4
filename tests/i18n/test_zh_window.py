"""The desk's window in zh_CN shows no English left untranslated."""

from __future__ import annotations

import pytest

from tests.ui.fakes import FakeLink, make_frame

from .untranslated import find_untranslated, untranslated, visible_texts

pytestmark = pytest.mark.gui


def test_checker_names_english_words_and_passes_units_codes_and_chinese():
    assert untranslated("Alarm settings…") == ["Alarm", "settings"]
    assert untranslated("燃气浓度 12.5 %LEL · RTT 40 ms") == []
    assert untranslated("急停\tEsc / F1") == []
    assert untranslated("PG-302 压力表 0.42 MPa") == []
    assert untranslated("link lost") == ["link", "lost"]


@pytest.fixture
def zh_window(zh, qtbot):
    from app.ui.main_window import MainWindow

    link = FakeLink()
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.resize(1280, 800)
    win.show()
    qtbot.waitExposed(win)
    link.set_state("connected")
    link.send_telemetry()
    link.frame_decoded.emit(make_frame())
    qtbot.waitUntil(lambda: win.telemetry_model.samples > 0)
    return win, link


def test_main_window_in_chinese_has_no_untranslated_text(zh_window):
    win, _link = zh_window
    texts = visible_texts(win)
    assert len(texts) > 100  # the walk reaches the panels, menus and status bar
    assert any("巡检" in t or "报警" in t for _w, t in texts)
    left = find_untranslated(win)
    assert not left, f"{len(left)} untranslated:\n" + "\n".join(left)


def test_main_window_in_chinese_after_link_loss(zh_window, qtbot):
    win, link = zh_window
    link.set_state("lost")
    qtbot.waitUntil(lambda: "链路" in win.link_status_text())
    left = find_untranslated(win)
    assert not left, f"{len(left)} untranslated:\n" + "\n".join(left)


def test_main_window_in_chinese_through_a_patrol_an_estop_and_a_link_loss(zh_window, qtbot):
    """The texts built at run time: patrol lines and points, e-stop delivery, link
    figures, alarm rows and the event log."""
    from app.comm import protocol as P
    from tests.ui.fakes import Stats

    win, link = zh_window
    points = [{"name": "PG-302", "kind": "meter", "x_m": 1.0, "y_m": 2.0, "state": "done"},
              {"name": "V-12", "kind": "valve", "x_m": 3.0, "y_m": 2.0, "state": "current"},
              {"name": "WP-1", "kind": "waypoint", "x_m": 5.0, "y_m": 2.0, "state": "pending"}]
    link.patrol_status_received.emit(P.PatrolStatus(
        state="paused", route="default", index=1, points=points,
        reason="operator took over (drive)", progress=0.4))
    win.map_model.flush()
    assert "F7" in win.patrol_text() and "巡检" in win.patrol_text()
    link.stats_changed.emit(Stats())
    link.send_telemetry(gas_lel_pct=30.0, battery_v=21.5)
    qtbot.waitUntil(lambda: len(win.telemetry_model.monitor.active()) >= 2, timeout=5000)
    win.control_panel.request_estop()  # sent, waiting for the robot's acknowledgement
    link.set_state("lost")  # ... which cannot come now: not delivered
    qtbot.waitUntil(lambda: "急停未送达" in win.banner_text()
                    or "急停未送达" in win.statusBar().currentMessage(), timeout=5000)
    win.resume_patrol()  # refused without a link: says so
    left = find_untranslated(win)
    assert not left, f"{len(left)} untranslated:\n" + "\n".join(left)
    log = "\n".join(win.alarm_panel.log_lines())
    assert "急停" in log and "链路" in log
