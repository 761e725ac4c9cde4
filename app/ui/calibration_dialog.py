"""Calibrating a new gauge type on a frozen frame.

The operator clicks the dial's centre, then the minimum tick, then the maximum tick, and
enters the two values, a name, a unit and (optionally) the normal band.
:func:`app.core.meter.calibrate_profile` turns the three points into an angle-form profile
and :func:`app.core.meter.save_profile` writes it (by default to
``resources/gauges/<name>.json``).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from app.core.meter import calibrate_profile, save_profile
from app.core.meter_service import DEFAULT_GAUGE_DIR
from app.widgets import ImageView, OverlayLine, OverlayText

__all__ = ["CalibrationDialog", "ClickImageView"]

log = logging.getLogger(__name__)

STEPS = ("centre", "minimum tick", "maximum tick")
MARK_COLORS = ("#00e5ff", "#3ddc84", "#ff5252")


class ClickImageView(ImageView):
    """An ImageView that reports clicks in image pixel coordinates."""

    clicked = Signal(float, float)

    def widget_to_image(self, p: QPointF) -> tuple[float, float] | None:
        size = self.image_size()
        r = self.target_rect()
        if size is None or r.width() <= 0 or not r.contains(p):
            return None
        return ((p.x() - r.x()) * size[0] / r.width(), (p.y() - r.y()) * size[1] / r.height())

    def image_to_widget(self, x: float, y: float) -> QPointF:
        size = self.image_size()
        r = self.target_rect()
        return QPointF(r.x() + x * r.width() / size[0], r.y() + y * r.height() / size[1])

    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt name)
        xy = self.widget_to_image(event.position())
        if xy is not None:
            self.clicked.emit(*xy)
        super().mousePressEvent(event)


def _spin(lo: float, hi: float, value: float, decimals: int = 3) -> QDoubleSpinBox:
    s = QDoubleSpinBox()
    s.setRange(lo, hi)
    s.setDecimals(decimals)
    s.setValue(value)
    return s


class CalibrationDialog(QDialog):
    """``CalibrationDialog(image_rgb)``: click centre, min tick, max tick; fill in; Save."""

    profile_saved = Signal(str)  # the path written

    def __init__(self, image_rgb: np.ndarray, parent: QWidget | None = None, *,
                 save_dir: str | Path = DEFAULT_GAUGE_DIR) -> None:
        super().__init__(parent)
        self.setWindowTitle("Calibrate a gauge profile")
        self.save_dir = Path(save_dir)
        self.points: list[tuple[float, float]] = []
        self.saved_path: Path | None = None
        self.view = ClickImageView(self, placeholder="no frame")
        self.view.setMinimumSize(480, 360)
        self.view.set_image(np.ascontiguousarray(image_rgb))
        self.prompt = QLabel(self)
        self.undo_button = QPushButton("Undo point", self)
        self.name_edit = QLineEdit(self)
        self.unit_edit = QLineEdit("MPa", self)
        self.min_spin = _spin(-1e6, 1e6, 0.0)
        self.max_spin = _spin(-1e6, 1e6, 1.6)
        self.clockwise_check = QCheckBox("scale runs clockwise", self)
        self.clockwise_check.setChecked(True)
        self.band_check = QCheckBox("normal band", self)
        self.normal_min_spin = _spin(-1e6, 1e6, 0.0)
        self.normal_max_spin = _spin(-1e6, 1e6, 1.0)
        self.path_edit = QLineEdit(self)
        self.error_label = QLabel("", self)
        self.error_label.setWordWrap(True)
        form = QFormLayout()
        form.addRow("Name", self.name_edit)
        form.addRow("Unit", self.unit_edit)
        form.addRow("Value at minimum tick", self.min_spin)
        form.addRow("Value at maximum tick", self.max_spin)
        form.addRow("", self.clockwise_check)
        band = QHBoxLayout()
        band.addWidget(self.band_check)
        band.addWidget(self.normal_min_spin)
        band.addWidget(QLabel("…"))
        band.addWidget(self.normal_max_spin)
        form.addRow("Alarm", band)
        form.addRow("Save to", self.path_edit)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Save
                                        | QDialogButtonBox.StandardButton.Cancel, self)
        self.save_button = self.buttons.button(QDialogButtonBox.StandardButton.Save)
        self.buttons.accepted.connect(self.save)
        self.buttons.rejected.connect(self.reject)
        side = QVBoxLayout()
        side.addWidget(self.prompt)
        side.addWidget(self.undo_button)
        side.addLayout(form)
        side.addWidget(self.error_label)
        side.addStretch(1)
        side.addWidget(self.buttons)
        lay = QHBoxLayout(self)
        lay.addWidget(self.view, 2)
        lay.addLayout(side, 1)
        self.view.clicked.connect(self.add_point)
        self.undo_button.clicked.connect(self.undo_point)
        self.name_edit.textChanged.connect(self._on_name)
        self._path_touched = False
        self.path_edit.textEdited.connect(lambda _t: setattr(self, "_path_touched", True))
        self._refresh()

    # ------------------------------------------------------------ points
    def add_point(self, x: float, y: float) -> None:
        if len(self.points) >= len(STEPS):
            return
        self.points.append((float(x), float(y)))
        self._refresh()

    def undo_point(self) -> None:
        if self.points:
            self.points.pop()
        self._refresh()

    def next_step(self) -> str | None:
        return STEPS[len(self.points)] if len(self.points) < len(STEPS) else None

    def _refresh(self) -> None:
        step = self.next_step()
        self.prompt.setText(f"Click the {step}." if step else
                            "All three points set; fill in and save.")
        ovs: list = []
        for i, (x, y) in enumerate(self.points):
            c = MARK_COLORS[i]
            ovs += [OverlayLine(x - 8, y, x + 8, y, c), OverlayLine(x, y - 8, x, y + 8, c),
                    OverlayText(x + 6, y - 6, STEPS[i], c)]
        if len(self.points) >= 2:
            cx, cy = self.points[0]
            for x, y in self.points[1:]:
                ovs.append(OverlayLine(cx, cy, x, y, "#ffffff"))
        self.view.set_overlays(ovs)
        self.save_button.setEnabled(step is None)

    def _on_name(self, name: str) -> None:
        if not self._path_touched:
            self.path_edit.setText(str(self.save_dir / f"{name.strip()}.json")
                                   if name.strip() else "")

    # ------------------------------------------------------------ result
    def profile_dict(self) -> dict:
        """The profile from the points and fields; ValueError names what is wrong."""
        if len(self.points) < 3:
            raise ValueError(f"click the {self.next_step()} first")
        name = self.name_edit.text().strip()
        if not name:
            raise ValueError("enter a name")
        nmin = self.normal_min_spin.value() if self.band_check.isChecked() else None
        nmax = self.normal_max_spin.value() if self.band_check.isChecked() else None
        c, p0, p1 = self.points
        return calibrate_profile(c, p0, p1, self.min_spin.value(), self.max_spin.value(),
                                 name=name, unit=self.unit_edit.text().strip(),
                                 clockwise=self.clockwise_check.isChecked(),
                                 normal_min=nmin, normal_max=nmax)

    def save(self) -> Path | None:
        try:
            d = self.profile_dict()
            path = Path(self.path_edit.text().strip() or self.save_dir / f"{d['name']}.json")
            path.parent.mkdir(parents=True, exist_ok=True)
            written = save_profile(d, path)
        except (ValueError, OSError) as e:
            self.error_label.setText(str(e))
            log.warning("calibration not saved: %s", e)
            return None
        self.saved_path = Path(written)
        self.error_label.setText("")
        self.profile_saved.emit(str(written))
        self.accept()
        return self.saved_path
