"""The window's header: the most severe unacknowledged alarm, always visible.

After ISA-101: calm grey while nothing needs the operator; colour only for an
abnormal state, and never colour alone — each priority also has its own shape
and its name in the text (◆ EMERGENCY, ▲ HIGH, ■ MEDIUM, ● LOW), so the header
reads the same to a colour-blind operator or on a monochrome screen.

A latched safety state of the robot (e-stop engaged, fail-safe stop) is a
state, not an alarm: acknowledging its alarm silences the alarm, but the header
shows the state, in its colour, for as long as the robot reports it
(``set_latched``). In a replay the header starts with "REPLAY hh:mm:ss ×2"
(the replay's position and speed, ``set_replay``), so a recorded alarm is never
taken for a live one.
"""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QWidget

from app.comm.protocol import AlarmFlag, RobotMode
from app.core.alarms import Alarm, AlarmMonitor, AlarmState, Priority
from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui import theme

__all__ = ["AlarmBanner", "LOOK", "banner_text", "latched_states", "level_name",
           "priority_mark", "tile_level"]

REPLAY_LOOK = ("#2f4f6f", "#ffffff")  # calm blue-grey: not an alarm colour

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
    return f"{LOOK[Priority(p)][2]} {translate('Priority', _PRIORITY_NAMES[Priority(p)])}"


_PRIORITY_NAMES = {Priority.EMERGENCY: QT_TRANSLATE_NOOP("Priority", "EMERGENCY"),
                   Priority.HIGH: QT_TRANSLATE_NOOP("Priority", "HIGH"),
                   Priority.MEDIUM: QT_TRANSLATE_NOOP("Priority", "MEDIUM"),
                   Priority.LOW: QT_TRANSLATE_NOOP("Priority", "LOW")}


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
            return translate("AlarmBanner", "No unacknowledged alarms ({standing} standing, "
                             "acknowledged)").format(standing=standing)
        return translate("AlarmBanner", "No active alarms")
    rtn = (translate("AlarmBanner", "  (returned to normal)")
           if top.state is AlarmState.RTN_UNACK else "")
    more = (translate("AlarmBanner", "   (+{n} more unacknowledged)").format(n=unacked - 1)
            if unacked > 1 else "")
    head = translate("AlarmBanner", "ALARM FLOOD — ") if flood else ""
    return f"{head}{priority_mark(top.priority)}: {top.text}{rtn}{more}"


def latched_states(mode: int | None, flags: int) -> list[tuple[Priority, str]]:
    """The robot's latched safety states from its mode and alarm flags, most
    severe first: they hold until the robot is reset, whatever the alarm list says."""
    out: list[tuple[Priority, str]] = []
    if mode == RobotMode.ESTOP or flags & AlarmFlag.ESTOP:
        out.append((Priority.EMERGENCY, translate(
            "AlarmBanner", "E-STOP ENGAGED — the robot holds still until reset (Ctrl+Shift+R)")))
    if mode == RobotMode.FAILSAFE or flags & AlarmFlag.FAILSAFE_STOP:
        out.append((Priority.HIGH, translate("AlarmBanner",
                                             "FAIL-SAFE STOP — the robot stopped itself")))
    return out


class AlarmBanner(QLabel):
    """The header line, refreshed from the monitor (``refresh``)."""

    def __init__(self, monitor: AlarmMonitor, parent: QWidget | None = None) -> None:
        super().__init__(translate("AlarmBanner", "No active alarms"), parent)
        self.monitor = monitor
        self.setObjectName("alarmBanner")
        self.setProperty("alarm", "")
        self.setToolTip(self.tr("The most severe unacknowledged alarm (Ctrl+K acknowledges the "
                        "selected alarm, Ctrl+Shift+K all visible ones)"))
        self.top: Alarm | None = None
        self.latched: list[tuple[Priority, str]] = []
        self.replay_text = ""
        self.refresh()

    def set_latched(self, states: list[tuple[Priority, str]]) -> None:
        """The robot's latched safety states (``latched_states``); [] when none."""
        if states != self.latched:
            self.latched = list(states)
            self.refresh()

    def set_replay(self, text: str) -> None:
        """"REPLAY hh:mm:ss ×2 …" while the window plays an archive back; "" live."""
        if text != self.replay_text:
            self.replay_text = text
            self.refresh()

    def refresh(self) -> None:
        m = self.monitor
        top = m.most_severe_unacknowledged()
        self.top = top
        parts = [self.replay_text] if self.replay_text else []
        parts += [f"{priority_mark(p)}: {text}" for p, text in self.latched]
        parts.append(banner_text(top, len(m.unacknowledged()), len(m.active()),
                                 m.flood_active))
        self.setText("   |   ".join(parts))
        # the state holds its colour whether or not its alarm was acknowledged
        prios = [p for p, _ in self.latched] + ([top.priority] if top is not None else [])
        worst = max(prios) if prios else None
        level = level_name(worst) if worst is not None else (
            "replay" if self.replay_text else "")
        if level != self.property("alarm"):
            self.setProperty("alarm", level)
            if worst is not None:
                bg, fg, _ = LOOK[worst]
            elif level == "replay":
                bg, fg = REPLAY_LOOK
            if level:
                self.setStyleSheet(f"QLabel#alarmBanner {{ background-color: {bg}; "
                                   f"color: {fg}; font-weight: bold; }}")
            else:
                self.setStyleSheet("")
            self.style().unpolish(self)
            self.style().polish(self)

    def level(self) -> str:
        return self.property("alarm") or ""
