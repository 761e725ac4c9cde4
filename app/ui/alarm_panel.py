"""Alarm panel: a thin view of the alarm manager (app.core.alarms.AlarmMonitor)
and the event log.

The list shows every alarm that is not normal (ISA-18.2: unacknowledged,
acknowledged, returned to normal unacknowledged, shelved, out of service),
filtered by state, priority and source. The operator acknowledges the selected
alarm (Ctrl+K) or every visible one (Ctrl+Shift+K), shelves one for a time with
a reason, or takes one out of service; each of these is a call on the monitor,
whose transitions reach every listener (and so the archive). During an alarm
flood the list groups by source (one row per source) and says so. A comment on an
alarm (a control room's OPC UA AddComment) shows in its row, with who made it, and in
the event log.

Selecting an alarm emits ``alarm_selected`` so the window can show its trend.

The table's model is :mod:`app.ui.alarm_table`, the event log :mod:`app.ui.event_log`,
the shelve and out-of-service dialogs :mod:`app.ui.alarm_dialogs`; their public
names are re-exported here.
"""

from __future__ import annotations

import getpass
import time
from collections.abc import Callable

from PySide6.QtCore import QItemSelectionModel, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
    QComboBox,
    QHBoxLayout,
    QLabel,
    QMessageBox,
    QPushButton,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from app.core.alarms import (
    FLOOD_ID,
    Alarm,
    AlarmMonitor,
    AlarmState,
    Priority,
    Transition,
    select_alarms,
)
from app.core.i18n import translate
from app.ui.alarm_banner import priority_mark
from app.ui.alarm_dialogs import OutOfServiceDialog, ShelveDialog
from app.ui.alarm_sound import AlarmSound
from app.ui.alarm_table import COLUMNS, STATE_FILTERS, STATE_TEXT, AlarmTableModel
from app.ui.event_log import EVENT_LOG_LINES, EventLog, clock_text, source_text
from app.ui.fitted_table import FittedTableView
from app.widgets.timer_phase import start_at_phase

__all__ = ["AlarmPanel", "AlarmTableModel", "COLUMNS", "EVENT_LOG_LINES", "STATE_TEXT",
           "clock_text", "source_text"]

