"""The alarm list's table model: one row per listed alarm (or, during a flood, per
source), its cells as the operator reads them (time, priority mark, source,
alarm text, value, limit, ISA-18.2 state, the latest comment), coloured by
priority (ISA-101: a handled alarm is dimmed, never coloured).

Column names and state texts are English source strings; the table shows them
translated (context "AlarmPanel").

The panel gives the model its rows again every second (values move without
transitions). When the rows are the same alarms (or groups) in the same order,
only the rows whose cells or look changed are announced (``dataChanged``): a
model reset would have the view measure every cell of every row again for its
fitted columns and repaint the whole table, every second. The cells shown are the
ones worked out for that comparison, not formatted again for each paint.
"""

from __future__ import annotations

from PySide6.QtCore import QAbstractTableModel, Qt
from PySide6.QtGui import QBrush, QColor

from app.core.alarms import Alarm, AlarmGroup, AlarmState
from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui import theme
from app.ui.alarm_banner import LOOK, priority_mark
from app.ui.event_log import clock_text, source_text

__all__ = ["AlarmTableModel", "COLUMNS", "STATE_FILTERS", "STATE_TEXT"]

# the source text (English) names the columns in rows(); the header shows them translated
COLUMNS = (QT_TRANSLATE_NOOP("AlarmPanel", "Time"), QT_TRANSLATE_NOOP("AlarmPanel", "Priority"),
           QT_TRANSLATE_NOOP("AlarmPanel", "Source"), QT_TRANSLATE_NOOP("AlarmPanel", "Alarm"),
           QT_TRANSLATE_NOOP("AlarmPanel", "Value"), QT_TRANSLATE_NOOP("AlarmPanel", "Limit"),
           QT_TRANSLATE_NOOP("AlarmPanel", "State"), QT_TRANSLATE_NOOP("AlarmPanel", "Comment"))
STATE_TEXT = {
    AlarmState.UNACK: QT_TRANSLATE_NOOP("AlarmPanel", "ACTIVE, unacknowledged"),
    AlarmState.ACKED: QT_TRANSLATE_NOOP("AlarmPanel", "ACTIVE, acknowledged"),
    AlarmState.RTN_UNACK: QT_TRANSLATE_NOOP("AlarmPanel", "CLEARED, unacknowledged"),
    AlarmState.SHELVED: QT_TRANSLATE_NOOP("AlarmPanel", "SHELVED"),
    AlarmState.OUT_OF_SERVICE: QT_TRANSLATE_NOOP("AlarmPanel", "OUT OF SERVICE"),
    AlarmState.NORMAL: QT_TRANSLATE_NOOP("AlarmPanel", "normal"),
}
STATE_FILTERS: tuple[tuple[str, frozenset | None], ...] = (
    (QT_TRANSLATE_NOOP("AlarmPanel", "All listed"), None),
    (QT_TRANSLATE_NOOP("AlarmPanel", "Unacknowledged"),
     frozenset({AlarmState.UNACK, AlarmState.RTN_UNACK})),
    (QT_TRANSLATE_NOOP("AlarmPanel", "Active"), frozenset({AlarmState.UNACK, AlarmState.ACKED})),
    (QT_TRANSLATE_NOOP("AlarmPanel", "Cleared, unacknowledged"),
     frozenset({AlarmState.RTN_UNACK})),
    (QT_TRANSLATE_NOOP("AlarmPanel", "Shelved"), frozenset({AlarmState.SHELVED})),
    (QT_TRANSLATE_NOOP("AlarmPanel", "Out of service"), frozenset({AlarmState.OUT_OF_SERVICE})),
)



def _value_text(a: Alarm) -> str:
    v = a.last_value if a.last_value is not None else a.value
    if a.condition in ("high", "low", "rate") and v is not None:
        unit = f" {a.unit}" if a.unit else ""
        per = "/min" if a.condition == "rate" else ""
        return f"{v:.2f}{unit}{per}"
    if a.condition == "stale" and v is not None:
        return f"{v:.0f} s"
    return translate("AlarmPanel", "set") if a.active else translate("AlarmPanel", "clear")


def _label(a: Alarm) -> str:
    return translate("AlarmText", a.label) if a.label else source_text(a.source)


def _comment_text(a: Alarm) -> str:
    if not a.comment:
        return ""
    return f"{a.comment_by}: {a.comment}" if a.comment_by else a.comment


def _state_text(a: Alarm) -> str:
    text = translate("AlarmPanel", STATE_TEXT[a.state])
    if a.state is AlarmState.SHELVED and a.shelved_until is not None:
        text += translate("AlarmPanel", " until {time}").format(time=clock_text(a.shelved_until))
    if a.reason and a.state in (AlarmState.SHELVED, AlarmState.OUT_OF_SERVICE):
        text += f" ({a.reason})"
    return text


