"""Control panel: teleoperation buttons and keys, speed, emergency stop, the
robot's mode and battery.

The panel only emits intents (``drive_requested``, ``stop_requested``,
``estop_requested``, ``reset_estop_requested``); the main window hands them to
the link. Driving is press-and-hold: while a direction button or key is held the
panel asks for motion, and when the last one is released it asks for a stop.
The link renews a non-zero drive command by itself, so an intent is emitted only
when what is held (or the speed) changes.

Keys (anywhere in the window): arrows or W/A/S/D drive, Space stops,
Esc or F1 is the EMERGENCY STOP, Ctrl+Shift+R resets it, +/- change the speed.
Key auto-repeat is ignored: only the first press and the real release count.
Losing the window's focus releases every held key (and so stops).

View only: while another desk holds the robot's control lease the drive pad
and speed are disabled, a line says who has control, and "Request control"
emits ``control_requested``. Stop and the EMERGENCY STOP always work.

No link (``set_link_up(False)``, from the window's link state): nothing here
could reach the robot, so the drive pad, speed, Stop, the e-stop reset and
"Request control" are disabled, drive keys do nothing, and a line says "no
link". A drive held when the link drops is released (a stop is asked for, so
nothing renews it once the link is back). The EMERGENCY STOP stays pressable:
it is tried whatever the link's state and says whether it arrived.

Under the e-stop button a line says what became of the last e-stop (sent and
acknowledged, or NOT DELIVERED; ``set_estop_status``). In a replay
(``set_replay``) there is nothing to control: the e-stop, the reset, the drive
pad and the speed are hidden, the keys do nothing, and a line says so.
"""

from __future__ import annotations

import math

from PySide6.QtCore import QEvent, QObject, Qt, Signal
from PySide6.QtGui import QKeyEvent
from PySide6.QtWidgets import (
    QAbstractSpinBox,
    QApplication,
    QComboBox,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPlainTextEdit,
    QPushButton,
    QSlider,
    QTextEdit,
    QVBoxLayout,
    QWidget,
)

from app.ui import theme
from app.widgets import StatusLamp, ValueTile, set_stale

DIRECTIONS = ("forward", "back", "left", "right")

DRIVE_KEYS: dict[int, str] = {
    Qt.Key.Key_Up: "forward", Qt.Key.Key_W: "forward",
    Qt.Key.Key_Down: "back", Qt.Key.Key_S: "back",
    Qt.Key.Key_Left: "left", Qt.Key.Key_A: "left",
    Qt.Key.Key_Right: "right", Qt.Key.Key_D: "right",
}
STOP_KEYS = (Qt.Key.Key_Space,)
ESTOP_KEYS = (Qt.Key.Key_Escape, Qt.Key.Key_F1)
FASTER_KEYS = (Qt.Key.Key_Plus, Qt.Key.Key_Equal)
SLOWER_KEYS = (Qt.Key.Key_Minus, Qt.Key.Key_Underscore)

SPEED_MIN_MPS = 0.1
SPEED_MAX_MPS = 1.0
SPEED_STEP_MPS = 0.05
TURN_PER_SPEED = 2.0  # rad/s of turn per m/s of the speed setting
TURN_MAX_RPS = 1.5


def drive_from_held(held: set[str], speed_mps: float) -> tuple[float, float]:
    """(linear_mps, angular_rps) for the held directions; opposite ones cancel.
    Left turns counter-clockwise (positive angular rate)."""
    lin = speed_mps * (("forward" in held) - ("back" in held))
    turn = min(TURN_PER_SPEED * speed_mps, TURN_MAX_RPS)
    ang = turn * (("left" in held) - ("right" in held))
    return float(lin), float(ang)


def _takes_text(w: QObject) -> bool:
    """A widget the operator types into: its letters, digits and signs are text."""
    if isinstance(w, (QLineEdit, QAbstractSpinBox, QTextEdit, QPlainTextEdit)):
        return not getattr(w, "isReadOnly", lambda: False)()
    return isinstance(w, QComboBox) and w.isEditable()


