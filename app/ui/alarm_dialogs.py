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
    QTabWidget,
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
from app.core.i18n import QT_TRANSLATE_NOOP, translate

__all__ = ["AlarmSettingsDialog", "OutOfServiceDialog", "ShelveDialog"]

SHELVE_PRESETS_MIN = (15, 30, 60, 120, 240, 480)


class ShelveDialog(QDialog):
    """Shelve one alarm: how long (minutes) and why (required)."""

    def __init__(self, alarm: Alarm, max_s: float, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Shelve alarm"))
        self.minutes = QSpinBox(self)
        self.minutes.setRange(1, max(1, int(max_s // 60)))
        self.minutes.setValue(min(60, self.minutes.maximum()))
        self.minutes.setSuffix(self.tr(" min"))
        self.presets = QComboBox(self)
        self.presets.addItem(self.tr("preset…"), None)
        for m in SHELVE_PRESETS_MIN:
            if m * 60 <= max_s:
                self.presets.addItem(f"{m} min" if m < 60 else f"{m // 60} h", m)
        self.presets.activated.connect(
            lambda i: self.presets.itemData(i) and self.minutes.setValue(self.presets.itemData(i)))
        self.reason = QLineEdit(self)
        self.reason.setPlaceholderText(self.tr("why (required), e.g. sensor under maintenance"))
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.reason.textChanged.connect(self._check)
        form = QFormLayout(self)
        form.addRow(QLabel(f"<b>{alarm.text}</b>", self))
        form.addRow(self.tr("Shelve for"), self.minutes)
        form.addRow("", self.presets)
        form.addRow(self.tr("Reason"), self.reason)
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
        self.setWindowTitle(self.tr("Alarm out of service"))
        self.reason = QLineEdit(self)
        self.reason.setPlaceholderText(
            self.tr("why (required), e.g. gas sensor replaced, work order 4711"))
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.reason.textChanged.connect(lambda t: self.buttons.button(
            QDialogButtonBox.StandardButton.Ok).setEnabled(bool(t.strip())))
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(False)
        form = QFormLayout(self)
        form.addRow(QLabel(f"<b>{alarm.text}</b><br>"
                           + self.tr("It will not be shown until put back in service."), self))
        form.addRow(self.tr("Reason"), self.reason)
        form.addRow(self.buttons)

    def reason_text(self) -> str:
        return self.reason.text().strip()


# section -> (tab title, [(column header, key, kind)]); kind: "text", "num", "opt" (a
# number that may be left empty), "priority"
SECTIONS: dict[str, tuple[str, list[tuple[str, str, str]]]] = {
    "limit": (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Limits"), [
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Label"), "label", "text"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Unit"), "unit", "text"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Low"), "low", "opt"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "High"), "high", "opt"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Deadband"), "deadband", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Priority"), "priority", "priority"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "On delay s"), "on_delay_s", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Off delay s"), "off_delay_s", "num")]),
    "rate": (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Rate of rise"), [
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Rise per min"), "rise_per_min", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Window s"), "window_s", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Deadband"), "deadband", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Priority"), "priority", "priority"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "On delay s"), "on_delay_s", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Off delay s"), "off_delay_s", "num")]),
    "stale": (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Stale data"), [
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "After s"), "after_s", "num"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Priority"), "priority", "priority")]),
    "flag": (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Robot faults"), [
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Text"), "text", "text"),
        (QT_TRANSLATE_NOOP("AlarmSettingsDialog", "Priority"), "priority", "priority")]),
}
COLUMNS = ("Channel",) + tuple(h for h, _, _ in SECTIONS["limit"][1])


def _rows(config: AlarmConfig, section: str) -> list[tuple[str, dict]]:
    if section == "limit":
        return [(r.channel, vars(r)) for r in config.limits]
    if section == "rate":
        return [(r.channel, vars(r)) for r in config.rates]
    if section == "stale":
        return [(r.channel, vars(r)) for r in config.stale]
    return [(name, {"priority": pri, "text": text}) for name, (pri, text) in config.flags.items()]


