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