class AlarmTableModel(QAbstractTableModel):
    """Rows of alarm snapshots (or, during a flood, of groups by source)."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.alarms: list[Alarm] = []
        self.groups: list[AlarmGroup] = []
        self.grouped = False
        self._looks: list[tuple] = []  # each row as last shown (_look)
        self.resets = 0

    def set_rows(self, alarms: list[Alarm], groups: list[AlarmGroup] | None) -> bool:
        """The rows to show. Returns True when the model was reset (other rows than
        before, or another order: a selection must be put back), False when only
        changed rows were announced."""
        grouped = groups is not None
        keys = [tuple(g.keys) for g in groups] if grouped else [(a.key,) for a in alarms]
        same = grouped == self.grouped and keys == [tuple(self.keys_at(r)) for r in
                                                    range(self.rowCount())]
        if not same:
            self.beginResetModel()
        self.alarms = alarms
        self.grouped = grouped
        self.groups = groups or []
        looks = [self._look(r) for r in range(self.rowCount())]
        if not same:
            self._looks = looks
            self.endResetModel()
            self.resets += 1
            return True
        last = len(COLUMNS) - 1
        changed = [r for r, (old, new) in enumerate(zip(self._looks, looks, strict=True))
                   if old != new]
        self._looks = looks  # what data() shows, before the views hear of it
        for r in changed:
            self.dataChanged.emit(self.index(r, 0), self.index(r, last))
        return False

    def _look(self, row: int) -> tuple:
        """All a row shows: its cells, priority, state and tooltip."""
        if self.grouped:
            g = self.groups[row]
            return self.cells(row), g.priority, g.keys
        a = self.alarms[row]
        return self.cells(row), a.priority, a.state, a.text, a.comment, a.comment_t

    def rowCount(self, parent=None) -> int:  # noqa: N802 (Qt's name)
        if parent is not None and parent.isValid():
            return 0
        return len(self.groups if self.grouped else self.alarms)

    def columnCount(self, parent=None) -> int:  # noqa: N802
        return 0 if parent is not None and parent.isValid() else len(COLUMNS)

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return translate("AlarmPanel", COLUMNS[section])
        return None

    def keys_at(self, row: int) -> tuple[str, ...]:
        if self.grouped:
            return self.groups[row].keys
        return (self.alarms[row].key,)

    def alarm_at(self, row: int) -> Alarm | None:
        return None if self.grouped else self.alarms[row]

    def cells(self, row: int) -> tuple[str, ...]:
        if self.grouped:
            g = self.groups[row]
            times = [a.raised_t for a in self.alarms if a.key in g.keys]
            return (clock_text(max(times)) if times else "", priority_mark(g.priority),
                    g.source, translate("AlarmPanel", "{n} alarms ({unacked} unacknowledged)")
                    .format(n=g.count, unacked=g.unacked), "", "",
                    "GROUP", "")
        a = self.alarms[row]
        unit = f" {a.unit}" if a.unit else ""
        limit = "" if a.limit is None else (
            f"{a.limit:g}{unit}/min" if a.condition == "rate" else
            f"{a.limit:g} s" if a.condition == "stale" else f"{a.limit:g}{unit}")
        return (clock_text(a.raised_t), priority_mark(a.priority), source_text(a.source),
                translate("AlarmPanel", "{label} high").format(label=_label(a))
                if a.condition == "high" else
                translate("AlarmPanel", "{label} low").format(label=_label(a))
                if a.condition == "low" else a.text,
                _value_text(a), limit, _state_text(a), _comment_text(a))

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        r, c = index.row(), index.column()
        if role == Qt.ItemDataRole.DisplayRole:  # the cells as set_rows worked them out
            return self._looks[r][0][c]
        pri = self.groups[r].priority if self.grouped else self.alarms[r].priority
        state = None if self.grouped else self.alarms[r].state
        dim = state in (AlarmState.ACKED, AlarmState.SHELVED, AlarmState.OUT_OF_SERVICE,
                        AlarmState.RTN_UNACK)
        if role == Qt.ItemDataRole.BackgroundRole and c == 1 and not dim:
            return QBrush(QColor(LOOK[pri][0]))
        if role == Qt.ItemDataRole.ForegroundRole:
            if c == 1 and not dim:
                return QBrush(QColor(LOOK[pri][1]))
            if dim:
                return QBrush(QColor(theme.TEXT_DIM))
        if role == Qt.ItemDataRole.ToolTipRole:
            if self.grouped:
                return "; ".join(self.keys_at(r))
            a = self.alarms[r]
            return a.text + (f"\n{clock_text(a.comment_t)}  {_comment_text(a)}"
                             if a.comment else "")
        if role == Qt.ItemDataRole.UserRole:
            return self.keys_at(r)
        return None

