"""The main window's menus: Robot (the control keys, resume patrol), View, Alarms, File.

The control keys are handled by the control panel's key filter; the menu only names
them (text after a tab is shown as the shortcut)."""

from __future__ import annotations

from typing import Any

from PySide6.QtGui import QAction, QKeySequence

from app.core.i18n import translate
from app.ui.data_panel import WINDOWS_MIN

__all__ = ["build_menus"]


def _language_menu(window: Any, view: Any) -> None:
    """View ▸ Language: the choice is stored (QSettings ``ui/language``) and takes
    effect at the next start, which the status bar says."""
    from PySide6.QtGui import QActionGroup

    from app.i18n import LANGUAGES, language, store_language

    menu = view.addMenu(translate("MainWindow", "Language"))
    group = QActionGroup(window)
    window.language_actions = {}
    for code, name in LANGUAGES.items():
        a = QAction(name, window)  # each language in its own words
        a.setCheckable(True)
        a.setChecked(code == language())
        a.setData(code)
        group.addAction(a)
        menu.addAction(a)
        window.language_actions[code] = a

        def chosen(_=False, code=code) -> None:
            store_language(code)
            if code != language():
                window.statusBar().showMessage(translate(
                    "MainWindow", "Language: {name} from the next start of the desk").format(
                    name=LANGUAGES[code]), 15000)
        a.triggered.connect(chosen)




def build_menus(window: Any) -> None:
    """Add the menus to ``window`` (a MainWindow) and keep their actions on it."""
    mb = window.menuBar()
    robot = mb.addMenu(translate("MainWindow", "&Robot"))
    window.robot_menu = robot
    # the control keys are handled by the control panel's key filter; the
    # menu only names them (text after a tab is shown as the shortcut)
    a = QAction(translate("MainWindow", "EMERGENCY STOP\tEsc / F1"), window)
    a.triggered.connect(window.control_panel.request_estop)
    robot.addAction(a)
    a = QAction(translate("MainWindow", "Stop\tSpace"), window)
    a.triggered.connect(window.control_panel.request_stop)
    robot.addAction(a)
    a = QAction(translate("MainWindow", "Reset e-stop\tCtrl+Shift+R"), window)
    a.triggered.connect(window.control_panel.reset_estop_requested)
    robot.addAction(a)
    a = QAction(translate("MainWindow", "Faster\t+"), window)
    a.triggered.connect(lambda: window.control_panel.set_speed_mps(
        window.control_panel.speed_mps() + 0.05))
    robot.addAction(a)
    a = QAction(translate("MainWindow", "Slower\t-"), window)
    a.triggered.connect(lambda: window.control_panel.set_speed_mps(
        window.control_panel.speed_mps() - 0.05))
    robot.addAction(a)
    # F7 resumes the patrol from any tab: the map panel's action moves to the window
    robot.addSeparator()
    a = window.map_panel.actions_["resume"]
    window.map_panel.removeAction(a)
    a.setText(translate("MainWindow", "Resume patrol"))
    a.triggered.disconnect()
    a.triggered.connect(window.resume_patrol)
    window.addAction(a)
    robot.addAction(a)
    window.resume_action = a

    view = mb.addMenu(translate("MainWindow", "&View"))
    window.window_actions: dict[int, QAction] = {}
    for i, minutes in enumerate(WINDOWS_MIN, start=1):
        a = QAction(translate("MainWindow", "Plot window {minutes} min").format(minutes=minutes),
                    window)
        a.setShortcut(QKeySequence(f"Ctrl+{i}"))
        a.triggered.connect(lambda _=False, m=minutes: window.data_panel.set_window_minutes(m))
        view.addAction(a)
        window.addAction(a)
        window.window_actions[minutes] = a
    a = QAction(translate("MainWindow", "Reset layout"), window)
    a.setShortcut(QKeySequence("Ctrl+Shift+0"))
    a.setToolTip(translate("MainWindow", "Window size, panel sizes and plot window as when "
                                         "first started"))
    a.triggered.connect(window.reset_layout)
    view.addAction(a)
    window.addAction(a)
    window.reset_layout_action = a
    a = QAction(translate("MainWindow", "Full screen"), window)
    a.setShortcut(QKeySequence("F11"))
    a.triggered.connect(lambda: window.showNormal() if window.isFullScreen()
                        else window.showFullScreen())
    view.addAction(a)
    window.addAction(a)
    _language_menu(window, view)

    alarms = mb.addMenu(translate("MainWindow", "&Alarms"))
    ap = window.alarm_panel
    for a in (ap.ack_action, ap.ack_all_action, ap.mute_action):
        alarms.addAction(a)  # the panel holds them (window-wide shortcuts)
    alarms.addSeparator()
    window.alarm_settings_action = QAction(translate("MainWindow", "Alarm settings…"), window)
    window.alarm_settings_action.triggered.connect(window.open_alarm_settings)
    alarms.addAction(window.alarm_settings_action)

    file_menu = mb.addMenu(translate("MainWindow", "&File"))
    a = QAction(translate("MainWindow", "Show log folder"), window)
    a.setShortcut(QKeySequence("Ctrl+Shift+L"))
    a.triggered.connect(window.show_log_folder)
    file_menu.addAction(a)
    window.addAction(a)
    window.show_log_action = a
    a = QAction(translate("MainWindow", "Quit"), window)
    a.setShortcut(QKeySequence("Ctrl+Q"))
    a.triggered.connect(window.close)
    file_menu.addAction(a)
    window.addAction(a)