class AlarmPanel(QWidget):
    """The alarm list with its filters and actions, and the event log."""

    alarm_selected = Signal(object)  # Alarm
    acknowledged = Signal(list)  # the transitions an acknowledge made
    comment_noted = Signal(object)  # Alarm: a comment on it came (from any thread)

    def __init__(self, monitor: AlarmMonitor | None = None, parent: QWidget | None = None, *,
                 max_log_lines: int = EVENT_LOG_LINES, user: str | None = None,
                 clock: Callable[[], float] = time.time,
                 sound: AlarmSound | None = None) -> None:
        super().__init__(parent)
        self.monitor = monitor if monitor is not None else AlarmMonitor(())
        self._clock = clock
        if user is None:
            try:
                user = getpass.getuser()
            except Exception:  # no login name (some containers)
                user = None
        self.user = user
        self.read_only = False  # a replay: the list is shown, not handled
        self.sound = sound if sound is not None else AlarmSound(self)
        self.errors: list[str] = []  # what the last operator actions refused, for the operator

        self.state_box = QComboBox(self)
        for name, _ in STATE_FILTERS:
            self.state_box.addItem(translate("AlarmPanel", name))
        self.priority_box = QComboBox(self)
        self.priority_box.addItem(self.tr("All priorities"), None)
        for p in sorted(Priority, reverse=True):
            self.priority_box.addItem(priority_mark(p), p)
        self.source_box = QComboBox(self)
        self.source_box.addItem(self.tr("All sources"), None)
        for box in (self.state_box, self.priority_box, self.source_box):
            box.currentIndexChanged.connect(self.refresh)
            box.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.count_label = QLabel(self.tr("no active alarms"), self)
        self.mute_box = QCheckBox(self.tr("Mute"), self)
        self.mute_box.setToolTip(self.tr("Silence the alarm sounds (Ctrl+M)"))
        self.mute_box.toggled.connect(self.sound.set_muted)
        self.group_box = QCheckBox(self.tr("Group by source"), self)
        self.group_box.toggled.connect(self.refresh)
        self.flood_label = QLabel("", self)
        self.flood_label.setObjectName("floodNotice")
        self.flood_label.setWordWrap(True)
        self.flood_label.setVisible(False)

        self.model = AlarmTableModel(self)
        self.table = FittedTableView(self)  # columns fit their text, measured by row
        self.table.setModel(self.model)
        self.table.verticalHeader().setVisible(False)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.ExtendedSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.selectionModel().selectionChanged.connect(self._on_selection)

        self.ack_button = QPushButton(self.tr("Acknowledge (Ctrl+K)"), self)
        self.ack_all_button = QPushButton(self.tr("Acknowledge visible (Ctrl+Shift+K)"), self)
        self.shelve_button = QPushButton(self.tr("Shelve…"), self)
        self.unshelve_button = QPushButton(self.tr("Unshelve"), self)
        self.oos_button = QPushButton(self.tr("Out of service…"), self)
        self.in_service_button = QPushButton(self.tr("Back in service"), self)
        self.reset_button = QPushButton(self.tr("Reset latch"), self)
        self.reset_button.setToolTip(self.tr(
            "Release a latched alarm (gas A2, over-range) once the value is back below its "
            "set-point less its deadband; a reset is not an acknowledgement"))
        for b, slot in ((self.ack_button, self.acknowledge_selected),
                        (self.ack_all_button, self.acknowledge_visible),
                        (self.shelve_button, self.shelve_selected),
                        (self.unshelve_button, self.unshelve_selected),
                        (self.oos_button, self.out_of_service_selected),
                        (self.in_service_button, self.in_service_selected),
                        (self.reset_button, self.reset_selected)):
            b.setFocusPolicy(Qt.FocusPolicy.NoFocus)
            b.clicked.connect(lambda _=False, s=slot: s())

        self.ack_action = QAction(self.tr("Acknowledge selected alarm"), self)
        self.ack_action.setShortcut(QKeySequence("Ctrl+K"))
        self.ack_action.triggered.connect(self.acknowledge_selected)
        self.ack_all_action = QAction(self.tr("Acknowledge all visible alarms"), self)
        self.ack_all_action.setShortcut(QKeySequence("Ctrl+Shift+K"))
        self.ack_all_action.triggered.connect(self.acknowledge_visible)
        self.mute_action = QAction(self.tr("Mute alarm sounds"), self)
        self.mute_action.setShortcut(QKeySequence("Ctrl+M"))
        self.mute_action.setCheckable(True)
        self.mute_action.toggled.connect(self.mute_box.setChecked)
        self.mute_box.toggled.connect(self.mute_action.setChecked)
        for a in (self.ack_action, self.ack_all_action, self.mute_action):
            a.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
            self.addAction(a)

        self.log = EventLog(self, max_lines=max_log_lines)
        self.log.setPlaceholderText(self.tr("event log"))

        left = QWidget(self)
        ll = QVBoxLayout(left)
        ll.setContentsMargins(0, 0, 0, 0)
        filters = QHBoxLayout()
        for w in (self.state_box, self.priority_box, self.source_box):
            filters.addWidget(w)
        filters.addWidget(self.count_label, 1)
        filters.addWidget(self.group_box)
        filters.addWidget(self.mute_box)
        ll.addLayout(filters)
        ll.addWidget(self.flood_label)
        ll.addWidget(self.table, 1)
        actions = QHBoxLayout()
        for b in (self.ack_button, self.ack_all_button, self.shelve_button,
                  self.unshelve_button, self.oos_button, self.in_service_button,
                  self.reset_button):
            actions.addWidget(b)
        actions.addStretch(1)
        ll.addLayout(actions)
        right = QWidget(self)
        rl = QVBoxLayout(right)
        rl.setContentsMargins(0, 0, 0, 0)
        rl.addWidget(QLabel(self.tr("Event log"), self))
        rl.addWidget(self.log, 1)
        split = QSplitter(Qt.Orientation.Horizontal, self)
        split.addWidget(left)
        split.addWidget(right)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(split)

        # comments come from the monitor's thread (an OPC UA client's, run by the desk's
        # timer): a queued signal brings them to this one
        self.comment_noted.connect(self.on_comment)
        note = self.comment_noted.emit
        self.monitor.add_comment_listener(note)
        self.destroyed.connect(lambda *_a, m=self.monitor: m.remove_comment_listener(note))

        self._was_flood = False
        self._values = QTimer(self)  # values move without transitions: refresh them
        self._values.setInterval(1000)
        self._values.timeout.connect(self.refresh)
        # a quarter second past the plots' once-a-second refresh: not in its slice
        start_at_phase(self._values, 0.25)
        self.refresh()

    # ------------------------------------------------------------- inputs
    def on_transition(self, tr: Transition) -> None:
        """Slot for the telemetry model's ``alarm_changed``: log, sound, refresh."""
        a = tr.alarm
        if tr.raised:
            self.add_log("alarm", "alarm", f"{priority_mark(a.priority)} {a.text}", tr.t)
            # during a flood only the notice and emergencies sound
            if not self.monitor.flood_active or a.key == FLOOD_ID \
                    or a.priority is Priority.EMERGENCY:
                self.sound.play(a.priority)
        elif tr.cleared:
            text = a.cleared_text
            if tr.reason == "reset":  # a latch released: who and when, as archived
                text += self.tr(" (latch reset by {0})").format(tr.user or "?")
            self.add_log("info", "alarm", text, tr.t)
        else:
            who = self.tr(" by {user}").format(user=tr.user) if tr.user else ""
            why = f": {tr.reason}" if tr.reason else ""
            state = translate("AlarmPanel", STATE_TEXT[tr.to_state])
            label = translate("AlarmText", a.label) if a.label else a.key
            self.add_log("info", "alarm", f"{label} {state}"
                         f"{who}{why}", tr.t)
        self.refresh()

    def on_comment(self, a: Alarm) -> None:
        """A comment on an alarm: a line in the event log (who and what); its row
        shows it."""
        label = translate("AlarmText", a.label) if a.label else a.key
        self.add_log("info", "alarm", self.tr("{label}: comment by {user}: {text}").format(
            label=label, user=a.comment_by or "?", text=a.comment or ""), a.comment_t)
        self.refresh()

    # ------------------------------------------------------------ filters
    def _filters(self) -> tuple:
        states = STATE_FILTERS[max(0, self.state_box.currentIndex())][1]
        pri = self.priority_box.currentData()
        src = self.source_box.currentData()
        return (states, None if pri is None else {Priority(pri)},
                None if src is None else {src})

    def set_filters(self, *, state: str | None = None, priority: Priority | None = None,
                    source: str | None = None) -> None:
        """Choose filters by name (None: all)."""
        names = [n for n, _ in STATE_FILTERS]
        self.state_box.setCurrentIndex(names.index(state) if state else 0)
        i = self.priority_box.findData(priority) if priority is not None else 0
        self.priority_box.setCurrentIndex(max(0, i))
        if source is not None and self.source_box.findData(source) < 0:
            self.source_box.addItem(source_text(source), source)
        i = self.source_box.findData(source) if source is not None else 0
        self.source_box.setCurrentIndex(max(0, i))

    def refresh(self) -> None:
        listed = self.monitor.listed()
        # keep the source filter's choices current
        sources = sorted({a.source for a in listed})
        for s in sources:
            if self.source_box.findData(s) < 0:
                self.source_box.blockSignals(True)
                self.source_box.addItem(source_text(s), s)
                self.source_box.blockSignals(False)
        states, pris, srcs = self._filters()
        visible = select_alarms(listed, states=states, priorities=pris, sources=srcs)
        flood = self.monitor.flood_active
        if flood and not self._was_flood:
            self.group_box.setChecked(True)  # grouping starts with the flood
        self._was_flood = flood
        if flood:
            n = self.monitor.flood.count(self._clock())
            self.flood_label.setText(
                self.tr("ALARM FLOOD: {n} alarms in the last {window} s (more than {max}). "
                        "The list is grouped by source; every alarm is still recorded.").format(
                    n=n, window=f"{self.monitor.flood.window_s:g}",
                    max=self.monitor.flood.max_per_minute))
        self.flood_label.setVisible(flood)
        selected = self.selected_keys()
        groups = (self.monitor.groups(within=[a.key for a in visible])
                  if self.group_box.isChecked() else None)
        sm = self.table.selectionModel()
        sm.blockSignals(True)
        if self.model.set_rows(visible, groups):  # reset: the selection is put back
            flags = (QItemSelectionModel.SelectionFlag.Select
                     | QItemSelectionModel.SelectionFlag.Rows)
            for r in range(self.model.rowCount()):
                if set(self.model.keys_at(r)) & set(selected):
                    sm.select(self.model.index(r, 0), flags)
            self.table.viewport().update()
        sm.blockSignals(False)
        n_active = sum(1 for a in listed if a.state in (AlarmState.UNACK, AlarmState.ACKED))
        n_unack = sum(1 for a in listed if not a.acknowledged)
        self.count_label.setText(
            self.tr("no active alarms") if not listed else
            self.tr("{active} active, {unack} unacknowledged, {listed} listed").format(
                active=n_active, unack=n_unack, listed=len(listed)))
        self._enable_actions()

    # ------------------------------------------------------------ selection
    def selected_keys(self) -> list[str]:
        rows = sorted({i.row() for i in self.table.selectionModel().selectedRows()})
        keys: list[str] = []
        for r in rows:
            if r < self.model.rowCount():
                keys += self.model.keys_at(r)
        return keys

    def selected_alarm(self) -> Alarm | None:
        keys = self.selected_keys()
        return self.monitor.get(keys[0]) if len(keys) == 1 else None

    def select_alarm(self, key: str) -> bool:
        for r in range(self.model.rowCount()):
            if key in self.model.keys_at(r):
                self.select_row(r)
                return True
        return False

    def select_row(self, row: int) -> None:
        """Select exactly ``row`` (whatever keyboard modifiers are held)."""
        self.table.selectionModel().select(
            self.model.index(row, 0), QItemSelectionModel.SelectionFlag.ClearAndSelect
            | QItemSelectionModel.SelectionFlag.Rows)

    def visible_keys(self) -> list[str]:
        keys: list[str] = []
        for r in range(self.model.rowCount()):
            keys += self.model.keys_at(r)
        return keys

    def _on_selection(self, *_args) -> None:
        self._enable_actions()
        a = self.selected_alarm()
        if a is not None:
            self.alarm_selected.emit(a)

    def set_read_only(self, on: bool) -> None:
        """Show the alarms without letting them be handled (a replay window:
        its alarm list is the recording's, not the station's)."""
        self.read_only = bool(on)
        self._enable_actions()

    def _enable_actions(self) -> None:
        for w in (self.ack_action, self.ack_all_action):
            w.setEnabled(not self.read_only)
        if self.read_only:
            for b in (self.ack_button, self.ack_all_button, self.shelve_button,
                      self.unshelve_button, self.oos_button, self.in_service_button,
                      self.reset_button):
                b.setEnabled(False)
            return
        sel = [self.monitor.get(k) for k in self.selected_keys()]
        sel = [a for a in sel if a is not None]
        one = sel[0] if len(sel) == 1 else None
        self.ack_button.setEnabled(any(not a.acknowledged for a in sel))
        self.ack_all_button.setEnabled(self.model.rowCount() > 0)
        self.shelve_button.setEnabled(one is not None and one.state in (
            AlarmState.UNACK, AlarmState.ACKED, AlarmState.RTN_UNACK))
        self.unshelve_button.setEnabled(one is not None and one.state is AlarmState.SHELVED)
        self.oos_button.setEnabled(one is not None
                                   and one.state is not AlarmState.OUT_OF_SERVICE)
        self.in_service_button.setEnabled(one is not None
                                          and one.state is AlarmState.OUT_OF_SERVICE)
        self.reset_button.setEnabled(one is not None and self.monitor.latched(one.key))

    # ------------------------------------------------------------ actions
    def acknowledge_selected(self) -> list[Transition]:
        if self.read_only:
            return []
        trs = self.monitor.acknowledge_all(self.selected_keys(), self._clock(), user=self.user)
        if trs:
            self.acknowledged.emit(trs)
        self.refresh()
        return trs

    def acknowledge_visible(self) -> list[Transition]:
        if self.read_only:
            return []
        trs = self.monitor.acknowledge_all(self.visible_keys(), self._clock(), user=self.user)
        if trs:
            self.acknowledged.emit(trs)
        self.refresh()
        return trs

    def shelve(self, key: str, duration_s: float, reason: str) -> list[Transition]:
        """Shelve ``key``; a refusal (bad duration, no reason) is shown, not raised."""
        if self.read_only:
            return []
        try:
            trs = self.monitor.shelve(key, self._clock(), duration_s, reason, user=self.user)
        except ValueError as e:
            self._refused(self.tr("cannot shelve {key}: {why}").format(key=key, why=e))
            return []
        self.refresh()
        return trs

    def shelve_selected(self, dialog: ShelveDialog | None = None) -> list[Transition]:
        a = self.selected_alarm()
        if a is None:
            return []
        dlg = dialog or ShelveDialog(a, self.monitor.max_shelve_s, self)
        if dialog is None and dlg.exec() != ShelveDialog.DialogCode.Accepted:
            return []
        return self.shelve(a.key, dlg.duration_s(), dlg.reason_text())

    def unshelve_selected(self) -> list[Transition]:
        if self.read_only:
            return []
        a = self.selected_alarm()
        trs = [] if a is None else self.monitor.unshelve(a.key, self._clock(), user=self.user)
        self.refresh()
        return trs

    def set_out_of_service(self, key: str, on: bool, reason: str | None = None
                           ) -> list[Transition]:
        if self.read_only:
            return []
        try:
            trs = self.monitor.set_out_of_service(key, on, self._clock(), reason,
                                                  user=self.user)
        except ValueError as e:
            self._refused(self.tr("cannot take {key} out of service: {why}").format(key=key, why=e))
            return []
        self.refresh()
        return trs

    def out_of_service_selected(self, dialog: OutOfServiceDialog | None = None
                                ) -> list[Transition]:
        a = self.selected_alarm()
        if a is None:
            return []
        dlg = dialog or OutOfServiceDialog(a, self)
        if dialog is None and dlg.exec() != OutOfServiceDialog.DialogCode.Accepted:
            return []
        return self.set_out_of_service(a.key, True, dlg.reason_text())

    def in_service_selected(self) -> list[Transition]:
        a = self.selected_alarm()
        return [] if a is None else self.set_out_of_service(a.key, False)

    def reset_selected(self) -> list[Transition]:
        """Reset the selected latched alarm; a refusal (value still high) is shown."""
        a = self.selected_alarm()
        if self.read_only or a is None:
            return []
        trs, why = self.monitor.reset(a.key, self._clock(), user=self.user)
        if why:
            self._refused(self.tr("cannot reset {key}: {why}").format(key=a.key, why=why))
        self.refresh()  # the reset itself is logged from its transition
        return trs

    def _refused(self, text: str) -> None:
        self.errors.append(text)
        self.add_log("warning", "alarm", text)
        if self.isVisible() and not _offscreen():
            QMessageBox.warning(self, self.tr("Alarm"), text)

    # ------------------------------------------------------------ queries
    def rows(self) -> list[dict[str, str]]:
        """The visible table as text, top row first (for tests and export)."""
        return [dict(zip(COLUMNS, self.model.cells(r), strict=True))
                | {"key": ",".join(self.model.keys_at(r))}
                for r in range(self.model.rowCount())]

    def active_count(self) -> int:
        return len(self.monitor.active())

    # --------------------------------------------------------------- log
    def set_log_clock(self, clock: Callable[[], float]) -> None:
        """Where an event-log line without its own time gets its stamp (default: the
        wall clock; a replay: its position in the recording)."""
        self.log.set_clock(clock)

    def add_log(self, level: str, source: str, text: str, t: float | None = None) -> None:
        self.log.add(level, source, text, t)

    def log_lines(self) -> list[str]:
        return self.log.lines()


def _offscreen() -> bool:
    from PySide6.QtGui import QGuiApplication

    return QGuiApplication.platformName() in ("offscreen", "minimal")
