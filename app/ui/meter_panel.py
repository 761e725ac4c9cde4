"""Meters tab: the latest recorded reading of every gauge, and the operator's read button.

One row per gauge: point, gauge, value, unit, normal band, state (normal / out of band /
no reading), confidence, time (UTC) and a note (the reason when there is no reading).
"""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.core.meter_service import NO_READING, OUT_OF_BAND, MeterRecord
from app.ui import theme
from app.ui.meter_model import MeterModel

__all__ = ["COLUMNS", "MeterModel", "MeterPanel"]

log = logging.getLogger(__name__)

# the source text (English) names the columns in rows(); the header shows them translated
COLUMNS = (QT_TRANSLATE_NOOP("MeterPanel", "Point"), QT_TRANSLATE_NOOP("MeterPanel", "Gauge"),
           QT_TRANSLATE_NOOP("MeterPanel", "Value"), QT_TRANSLATE_NOOP("MeterPanel", "Unit"),
           QT_TRANSLATE_NOOP("MeterPanel", "Normal band"), QT_TRANSLATE_NOOP("MeterPanel", "State"),
           QT_TRANSLATE_NOOP("MeterPanel", "Confidence"), QT_TRANSLATE_NOOP("MeterPanel", "Time"),
           QT_TRANSLATE_NOOP("MeterPanel", "Note"))


def _note(rec: MeterRecord) -> str:
    """The reason there is no reading; for a calibrated point, that it was read as one."""
    calibrated = (translate("MeterPanel", "calibrated point")
                  if (rec.method or "").startswith("calibrated") else "")
    return "; ".join(t for t in (rec.reason or "", calibrated) if t)


class MeterPanel(QWidget):
    read_requested = Signal(str)  # gauge id
    calibrate_requested = Signal()
    point_calibrated = Signal(str, str)  # point, calibrated profile path

    def __init__(self, model: MeterModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.gauge_combo = QComboBox(self)
        self.gauge_combo.addItems(model.gauge_ids())
        self.read_button = QPushButton(self.tr("Read meter"), self)
        self.read_button.setToolTip(self.tr("Aim the camera at the chosen gauge and read it"))
        self.calibrate_button = QPushButton(self.tr("Calibrate…"), self)
        self.calibrate_button.setToolTip(self.tr("Make a gauge profile, or calibrate an inspection "
                                         "point of the route, on the current frame"))
        self.status_label = QLabel(self.tr("idle"), self)
        top = QHBoxLayout()
        top.addWidget(QLabel(self.tr("Gauge"), self))
        top.addWidget(self.gauge_combo)
        top.addWidget(self.read_button)
        top.addWidget(self.calibrate_button)
        top.addWidget(self.status_label, 1)
        self.table = QTableWidget(0, len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels([translate("MeterPanel", c) for c in COLUMNS])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.
                                                           ResizeToContents)
        self.table.horizontalHeader().setStretchLastSection(True)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(top)
        lay.addWidget(self.table, 1)
        self._rows: dict[str, int] = {}
        self.dialog = None
        self.read_button.clicked.connect(self._on_read)
        self.calibrate_button.clicked.connect(self._on_calibrate)
        self.read_requested.connect(model.request_read)
        model.record_added.connect(self.show_record)
        model.status_changed.connect(self.status_label.setText)
        model.session_changed.connect(lambda g: self.read_button.setEnabled(g is None))
        for rec in model.records():
            self.show_record(rec)

    def _on_read(self) -> None:
        gid = self.gauge_combo.currentText()
        if gid:
            self.read_requested.emit(gid)

    def _on_calibrate(self) -> None:
        from app.ui.calibration_dialog import CalibrationDialog

        img, at = self.model.calibration_frame()
        if img is None:
            self.status_label.setText(self.tr("no frame to calibrate on yet"))
            return
        self.calibrate_requested.emit()
        dlg = CalibrationDialog(img.copy(), self, service=self.model.service, point=at)
        dlg.point_calibrated.connect(lambda *_: self.model.reload_route())
        dlg.point_calibrated.connect(self.point_calibrated)
        dlg.open()
        self.dialog = dlg  # the open calibration dialog (kept alive while open)

    def show_record(self, rec: MeterRecord) -> None:
        row = self._rows.get(rec.gauge_id)
        if row is None:
            row = self.table.rowCount()
            self.table.insertRow(row)
            self._rows[rec.gauge_id] = row
        value = "—" if rec.value is None else f"{rec.value:.4g}"
        conf = f"{rec.confidence:.2f}"
        cells = (rec.point, rec.gauge_id, value, rec.unit, rec.band_text,
                 translate("MeterState", rec.state), conf,
                 rec.time_utc.replace("T", " ").replace("+00:00", " UTC"), _note(rec))
        color = None
        if rec.state == OUT_OF_BAND:
            color = QColor(theme.ALARM_MEDIUM)
        elif rec.state == NO_READING:
            color = QColor(theme.TEXT_DIM)
        for col, text in enumerate(cells):
            item = QTableWidgetItem(text)
            if col in (2, 6):
                item.setTextAlignment(Qt.AlignmentFlag.AlignRight |
                                      Qt.AlignmentFlag.AlignVCenter)
            if color is not None and col == 5:
                item.setForeground(QBrush(color))
            self.table.setItem(row, col, item)

    # ------------------------------------------------------------ queries (tests)
    def row_texts(self, gauge_id: str) -> dict[str, str] | None:
        row = self._rows.get(gauge_id)
        if row is None:
            return None
        return {name: (self.table.item(row, c).text() if self.table.item(row, c) else "")
                for c, name in enumerate(COLUMNS)}