class AlarmSettingsDialog(QDialog):
    """Limits, rate-of-rise and stale-data rules, the robot faults' priorities and
    the flood threshold, one tab each. The values are checked as a TOML file would
    be; OK stays disabled while anything is wrong, and the problems are listed by
    key."""

    def __init__(self, config: AlarmConfig, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Alarm settings"))
        self.base = config
        self.result_config: AlarmConfig | None = None
        self.tables: dict[str, QTableWidget] = {}
        tabs = QTabWidget(self)
        for section, (title, cols) in SECTIONS.items():
            rows = _rows(config, section)
            t = QTableWidget(len(rows), len(cols) + 1, self)
            first = self.tr("Flag") if section == "flag" else self.tr("Channel")
            t.setHorizontalHeaderLabels([first] + [self.tr(h) for h, _, _ in cols])
            t.verticalHeader().setVisible(False)
            t.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
            for r, (name, values) in enumerate(rows):
                item = QTableWidgetItem(name)
                item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsEditable)
                t.setItem(r, 0, item)
                for c, (_, key, kind) in enumerate(cols, start=1):
                    v = values.get(key)
                    if kind == "priority":
                        box = QComboBox(t)
                        for p in sorted(Priority, reverse=True):  # shown translated
                            box.addItem(translate("Priority", p.name), p.name)
                        box.setCurrentIndex(box.findData(Priority(v).name))
                        box.currentTextChanged.connect(self.validate)
                        t.setCellWidget(r, c, box)
                        continue
                    text = "" if v is None else (f"{v:g}" if isinstance(v, float) else str(v))
                    t.setItem(r, c, QTableWidgetItem(text))
            t.itemChanged.connect(self.validate)
            self.tables[section] = t
            tabs.addTab(t, self.tr(title))
        self.table = self.tables["limit"]
        self.flood = QSpinBox(self)
        self.flood.setRange(1, 1000)
        self.flood.setValue(config.flood_per_minute)
        self.flood.setSuffix(self.tr(" alarms in {s} s").format(s=f"{config.flood_window_s:g}"))
        self.problems = QLabel("", self)
        self.problems.setWordWrap(True)
        self.problems.setObjectName("settingsProblems")
        self.save_button = QPushButton(self.tr("Save as TOML…"), self)
        self.save_button.clicked.connect(self._save_dialog)
        self.buttons = QDialogButtonBox(
            QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel, self)
        self.buttons.addButton(self.save_button, QDialogButtonBox.ButtonRole.ActionRole)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        lay = QVBoxLayout(self)
        lay.addWidget(QLabel(self.tr("Limits: an empty Low or High means no such limit. Delays "
                             "in seconds, deadbands in the channel's unit."), self))
        lay.addWidget(tabs, 1)
        form = QFormLayout()
        form.addRow(self.tr("Flood guard above"), self.flood)
        lay.addLayout(form)
        lay.addWidget(self.problems)
        lay.addWidget(self.buttons)
        self.flood.valueChanged.connect(self.validate)
        self.resize(900, 380)
        self.validate()

    # ------------------------------------------------------------ editing
    def set_cell(self, name: str, column: str, text: str, section: str = "limit") -> None:
        """Type ``text`` into the cell of ``name`` / ``column`` (used by tests too)."""
        t = self.tables[section]
        r = self._row(t, name)
        headers = ["Flag" if section == "flag" else "Channel"] + [
            h for h, _, _ in SECTIONS[section][1]]  # the source (English) column names
        c = headers.index(column)
        w = t.cellWidget(r, c)
        if isinstance(w, QComboBox):
            w.setCurrentIndex(w.findData(text))
        else:
            t.item(r, c).setText(text)

    @staticmethod
    def _row(t: QTableWidget, name: str) -> int:
        for r in range(t.rowCount()):
            if t.item(r, 0).text() == name:
                return r
        raise KeyError(name)

    def _tables(self) -> tuple[dict, list[str]]:
        """The tables as TOML-shaped data, and the cells that are not numbers."""
        data: dict[str, dict] = {}
        problems: list[str] = []
        for section, (_, cols) in SECTIONS.items():
            t = self.tables[section]
            out: dict[str, dict] = {}
            for r in range(t.rowCount()):
                name = t.item(r, 0).text()
                row: dict = {}
                for c, (_, key, kind) in enumerate(cols, start=1):
                    w = t.cellWidget(r, c)
                    text = (str(w.currentData()) if isinstance(w, QComboBox)
                            else t.item(r, c).text()).strip()
                    if kind in ("text", "priority"):
                        if text or kind == "priority":
                            row[key] = text
                        continue
                    if not text:
                        if kind == "opt":
                            continue
                        text = "0"
                    try:
                        v = float(text)
                        if not math.isfinite(v):
                            raise ValueError
                    except ValueError:
                        problems.append(f"settings: [{section}.{name}] {key}: expected a "
                                        f"number, got {text!r}")
                        continue
                    row[key] = v
                out[name] = row
            data[section] = out
        return data, problems

    def validate(self, *_args) -> list[str]:
        tables, problems = self._tables()
        raw = dict(getattr(self.base, "_raw", {}))
        for section, rows in tables.items():  # keys the dialog does not show are kept
            shown = {key for _, key, _ in SECTIONS[section][1]}
            for name, row in rows.items():
                for key, v in raw.get(section, {}).get(name, {}).items():
                    if key not in shown:
                        row.setdefault(key, v)
        raw.update(tables)
        raw["flood"] = {**raw.get("flood", {}), "max_per_minute": self.flood.value()}
        cfg, more = parse_alarm_config(raw, "settings")
        problems += [p for p in more if p not in problems]
        # a rule the parser had to leave out (bad row) must not silently fall back
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
        path, _ = QFileDialog.getSaveFileName(self, self.tr("Save alarm rules"), "alarms.toml",
                                              self.tr("TOML (*.toml)"))
        if path:
            try:
                self.save(path)
            except (OSError, ValueError) as e:
                self.problems.setText(self.tr("could not save {path}: {why}").format(path=path,
                                                                                   why=e))
