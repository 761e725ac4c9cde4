"""The desk's layout lasts (QSettings in a temporary folder): change it, close the window,
open a new one -> restored; "Reset layout" -> the layout the window was built with."""

from __future__ import annotations

import pytest
from PySide6.QtCore import QRect, QSettings, QSize
from PySide6.QtWidgets import QSplitter

from app.ui.main_window import MainWindow
from app.ui.window_settings import WindowSettings, last_address, remember_address

from .fakes import FakeLink

pytestmark = pytest.mark.gui


@pytest.fixture
def settings(tmp_path):
    QSettings.setDefaultFormat(QSettings.Format.IniFormat)
    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, str(tmp_path))
    s = QSettings(str(tmp_path / "desk.ini"), QSettings.Format.IniFormat)
    s.setValue("ui/language", "zh_CN")  # someone else's setting: never touched here
    return s


def _open(qtbot, settings) -> MainWindow:
    win = MainWindow(FakeLink())
    qtbot.addWidget(win)
    if not win.keep_layout(settings):
        win.resize(1280, 800)
    win.show()
    qtbot.waitExposed(win)
    return win


def _sizes(win) -> dict[str, list[int]]:
    return {s.objectName(): s.sizes() for s in win.findChildren(QSplitter) if s.objectName()}


def test_layout_is_restored_after_a_restart_and_reset_gives_the_default(qtbot, settings):
    win = _open(qtbot, settings)
    default_sizes = _sizes(win)
    default_minutes = win.data_panel.window_minutes()
    assert set(default_sizes) == {"bodySplitter", "viewsSplitter", "controlSplitter"}

    least = win.minimumSizeHint()  # a size of the operator's, above the window's least
    size = (max(1300, least.width() + 30), max(850, least.height() + 30))
    win.resize(*size)
    qtbot.waitUntil(lambda: (win.width(), win.height()) == size)
    # the operator drags the split between the camera and the plots
    split = win.findChild(QSplitter, "viewsSplitter")
    left, right = split.sizes()
    split.setSizes([left + 150, right - 150])
    qtbot.waitUntil(lambda: split.sizes()[0] > left + 100)
    win.window_actions[60].trigger()
    assert win.data_panel.window_minutes() == 60
    win.close()
    geometry = settings.value("window/geometry")
    splitter_state = settings.value("window/splitter/viewsSplitter")
    assert geometry and splitter_state

    # a new window (a restart): the saved layout is applied before it is shown
    again = MainWindow(FakeLink())
    qtbot.addWidget(again)
    assert again.keep_layout(settings) is True
    assert again.findChild(QSplitter, "viewsSplitter").saveState() == splitter_state
    assert again.data_panel.window_minutes() == 60
    # the geometry is Qt's to fit to the screen (the offscreen one is 800 x 800 px):
    # the same as a window given the saved geometry, not the default size
    probe = MainWindow(FakeLink())
    qtbot.addWidget(probe)
    assert probe.restoreGeometry(geometry)
    assert again.geometry() == probe.geometry() != QRect(0, 0, 1440, 900)
    again.show()
    qtbot.waitExposed(again)

    again.reset_layout_action.trigger()
    # the default size, or what the platform makes of it on its small offscreen screen
    # (it may fit a shown window to the screen after the resize): as a fresh window's
    fresh = MainWindow(FakeLink())
    qtbot.addWidget(fresh)
    fresh.resize(1440, 900)
    fresh.show()
    qtbot.waitExposed(fresh)
    qtbot.waitUntil(lambda: again.size() in (QSize(1440, 900), fresh.size()), timeout=10000)
    assert again.size() != probe.size()  # not the operator's restored layout
    # the camera / plots split back to its first proportion (not the dragged one)
    a, b = again.findChild(QSplitter, "viewsSplitter").sizes()
    d0, d1 = default_sizes["viewsSplitter"]
    assert a / (a + b) == pytest.approx(d0 / (d0 + d1), abs=0.03)
    assert a / (a + b) < (left + 150) / (left + right) - 0.05
    assert again.data_panel.window_minutes() == default_minutes
    assert settings.value("window/geometry") is None  # forgotten
    assert settings.value("window/splitter/viewsSplitter") is None
    assert settings.value("ui/language") == "zh_CN"  # kept
    assert again.statusBar().currentMessage() == "Layout reset"


def test_a_window_without_saved_layout_keeps_its_size(qtbot, settings):
    win = MainWindow(FakeLink())
    qtbot.addWidget(win)
    assert win.keep_layout(settings) is False
    ws = WindowSettings(win, settings)
    settings.setValue("window/geometry", b"not a geometry")
    assert ws.restore() is False  # another version's value: skipped, not a crash


def test_last_robot_address_is_remembered(settings):
    assert last_address() is None
    remember_address("10.0.0.7", 9000)
    assert last_address() == "10.0.0.7:9000"


def test_show_log_folder_names_the_desk_log_folder(qtbot, settings, tmp_path, monkeypatch):
    from PySide6.QtGui import QDesktopServices

    opened = []
    monkeypatch.setattr(QDesktopServices, "openUrl", lambda url: opened.append(url) or True)
    monkeypatch.setenv("STATION_PATROL_LOG_DIR", str(tmp_path / "logs"))
    win = _open(qtbot, settings)
    win.show_log_action.trigger()
    assert [u.toLocalFile() for u in opened] == [str(tmp_path / "logs")]
    assert win.show_log_action.shortcut().toString() == "Ctrl+Shift+L"


def test_connect_alone_goes_to_the_last_robot(settings, capsys):
    from app.cli import main

    assert main(["--connect", "--headless"]) == 2
    assert "no robot connected to before" in capsys.readouterr().err
    remember_address("127.0.0.1", 9)  # discard: nothing answers there
    assert main(["--connect", "--headless"]) == 1
    assert "cannot connect to 127.0.0.1:9" in capsys.readouterr().err


def test_route_editor_opens_the_operator_routes_folder_not_the_cwd(qtbot, tmp_path,
                                                                  monkeypatch):
    from app.core.paths import ROUTES_ENV, resource
    from app.ui.route_editor import RouteEditor

    monkeypatch.chdir(tmp_path)  # a folder with no resources/ in it
    monkeypatch.setenv(ROUTES_ENV, str(tmp_path / "my-routes"))
    editor = RouteEditor()
    qtbot.addWidget(editor)
    assert editor._dir() == str(resource("routes"))  # no routes of the operator's yet
    (tmp_path / "my-routes").mkdir()
    assert editor._dir() == str(tmp_path / "my-routes")
