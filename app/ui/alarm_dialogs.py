"""Small dialogs of the alarm panel: shelve (duration and reason), out of
service (reason), and the alarm settings (limits, priorities, deadband, delays)
with validation by the same code that checks the TOML file."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFileDialog,
    QFormLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QPushButton,
    QSpinBox,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.alarms import (
    Alarm,
    AlarmConfig,
    Priority,
    dump_alarm_config,
    parse_alarm_config,
)

__all__ = ["AlarmSettingsDialog", "OutOfServiceDialog", "ShelveDialog"]

SHELVE_PRESETS_MIN = (15, 30, 60, 120, 240, 480)


class ShelveDialog(QDialog):
    """Shelve one alarm: how long (minutes) and why (required)."""

    def __init__(self, alarm: Alarm, max_s: float, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Shelve alarm")
        self.minutes = QSpinBox(self)
        self.minutes.setRange(1, max(1, int(max_s // 60)))
        self.minutes.setValue(min(60, self.minutes.maximum()))
        self.minutes.setSuffix(" min")
        self.presets = QComboBox(self)
        self.presets.addItem("preset…", None)
        for m in SHELVE_PRESETS_MIN:
            if m * 60 <= max_s:
                self.presets.addItem(f"{m} min" if m < 60 else f"{m // 60} h", m)
        self.presets.activated.connect(
            lambda i: self.presets.itemData(i) and self.minutes.setValue(self.presets.itemData(i)))
        self.reason = QLineEdit(self)
        self.reason.setPlaceholderText("why (required), e.g. sensor under maintenance")
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.reason.textChanged.connect(self._check)
        form = QFormLayout(self)
        form.addRow(QLabel(f"<b>{alarm.text}</b>", self))
        form.addRow("Shelve for", self.minutes)
        form.addRow("", self.presets)
        form.addRow("Reason", self.reason)
        form.addRow(self.buttons)
        self._check()

    def _check(self) -> None:
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(
            bool(self.reason.text().strip()))

    def duration_s(self) -> float:
        return self.minutes.value() * 60.0

    def reason_text(self) -> str:
        return self.reason.text().strip()


class OutOfServiceDialog(QDialog):
    """Take an alarm out of service for maintenance: the reason is required."""

    def __init__(self, alarm: Alarm, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Alarm out of service")
        self.reason = QLineEdit(self)
        self.reason.setPlaceholderText("why (required), e.g. gas sensor replaced, work order 4711")
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.reason.textChanged.connect(lambda t: self.buttons.button(
            QDialogButtonBox.StandardButton.Ok).setEnabled(bool(t.strip())))
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(False)
        form = QFormLayout(self)
        form.addRow(QLabel(f"<b>{alarm.text}</b><br>It will not be shown until put back "
                           f"in service.", self))
        form.addRow("Reason", self.reason)
        form.addRow(self.buttons)

    def reason_text(self) -> str:
        return self.reason.text().strip()


COLUMNS = ("Channel", "Label", "Unit", "Low", "High", "Deadband", "Priority",
           "On delay s", "Off delay s")
_KEYS = ("label", "unit", "low", "high", "deadband", "priority", "on_delay_s", "off_delay_s")


class AlarmSettingsDialog(QDialog):
    """Limits, priorities, deadband and delays of every limit rule, and the
    flood threshold. The values are checked as a TOML file would be; OK stays
    disabled while anything is wrong, and the problems are listed by key."""

    def __init__(self, config: AlarmConfig, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Alarm settings")
        self.base = config
        self.result_config: AlarmConfig | None = None
        self.table = QTableWidget(len(config.limits), len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setSectionResizeMode(
            QHeaderView.ResizeMode.ResizeToContents)
        for r, rule in enumerate(config.limits):
            item = QTableWidgetItem(rule.channel)
            item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsEditable)
            self.table.setItem(r, 0, item)
            for c, key in enumerate(_KEYS, start=1):
                v = getattr(rule, key)
                if key == "priority":
                    box = QComboBox(self.table)
                    box.addItems([p.name for p in sorted(Priority, reverse=True)])
                    box.setCurrentText(v.name)
                    box.currentTextChanged.connect(self.validate)
                    self.table.setCellWidget(r, c, box)
                    continue
                text = "" if v is None else (f"{v:g}" if isinstance(v, float) else str(v))
                self.table.setItem(r, c, QTableWidgetItem(text))
        self.flood = QSpinBox(self)
        self.flood.setRange(1, 1000)
        self.flood.setValue(config.flood_per_minute)
        self.flood.setSuffix(" alarms per window")
        self.problems = QLabel("", self)
        self.problems.setWordWrap(True)
        self.problems.setObjectName("settingsProblems")
        self.save_button = QPushButton("Save as TOML…", self)
        self.save_button.clicked.connect(self._save_dialog)
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.addButton(self.save_button, QDialogButtonBox.ButtonRole.ActionRole)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay = QVBoxLayout(self)
        lay.addWidget(QLabel("Limit alarms (empty Low/High: no such limit)", self))
        lay.addWidget(self.table, 1)
        form = QFormLayout()
        form.addRow("Flood guard above", self.flood)
        lay.addLayout(form)
        lay.addWidget(self.problems)
        lay.addWidget(self.buttons)
        self.table.itemChanged.connect(self.validate)
        self.flood.valueChanged.connect(self.validate)
        self.resize(900, 360)
        self.validate()

    # ------------------------------------------------------------ editing
    def set_cell(self, channel: str, column: str, text: str) -> None:
        """Type ``text`` into the cell of ``channel`` / ``column`` (used by tests too)."""
        r = self._row(channel)
        c = COLUMNS.index(column)
        w = self.table.cellWidget(r, c)
        if isinstance(w, QComboBox):
            w.setCurrentText(text)
        else:
            self.table.item(r, c).setText(text)

    def _row(self, channel: str) -> int:
        for r in range(self.table.rowCount()):
            if self.table.item(r, 0).text() == channel:
                return r
        raise KeyError(channel)

    def _tables(self) -> tuple[dict, list[str]]:
        """The table as TOML-shaped data, and the cells that are not numbers."""
        limits: dict[str, dict] = {}
        problems: list[str] = []
        for r in range(self.table.rowCount()):
            ch = self.table.item(r, 0).text()
            t: dict = {}
            for c, key in enumerate(_KEYS, start=1):
                w = self.table.cellWidget(r, c)
                text = w.currentText() if isinstance(w, QComboBox) else self.table.item(r, c).text()
                text = text.strip()
                if key in ("label", "unit", "priority"):
                    t[key] = text
                    continue
                if not text:
                    if key in ("low", "high"):
                        continue
                    text = "0"
                try:
                    v = float(text)
                    if not math.isfinite(v):
                        raise ValueError
                except ValueError:
                    problems.append(f"settings: [limit.{ch}] {key}: expected a number, "
                                    f"got {text!r}")
                    continue
                t[key] = v
            limits[ch] = t
        return limits, problems

    def validate(self, *_args) -> list[str]:
        limits, problems = self._tables()
        raw = dict(getattr(self.base, "_raw", {}))
        raw["limit"] = limits
        raw["flood"] = {**raw.get("flood", {}), "max_per_minute": self.flood.value()}
        cfg, more = parse_alarm_config(raw, "settings")
        problems += [p for p in more if p not in problems]
        # a limit left out by the parser (bad row) must not silently fall back
        self.result_config = None if problems else cfg
        self.problems.setText("\n".join(problems) if problems else "")
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(not problems)
        self.save_button.setEnabled(not problems)
        return problems

    def config(self) -> AlarmConfig | None:
        """The edited configuration, or None while something is invalid."""
        return self.result_config

    def save(self, path: str | Path) -> None:
        cfg = self.config()
        if cfg is None:
            raise ValueError("the settings are not valid")
        text = dump_alarm_config(cfg)
        tomllib.loads(text)  # what is written reads back
        Path(path).write_text(text, encoding="utf-8")

    def _save_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save alarm rules", "alarms.toml",
                                              "TOML (*.toml)")
        if path:
            try:
                self.save(path)
            except (OSError, ValueError) as e:
                self.problems.setText(f"could not save {path}: {e}")
