"""The map panel's read-out of the patrol: what the robot says it is doing.

- :class:`PatrolStatus` — the state line (with its age, greyed, once the status
  is no longer current; in alarm colour for an abnormal state), the route and the
  local planner, the localisation line, the progress bar and the reason.
- :class:`PatrolPointsTable` — the route's points with their states, one row
  each; the operator selects a row to send the robot there.

Both only show what the MapModel holds and send nothing; the MapPanel places
them, with its patrol buttons between the two. Their strings keep the map
panel's translation context ("MapPanel"), as they did when they lived there.
"""

from __future__ import annotations

import math

from PySide6.QtCore import QCoreApplication
from PySide6.QtGui import QColor, QFont
from PySide6.QtWidgets import (
    QLabel,
    QProgressBar,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.pose_estimate import quality_line
from app.ui import theme
from app.ui.map_model import PATROL_ABNORMAL, MapModel, patrol_state_text
from app.widgets.stale import set_stale

__all__ = ["PatrolPointsTable", "PatrolStatus"]



class PatrolStatus(QWidget):
    """The patrol's state, route, localisation, progress and reason lines."""

    def __init__(self, model: MapModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.state_label = QLabel(QCoreApplication.translate("MapPanel", "Patrol: —"), self)
        self._patrol_age = ""  # "last known ..." once the patrol status is not current
        self.state_label.setWordWrap(True)
        f = QFont(self.state_label.font())
        f.setBold(True)
        self.state_label.setFont(f)
        self.route_label = QLabel(QCoreApplication.translate("MapPanel", "Route: —"), self)
        self.loc_label = QLabel(quality_line(None)[0], self)
        self.loc_label.setWordWrap(True)
        self.reason_label = QLabel("", self)
        self.reason_label.setWordWrap(True)
        self.progress = QProgressBar(self)
        self.progress.setRange(0, 100)
        self.progress.setValue(0)
        self.progress.setFormat("%p %")
        self.progress.setStyleSheet("QProgressBar::chunk { background-color: #8a8a8a; }")
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        for w in (self.state_label, self.route_label, self.loc_label, self.progress,
                  self.reason_label):
            lay.addWidget(w)

    def show_quality(self, quality) -> None:
        """The localisation line for ``quality`` (a PoseQuality or None), in alarm
        colour when the operator must act."""
        text, needs_operator = quality_line(quality)
        if text != self.loc_label.text():
            self.loc_label.setText(text)
            alarm = f"color: {theme.ALARM_HIGH};"
            self.loc_label.setStyleSheet(alarm if needs_operator else "")

    def show_age(self, text: str) -> None:
        """``text``: the patrol status's age ("" while it is current); the state line
        says it and loses its colour."""
        if text != self._patrol_age:
            self._patrol_age = text
            set_stale(self.state_label, bool(text))
            self._show_state_line()

    def show_patrol(self) -> None:
        """The lines for the model's patrol status."""
        p = self.model.patrol or {}
        self._show_state_line()
        planner = (QCoreApplication.translate("MapPanel", "  ·  local planner {name}")
                   .format(name=p["local_planner"]) if p.get("local_planner") else "")
        self.route_label.setText(QCoreApplication.translate("MapPanel", "Route: {route}").format(
            route=patrol_state_text(p.get("route") or "—"))
                                 + planner)
        prog = p.get("progress", 0.0)
        if math.isfinite(prog):
            self.progress.setValue(int(round(100 * min(max(prog, 0.0), 1.0))))
        self.reason_label.setText(patrol_state_text(p.get("reason", "")))

    def _show_state_line(self) -> None:
        state = (self.model.patrol or {}).get("state", "")
        line = QCoreApplication.translate("MapPanel", "Patrol: {state}").format(
            state=patrol_state_text(state, upper=True) if state else "—")
        self.state_label.setText(f"{line} ({self._patrol_age})" if self._patrol_age else line)
        color = theme.ALARM_HIGH if state in PATROL_ABNORMAL and not self._patrol_age else None
        sheet = f"color: {color};" if color else ""
        if sheet != self.state_label.styleSheet():  # a new style sheet re-polishes: dear
            self.state_label.setStyleSheet(sheet)


class PatrolPointsTable(QTableWidget):
    """The patrol's points (name, kind, state), one selectable row each."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(0, 3, parent)
        self.setHorizontalHeaderLabels((QCoreApplication.translate("MapPanel", "point"),
                                        QCoreApplication.translate("MapPanel", "kind"),
                                        QCoreApplication.translate("MapPanel", "state")))
        self.verticalHeader().setVisible(False)
        self.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.setSelectionMode(QTableWidget.SelectionMode.SingleSelection)
        self.horizontalHeader().setStretchLastSection(True)
        self._shown: list[dict] = []  # the patrol points the table shows

    def show_points(self, pts: list[dict]) -> None:
        """Refill the rows when the points or their states changed (a status comes
        often; its points change rarely)."""
        if pts == self._shown:
            return
        self._shown = [dict(q) for q in pts]
        self.setRowCount(len(pts))
        for r, q in enumerate(pts):
            for c, text in enumerate((q["name"], patrol_state_text(q["kind"]),
                                      patrol_state_text(q["state"]))):
                item = QTableWidgetItem(text)
                if q["state"] == "current":
                    item.setForeground(QColor(theme.ACCENT))
                    fb = item.font()
                    fb.setBold(True)
                    item.setFont(fb)
                elif q["state"] in ("skipped", "failed"):
                    item.setForeground(QColor(theme.ALARM_HIGH))
                elif q["state"] == "done":
                    item.setForeground(QColor(theme.TEXT_DIM))
                self.setItem(r, c, item)
