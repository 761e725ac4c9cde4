"""The window's header: the most severe unacknowledged alarm, always visible.

After ISA-101: calm grey while nothing needs the operator; colour only for an
abnormal state, and never colour alone — each priority also has its own shape
and its name in the text (◆ EMERGENCY, ▲ HIGH, ■ MEDIUM, ● LOW), so the header
reads the same to a colour-blind operator or on a monochrome screen.
"""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QWidget

from app.core.alarms import Alarm, AlarmMonitor, AlarmState, Priority
from app.ui import theme

__all__ = ["AlarmBanner", "LOOK", "banner_text", "level_name", "priority_mark", "tile_level"]

ALARM_EMERGENCY = "#7a0019"
# priority -> (background, text colour, shape)
LOOK: dict[Priority, tuple[str, str, str]] = {
    Priority.EMERGENCY: (ALARM_EMERGENCY, "#ffffff", "◆"),
    Priority.HIGH: (theme.ALARM_HIGH, "#ffffff", "▲"),
    Priority.MEDIUM: (theme.ALARM_MEDIUM, "#000000", "■"),
    Priority.LOW: (theme.ALARM_LOW, "#000000", "●"),
}


def priority_mark(p: Priority) -> str:
    """Shape and name, e.g. "▲ HIGH"."""
    return f"{LOOK[Priority(p)][2]} {Priority(p).name}"


def level_name(p: Priority | None) -> str:
    """"emergency"/"high"/"medium"/"low", or "" for none."""
    return "" if p is None else Priority(p).name.lower()


def tile_level(p: Priority | None) -> str:
    """The value tiles' style level (they know high/medium/low; emergency shows as high)."""
    if p is None:
        return ""
    return theme.level_of(min(Priority(p), Priority.HIGH))


def banner_text(top: Alarm | None, unacked: int, standing: int, flood: bool) -> str:
    """The header's line (a pure function of the monitor's state)."""
    if top is None:
        if standing:
            return f"No unacknowledged alarms ({standing} standing, acknowledged)"
        return "No active alarms"
    rtn = "  (returned to normal)" if top.state is AlarmState.RTN_UNACK else ""
    more = f"   (+{unacked - 1} more unacknowledged)" if unacked > 1 else ""
    head = "ALARM FLOOD — " if flood else ""
    return f"{head}{priority_mark(top.priority)}: {top.text}{rtn}{more}"


class AlarmBanner(QLabel):
    """The header line, refreshed from the monitor (``refresh``)."""

    def __init__(self, monitor: AlarmMonitor, parent: QWidget | None = None) -> None:
        super().__init__("No active alarms", parent)
        self.monitor = monitor
        self.setObjectName("alarmBanner")
        self.setProperty("alarm", "")
        self.setToolTip("The most severe unacknowledged alarm (Ctrl+K acknowledges the "
                        "selected alarm, Ctrl+Shift+K all visible ones)")
        self.top: Alarm | None = None
        self.refresh()

    def refresh(self) -> None:
        m = self.monitor
        top = m.most_severe_unacknowledged()
        self.top = top
        self.setText(banner_text(top, len(m.unacknowledged()), len(m.active()),
                                 m.flood_active))
        level = "" if top is None else level_name(top.priority)
        if level != self.property("alarm"):
            self.setProperty("alarm", level)
            if top is None:
                self.setStyleSheet("")
            else:
                bg, fg, _ = LOOK[top.priority]
                self.setStyleSheet(f"QLabel#alarmBanner {{ background-color: {bg}; "
                                   f"color: {fg}; font-weight: bold; }}")
            self.style().unpolish(self)
            self.style().polish(self)

    def level(self) -> str:
        return self.property("alarm") or ""