# the events the key filter looks at; a set built once: the filter sees every event
# the application delivers, and spelling the enum members out in it for each one cost
# more than the rest of the filter
_KEY_EVENTS = frozenset({QEvent.Type.KeyPress, QEvent.Type.KeyRelease,
                         QEvent.Type.ShortcutOverride, QEvent.Type.WindowDeactivate})


class _KeyFilter(QObject):
    """Application-wide key filter that only acts on keys meant for one window."""

    def __init__(self, panel: ControlPanel) -> None:
        super().__init__(panel)
        self.panel = panel

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt name)
        t = event.type()
        if t not in _KEY_EVENTS:
            return False
        try:
            window = self.panel.window()
        except RuntimeError:  # the panel is being destroyed
            return False
        if not isinstance(obj, QWidget) or obj.window() is not window:
            return False
        if t == QEvent.Type.WindowDeactivate:
            if obj is window:
                self.panel.release_all_keys()
            return False
        return self.panel.handle_key(event, t, typing=_takes_text(obj))


class ControlPanel(QWidget):
    drive_requested = Signal(float, float)  # linear_mps, angular_rps
    stop_requested = Signal()
    estop_requested = Signal()
    reset_estop_requested = Signal()
    speed_changed = Signal(float)  # m/s
    control_requested = Signal()  # ask the robot for the control lease

    def __init__(self, parent: QWidget | None = None, *, speed_mps: float = 0.3) -> None:
        super().__init__(parent)
        self._held_buttons: set[str] = set()
        self._held_keys: set[str] = set()
        self._last_cmd: tuple[float, float] = (0.0, 0.0)

        # ---- e-stop: big, always first
        self.estop_button = QPushButton(self.tr("EMERGENCY STOP  (Esc / F1)"), self)
        self.estop_button.setObjectName("estopButton")
        self.estop_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.estop_button.setToolTip(self.tr("Stops the robot at once. Keys: Esc or F1"))
        self.estop_button.pressed.connect(self.request_estop)
        self.reset_button = QPushButton(self.tr("Reset e-stop  (Ctrl+Shift+R)"), self)
        self.reset_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.reset_button.clicked.connect(self.reset_estop_requested)
        self.estop_status = QLabel("", self)
        self.estop_status.setObjectName("estopStatus")
        self.estop_status.setWordWrap(True)
        self.estop_status.setVisible(False)
        self.replay = False
        self.replay_label = QLabel(self.tr("REPLAY — view only: no drive, no e-stop, no commands "
                                   "(nothing here reaches a robot)"), self)
        self.replay_label.setObjectName("replayLabel")
        self.replay_label.setWordWrap(True)
        self.replay_label.setVisible(False)
        self.link_up = True  # a panel on its own; the window says when there is no link
        self.no_link_label = QLabel(self.tr("NO LINK — drive and commands are off until the robot "
                                    "answers again; the e-stop is still tried and says "
                                    "whether it arrived"), self)
        self.no_link_label.setObjectName("noLinkLabel")
        self.no_link_label.setWordWrap(True)
        self.no_link_label.setVisible(False)

        # ---- drive pad
        self._buttons: dict[str, QPushButton] = {}
        pad = QGridLayout()
        labels = {"forward": self.tr("▲ Forward"), "back": self.tr("▼ Back"),
                  "left": self.tr("◀ Left"), "right": self.tr("Right ▶")}
        where = {"forward": (0, 1), "left": (1, 0), "right": (1, 2), "back": (2, 1)}
        for d in DIRECTIONS:
            b = QPushButton(labels[d], self)
            b.setFocusPolicy(Qt.FocusPolicy.NoFocus)
            b.setAutoRepeat(False)
            b.pressed.connect(lambda d=d: self._button_pressed(d))
            b.released.connect(lambda d=d: self._button_released(d))
            self._buttons[d] = b
            pad.addWidget(b, *where[d])
        self.stop_button = QPushButton(self.tr("■ Stop"), self)
        self.stop_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.stop_button.setToolTip(self.tr("Stop driving (Space)"))
        self.stop_button.clicked.connect(self.request_stop)
        pad.addWidget(self.stop_button, 1, 1)

        # ---- speed
        self.speed_slider = QSlider(Qt.Orientation.Horizontal, self)
        self.speed_slider.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.speed_slider.setRange(round(SPEED_MIN_MPS / SPEED_STEP_MPS),
                                   round(SPEED_MAX_MPS / SPEED_STEP_MPS))
        self.speed_slider.setValue(round(speed_mps / SPEED_STEP_MPS))
        self.speed_slider.setToolTip(self.tr("Drive speed (+ / - keys)"))
        self.speed_label = QLabel(self)
        self.speed_slider.valueChanged.connect(self._on_speed)
        speed_row = QHBoxLayout()
        speed_row.addWidget(QLabel(self.tr("Speed"), self))
        speed_row.addWidget(self.speed_slider, 1)
        speed_row.addWidget(self.speed_label)
        self._on_speed(self.speed_slider.value())

        # ---- robot state
        self.mode_lamp = StatusLamp(self.tr("mode —"), self)
        self.battery_tile = ValueTile(self.tr("Battery"), "V", self, fmt="{:.2f}")
        self.battery_pct = QLabel(self.tr("— %"), self)
        state_row = QHBoxLayout()
        state_row.addWidget(self.mode_lamp, 1)
        state_row.addWidget(self.battery_tile)
        state_row.addWidget(self.battery_pct)

        # ---- control lease
        self.view_only = False
        self._lease_saved: str | None = None  # the robot's last word while the link is down
        self.lease_label = QLabel("", self)
        self.lease_label.setWordWrap(True)
        self.lease_label.setObjectName("leaseLabel")
        self.request_button = QPushButton(self.tr("Request control"), self)
        self.request_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.request_button.setToolTip(self.tr("Ask the desk that has control to hand it over"))
        self.request_button.clicked.connect(self.control_requested)
        self.request_button.setVisible(False)

        drive_box = QGroupBox(self.tr("Drive (arrows / WASD, Space stops)"), self)
        self.drive_box = drive_box
        dl = QVBoxLayout(drive_box)
        dl.addLayout(pad)
        dl.addLayout(speed_row)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(self.replay_label)
        lay.addWidget(self.no_link_label)
        lay.addWidget(self.estop_button)
        lay.addWidget(self.estop_status)
        lay.addWidget(self.reset_button)
        lay.addWidget(self.lease_label)
        lay.addWidget(self.request_button)
        lay.addWidget(drive_box)
        lay.addLayout(state_row)
        lay.addStretch(1)

        self._key_filter = _KeyFilter(self)
        app = QApplication.instance()
        if app is not None:
            app.installEventFilter(self._key_filter)

    # --------------------------------------------------------------- queries
    def button(self, name: str) -> QPushButton:
        """The button called ``name``: forward, back, left, right, stop, estop, reset_estop."""
        extra = {"stop": self.stop_button, "estop": self.estop_button,
                 "reset_estop": self.reset_button}
        return extra[name] if name in extra else self._buttons[name]

    def held(self) -> set[str]:
        return self._held_buttons | self._held_keys

    def speed_mps(self) -> float:
        return self.speed_slider.value() * SPEED_STEP_MPS

    def set_view_only(self, on: bool, text: str = "") -> None:
        """Another desk has control (``on``): disable driving, say who has it."""
        if on and self.held():
            self.request_stop()
        self.view_only = bool(on)
        self._enable_controls()
        self.request_button.setVisible(bool(on))
        if self._lease_saved is not None:  # news from the robot: the link is back
            self._lease_saved = None
            set_stale(self.lease_label, False)
        self.lease_label.setText(text)

    def lease_text(self) -> str:
        return self.lease_label.text()

    def set_link_up(self, up: bool) -> None:
        """The link is up (``up``) or there is none: without one every control that
        would send something is disabled and a line says "no link"; the e-stop stays."""
        up = bool(up)
        if not up and self.held():
            self.request_stop()  # nothing may renew this drive when the link returns
        self.link_up = up
        self._enable_controls()
        self.no_link_label.setVisible(not up and not self.replay)

    def controls_enabled(self) -> dict[str, bool]:
        """Which controls take input now (name -> enabled)."""
        out = {d: b.isEnabled() for d, b in self._buttons.items()}
        out.update(stop=self.stop_button.isEnabled(), speed=self.speed_slider.isEnabled(),
                   estop=self.estop_button.isEnabled(), reset_estop=self.reset_button.isEnabled(),
                   request_control=self.request_button.isEnabled())
        return out

    def _enable_controls(self) -> None:
        live = self.link_up and not self.replay
        drive = live and not self.view_only
        for b in self._buttons.values():
            b.setEnabled(drive)
        self.speed_slider.setEnabled(drive)
        for b in (self.stop_button, self.reset_button, self.request_button):
            b.setEnabled(live)

    def set_replay(self, on: bool) -> None:
        """A replay: hide every control (nothing would reach a robot) and say so."""
        self.replay = bool(on)
        self._held_buttons.clear()
        self._held_keys.clear()
        self._last_cmd = (0.0, 0.0)
        for w in (self.estop_button, self.reset_button, self.drive_box, self.request_button,
                  self.lease_label):
            w.setVisible(not on)
            w.setEnabled(not on)
        self.estop_status.setVisible(False)
        self.replay_label.setVisible(bool(on))
        self.no_link_label.setVisible(not on and not self.link_up)
        self._enable_controls()

    def set_estop_status(self, text: str, failed: bool) -> None:
        """What became of the last e-stop; ``failed``: it did not reach the robot."""
        self.estop_status.setText(text)
        self.estop_status.setVisible(bool(text) and not self.replay)
        self.estop_status.setStyleSheet(
            f"QLabel#estopStatus {{ color: #ffffff; background-color: {theme.ALARM_HIGH}; "
            "font-weight: bold; padding: 2px; }" if failed else "")

    def estop_status_text(self) -> str:
        return self.estop_status.text()

    # --------------------------------------------------------------- intents
    def set_speed_mps(self, speed: float) -> None:
        self.speed_slider.setValue(round(speed / SPEED_STEP_MPS))

    def request_stop(self) -> None:
        if self.replay:
            return
        self._held_buttons.clear()
        self._held_keys.clear()
        self._last_cmd = (0.0, 0.0)
        self.stop_requested.emit()

    def request_estop(self) -> None:
        if self.replay:
            return
        self._held_buttons.clear()
        self._held_keys.clear()
        self._last_cmd = (0.0, 0.0)
        self.estop_requested.emit()

    def release_all_keys(self) -> None:
        if self._held_keys:
            self._held_keys.clear()
            self._update_drive()

    def _button_pressed(self, d: str) -> None:
        self._held_buttons.add(d)
        self._update_drive()

    def _button_released(self, d: str) -> None:
        self._held_buttons.discard(d)
        self._update_drive()

    def _on_speed(self, value: int) -> None:
        speed = value * SPEED_STEP_MPS
        self.speed_label.setText(f"{speed:.2f} m/s")
        self.speed_changed.emit(speed)
        if self.held():
            self._update_drive()

    def _update_drive(self) -> None:
        if self.view_only or self.replay or not self.link_up:
            self._held_buttons.clear()
            self._held_keys.clear()
            return
        cmd = drive_from_held(self.held(), self.speed_mps())
        if cmd == self._last_cmd:
            return
        self._last_cmd = cmd
        if cmd == (0.0, 0.0):
            self.stop_requested.emit()
        else:
            self.drive_requested.emit(*cmd)

    def handle_key(self, event: QKeyEvent, etype: QEvent.Type, *, typing: bool = False) -> bool:
        """Act on a desk key; True when the key was ours (and is consumed).
        ``typing``: the focus is in a text field, which keeps its keys — except the
        e-stop keys, and the release of a drive key held before (so it still stops)."""
        if self.replay:
            return False  # a replay has nothing to drive or stop
        key = event.key()
        mods = event.modifiers() & ~Qt.KeyboardModifier.KeypadModifier
        plain = mods in (Qt.KeyboardModifier.NoModifier, Qt.KeyboardModifier.ShiftModifier)
        reset = (key == Qt.Key.Key_R and mods == (Qt.KeyboardModifier.ControlModifier
                                                  | Qt.KeyboardModifier.ShiftModifier))
        # a drive key's release counts whatever the modifiers are by then
        release_drive = etype == QEvent.Type.KeyRelease and key in DRIVE_KEYS
        desk_key = (key in DRIVE_KEYS or key in STOP_KEYS or key in ESTOP_KEYS
                    or key in FASTER_KEYS or key in SLOWER_KEYS)
        ours = reset or release_drive or (plain and desk_key)
        held_before = release_drive and DRIVE_KEYS[key] in self._held_keys
        if typing and not (key in ESTOP_KEYS or held_before):
            ours = False
        if not ours:
            return False
        if etype == QEvent.Type.ShortcutOverride:
            event.accept()  # we want the key press itself, not a shortcut
            return True
        if event.isAutoRepeat():
            return True  # holding a key: the first press already counts
        press = etype == QEvent.Type.KeyPress
        if key in DRIVE_KEYS:
            d = DRIVE_KEYS[key]
            if press:
                self._held_keys.add(d)
            else:
                self._held_keys.discard(d)
            self._update_drive()
        elif not press:
            return True
        elif key in ESTOP_KEYS:
            self.request_estop()
        elif key in STOP_KEYS:
            self.request_stop()
        elif reset:
            self.reset_estop_requested.emit()
        elif key in FASTER_KEYS:
            self.speed_slider.setValue(self.speed_slider.value() + 1)
        elif key in SLOWER_KEYS:
            self.speed_slider.setValue(self.speed_slider.value() - 1)
        return True

    # --------------------------------------------------------------- robot state
    def show_freshness(self, telemetry, control, link_up: bool) -> None:
        """Mode and battery (from telemetry) and the control line, each with its
        age when no longer current; with the link down control is "no link"."""
        text = telemetry.text() or None
        self.mode_lamp.set_stale(text)
        self.battery_tile.set_stale(text)
        set_stale(self.battery_pct, bool(text))
        if link_up:
            if self._lease_saved is not None:
                self.lease_label.setText(self._lease_saved)
                self._lease_saved = None
                set_stale(self.lease_label, False)
            return
        if self._lease_saved is None:
            self._lease_saved = self.lease_label.text()
        when = control.text()
        self.lease_label.setText(self.tr("no link — control unknown")
                                  + (f" ({when})" if when else ""))
        set_stale(self.lease_label, True)

    def set_mode(self, name: str, abnormal: bool = False) -> None:
        self.mode_lamp.set_status(self.tr("mode {name}").format(name=name),
                                  theme.ALARM_HIGH if abnormal else None)

    def mode_text(self) -> str:
        return self.mode_lamp.text()

    def set_battery(self, volts: float, percent: float, level: str | None = None) -> None:
        self.battery_tile.set_value(volts)
        self.battery_tile.set_alarm(level)
        self.battery_pct.setText("— %" if not math.isfinite(percent) else f"≈{percent:.0f} %")
