"""The desk's look, after ISA-101: calm greys for the normal state, colour only
for what is abnormal, so an alarm is the only thing that stands out.

Colours by meaning (not by decoration):

* HIGH priority alarm — red with white text
* MEDIUM priority alarm — amber with black text
* LOW priority alarm — yellow with black text
* link lost — amber, steady (no flashing): the desk's own link is abnormal
* stale data (a value shown that is no longer current: the link is down or the
  source went quiet) — no colour: grey text, a dashed outline, hatching on the
  value tiles and its age ("last known 15:17:21, 40 s ago"); an old number must
  not look like a live limit alarm
"""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtGui import QColor, QPalette
from PySide6.QtWidgets import QApplication

from app.core.alarms import Priority
from app.widgets.palette import (  # noqa: F401  (the theme's names for the colours)
    ABNORMAL,
    ACCENT,
    ALARM_HIGH,
    ALARM_LOW,
    ALARM_MEDIUM,
    BACKGROUND,
    BORDER,
    CURVE,
    ESTOP,
    GREY_DARK,
    GREY_MID,
    LIMIT_LINE,
    PANEL,
    PLOT_BACKGROUND,
    STALE_OUTLINE,
    STALE_TEXT,
    TEXT,
    TEXT_DIM,
)

LEVEL_NAMES: dict[Priority, str] = {Priority.HIGH: "high", Priority.MEDIUM: "medium",
                                    Priority.LOW: "low"}
LEVEL_COLORS: dict[str, str] = {"high": ALARM_HIGH, "medium": ALARM_MEDIUM,
                                "low": ALARM_LOW}
LEVEL_TEXT: dict[str, str] = {"high": "#ffffff", "medium": "#000000", "low": "#000000"}


def level_of(priority: Priority | int | None) -> str:
    """The style level name of an alarm priority ("" for none)."""
    if priority is None:
        return ""
    return LEVEL_NAMES.get(Priority(priority), "")


def color_of(priority: Priority | int | None) -> str | None:
    return LEVEL_COLORS.get(level_of(priority))


QSS = f"""
QGroupBox {{ border: 1px solid {BORDER}; border-radius: 3px; margin-top: 14px;
             background-color: {PANEL}; font-weight: bold; }}
QGroupBox::title {{ subcontrol-origin: margin; left: 8px; padding: 0 3px; }}
QPushButton {{ background-color: #c8c8c8; border: 1px solid {BORDER}; border-radius: 3px;
               padding: 5px 10px; min-height: 22px; }}
QPushButton:pressed, QPushButton:checked {{ background-color: #a9a9a9; }}
QPushButton:disabled {{ color: {TEXT_DIM}; }}
QPushButton#estopButton {{ background-color: {ESTOP}; color: #ffffff; font-size: 16pt;
                           font-weight: bold; border: 3px solid #5a0000; min-height: 56px; }}
QPushButton#estopButton:pressed {{ background-color: #8b0000; }}
QTableView, QPlainTextEdit, QListView#eventLog {{ background-color: #ededed;
    gridline-color: {BORDER}; selection-background-color: #9a9a9a; }}
QHeaderView::section {{ background-color: #c8c8c8; border: 0px; border-right: 1px solid {BORDER};
                        padding: 2px 4px; }}
QStatusBar {{ background-color: #c8c8c8; }}
QStatusBar QLabel {{ background-color: #c8c8c8; padding: 0 6px; }}
QStatusBar StatusLamp, QStatusBar StatusLamp QLabel {{ background-color: #c8c8c8; }}
QLabel#alarmBanner {{ background-color: {PANEL}; color: {TEXT_DIM}; padding: 4px 8px;
                      font-size: 12pt; border: 1px solid {BORDER}; }}
QLabel#alarmBanner[alarm="high"] {{ background-color: {ALARM_HIGH}; color: #ffffff;
                                    font-weight: bold; }}
QLabel#alarmBanner[alarm="medium"] {{ background-color: {ALARM_MEDIUM}; color: #000000;
                                      font-weight: bold; }}
QLabel#alarmBanner[alarm="low"] {{ background-color: {ALARM_LOW}; color: #000000;
                                   font-weight: bold; }}
QLabel[abnormal="true"] {{ color: #000000; background-color: {ABNORMAL}; font-weight: bold; }}
ValueTile {{ background-color: {PANEL}; border: 1px solid {BORDER}; border-radius: 3px; }}
ValueTile QLabel {{ background-color: transparent; }}
ValueTile QLabel#tileLabel, ValueTile QLabel#tileUnit {{ color: {TEXT_DIM}; }}
ValueTile[alarm="high"] {{ background-color: {ALARM_HIGH}; }}
ValueTile[alarm="high"] QLabel {{ color: #ffffff; }}
ValueTile[alarm="medium"] {{ background-color: {ALARM_MEDIUM}; }}
ValueTile[alarm="medium"] QLabel {{ color: #000000; }}
ValueTile[alarm="low"] {{ background-color: {ALARM_LOW}; }}
ValueTile[alarm="low"] QLabel {{ color: #000000; }}
ValueTile[stale="true"] {{ background-color: {PANEL}; border: 1px dashed {STALE_OUTLINE}; }}
ValueTile[stale="true"] QLabel {{ color: {STALE_TEXT}; }}
ValueTile QLabel#tileAge {{ color: {TEXT}; font-style: italic; }}
QLabel[stale="true"] {{ color: {STALE_TEXT}; background-color: transparent; font-style: italic;
                        border: 1px dashed {STALE_OUTLINE}; padding: 0 3px; }}
StatusLamp[stale="true"] QLabel {{ color: {STALE_TEXT}; font-style: italic; }}
"""


def palette() -> QPalette:
    pal = QPalette()
    for role, color in ((QPalette.ColorRole.Window, BACKGROUND),
                        (QPalette.ColorRole.Base, "#ededed"),
                        (QPalette.ColorRole.AlternateBase, PANEL),
                        (QPalette.ColorRole.Button, "#c8c8c8"),
                        (QPalette.ColorRole.WindowText, TEXT),
                        (QPalette.ColorRole.Text, TEXT),
                        (QPalette.ColorRole.ButtonText, TEXT)):
        pal.setColor(role, QColor(color))
    return pal


def configure_pyqtgraph() -> None:
    pg.setConfigOptions(background=PLOT_BACKGROUND, foreground=TEXT, antialias=False)


def apply_theme(app: QApplication) -> None:
    """Apply the style sheet and the plot colours (call before building windows)."""
    configure_pyqtgraph()
    app.setPalette(palette())
    app.setStyleSheet(QSS)
