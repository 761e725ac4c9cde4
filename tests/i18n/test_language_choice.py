"""Which language the desk starts in: --lang, then the stored setting, then the system;
the View menu stores the choice for the next start."""

from __future__ import annotations

import pytest
from PySide6.QtCore import QLocale, QSettings, QStandardPaths

from app.i18n import SETTINGS_KEY, choose_language, install_language, language

pytestmark = pytest.mark.gui


@pytest.fixture
def settings(qapp, tmp_path, monkeypatch):
    """QSettings in a folder of the test's own (never the user's)."""
    QStandardPaths.setTestModeEnabled(True)
    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path))
    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, str(tmp_path))
    QSettings().remove(SETTINGS_KEY)
    yield QSettings()
    QSettings().remove(SETTINGS_KEY)


def test_command_line_wins_over_setting_and_system(settings, monkeypatch):
    settings.setValue(SETTINGS_KEY, "en")
    assert choose_language("zh_CN") == "zh_CN"
    settings.setValue(SETTINGS_KEY, "zh_CN")
    assert choose_language("en") == "en"
    assert choose_language(None) == "zh_CN"  # the stored setting


def test_system_locale_when_nothing_is_chosen(settings, monkeypatch):
    monkeypatch.setattr(QLocale, "system", staticmethod(lambda: QLocale("zh_CN")))
    assert choose_language(None) == "zh_CN"
    monkeypatch.setattr(QLocale, "system", staticmethod(lambda: QLocale("fr_FR")))
    assert choose_language(None) == "en"  # no French: the source text


def test_view_menu_stores_the_language_for_the_next_start(settings, qtbot):
    from app.ui.main_window import MainWindow
    from tests.ui.fakes import FakeLink

    assert install_language("en") == "en" and language() == "en"
    win = MainWindow(FakeLink())
    qtbot.addWidget(win)
    assert win.language_actions["en"].isChecked()
    win.language_actions["zh_CN"].trigger()
    assert QSettings().value(SETTINGS_KEY) == "zh_CN"
    assert "简体中文" in win.statusBar().currentMessage()  # takes effect at the next start
    assert choose_language(None) == "zh_CN"
    assert language() == "en"  # this window stays as it started


def test_installing_english_after_chinese_gives_the_source_text_back(qapp):
    from app.core.freshness import age_text

    install_language("zh_CN", qapp)
    assert age_text(40) == "40 s 前"
    install_language("en", qapp)
    assert age_text(40) == "40 s ago"
