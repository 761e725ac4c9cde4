"""Calibrating a gauge on a frozen frame: a new gauge type, or one inspection point.

The operator clicks the dial's centre (the needle's pivot), then the minimum tick, then the
maximum tick.  "Suggest" fills the three from the uncalibrated reader's findings (on a
worker thread) for the operator to check and correct.

- **New gauge profile**: enter the two values, a name, a unit and (optionally) the normal
  band; :func:`app.core.meter.calibrate_profile` turns the points into an angle-form
  profile and :func:`app.core.meter.save_profile` writes it (by default to
  ``<user data>/gauges/<name>.json``, app.core.paths).
- **Inspection point** of the active route (the point the robot is at is chosen first): the
  values come from the gauge type's profile; :func:`app.core.inspection_points.
  calibrate_point` stores the calibrated profile and this frame as its reference beside the
  route, and later patrols read that point with it.
"""

from __future__ import annotations

import functools
import logging
from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
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

from app.core.i18n import QT_TRANSLATE_NOOP
from app.core.inspection_points import calibrate_point, suggest_points
from app.core.meter import calibrate_profile, load_profile, save_profile
from app.core.meter_service import MeterService
from app.core.paths import user_gauges_dir
from app.gui_jobs import GuiJobs
from app.widgets import ImageView, OverlayLine, OverlayText

__all__ = ["CalibrationDialog", "ClickImageView"]

log = logging.getLogger(__name__)

STEPS = (QT_TRANSLATE_NOOP("CalibrationDialog", "centre"),
         QT_TRANSLATE_NOOP("CalibrationDialog", "minimum tick"),
         QT_TRANSLATE_NOOP("CalibrationDialog", "maximum tick"))
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
    """``CalibrationDialog(image_rgb)``: click centre, min tick, max tick; fill in; Save.

    With a ``service`` whose active route has meter points, "Store for" offers each point;
    ``point`` chooses one at the start (the point the robot is inspecting)."""

    profile_saved = Signal(str)  # the path written
    point_calibrated = Signal(str, str)  # point, calibrated profile path
    points_suggested = Signal(bool)  # the suggestion came back: points set or not

    def __init__(self, image_rgb: np.ndarray, parent: QWidget | None = None, *,
                 save_dir: str | Path | None = None,
                 service: MeterService | None = None, point: str | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Calibrate a gauge profile"))
        # the operator's profiles folder (user_gauges_dir), never the shipped resources
        self.save_dir = user_gauges_dir() if save_dir is None else Path(save_dir)
        self.service = service
        self.image = np.ascontiguousarray(image_rgb)
        self.points: list[tuple[float, float]] = []
        self.saved_path: Path | None = None
        self.target_combo = QComboBox(self)
        self.target_combo.addItem(self.tr("new gauge profile"), None)
        route_points = service.route_points() if service is not None else []
        for name, gauge in route_points:
            self.target_combo.addItem(
                self.tr("inspection point {name} ({gauge})").format(name=name, gauge=gauge),
                (name, gauge))
        self.suggest_button = QPushButton(self.tr("Suggest points"), self)
        self.suggest_button.setToolTip(
            self.tr("Place the three points where the reader finds them"))
        # the suggestion is looked for on the dialog's own pool; a dialog closed
        # meanwhile waits for it and gets no result (app/gui_jobs)
        self._jobs = GuiJobs(self)
        self.view = ClickImageView(self, placeholder=self.tr("no frame"))
        self.view.setMinimumSize(480, 360)
        self.view.set_image(self.image)
        self.prompt = QLabel(self)
        self.undo_button = QPushButton(self.tr("Undo point"), self)
        self.name_edit = QLineEdit(self)
        self.unit_edit = QLineEdit(self.tr("MPa"), self)
        self.min_spin = _spin(-1e6, 1e6, 0.0)
        self.max_spin = _spin(-1e6, 1e6, 1.6)
        self.clockwise_check = QCheckBox(self.tr("scale runs clockwise"), self)
        self.clockwise_check.setChecked(True)
        self.band_check = QCheckBox(self.tr("normal band"), self)
        self.normal_min_spin = _spin(-1e6, 1e6, 0.0)
        self.normal_max_spin = _spin(-1e6, 1e6, 1.0)
        self.path_edit = QLineEdit(self)
        self.error_label = QLabel("", self)
        self.error_label.setWordWrap(True)
        form = QFormLayout()
        form.addRow(self.tr("Store for"), self.target_combo)
        form.addRow(self.tr("Name"), self.name_edit)
        form.addRow(self.tr("Unit"), self.unit_edit)
        form.addRow(self.tr("Value at minimum tick"), self.min_spin)
        form.addRow(self.tr("Value at maximum tick"), self.max_spin)
        form.addRow("", self.clockwise_check)
        band = QHBoxLayout()
        band.addWidget(self.band_check)
        band.addWidget(self.normal_min_spin)
        band.addWidget(QLabel(self.tr("…")))
        band.addWidget(self.normal_max_spin)
        form.addRow(self.tr("Alarm"), band)
        form.addRow(self.tr("Save to"), self.path_edit)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Save
                                        | QDialogButtonBox.StandardButton.Cancel, self)
        self.save_button = self.buttons.button(QDialogButtonBox.StandardButton.Save)
        self.buttons.accepted.connect(self.save)
        self.buttons.rejected.connect(self.reject)
        side = QVBoxLayout()
        side.addWidget(self.prompt)
        side.addWidget(self.undo_button)
        side.addWidget(self.suggest_button)
        side.addLayout(form)
        side.addWidget(self.error_label)
        side.addStretch(1)
        side.addWidget(self.buttons)
        lay = QHBoxLayout(self)
        lay.addWidget(self.view, 2)
        lay.addLayout(side, 1)
        self.view.clicked.connect(self.add_point)
        self.undo_button.clicked.connect(self.undo_point)
        self.suggest_button.clicked.connect(self.suggest)
        self.target_combo.currentIndexChanged.connect(self._on_target)
        self.name_edit.textChanged.connect(self._on_name)
        self._path_touched = False
        self.path_edit.textEdited.connect(lambda _t: setattr(self, "_path_touched", True))
        if point is not None:
            self.choose_point(point)
        self._refresh()

    # ------------------------------------------------------------ target
    def target_point(self) -> tuple[str, str] | None:
        """(point, gauge) being calibrated, or None for a new gauge profile."""
        return self.target_combo.currentData()

    def choose_point(self, point: str | None) -> bool:
        """Store for ``point`` of the active route (None: a new gauge profile)."""
        for i in range(self.target_combo.count()):
            data = self.target_combo.itemData(i)
            if (data is None and point is None) or (data is not None and data[0] == point):
                self.target_combo.setCurrentIndex(i)
                return True
        return False

    def _base_profile(self):
        target = self.target_point()
        if target is None:
            return None
        try:
            return self.service.profile(target[1])
        except ValueError as e:
            self.error_label.setText(str(e))
            return None

    def _on_target(self, _i: int = 0) -> None:
        """A route point takes its values from its gauge type's profile."""
        target = self.target_point()
        for w in (self.name_edit, self.unit_edit, self.min_spin, self.max_spin,
                  self.band_check, self.normal_min_spin, self.normal_max_spin, self.path_edit):
            w.setEnabled(target is None)
        base = self._base_profile()
        if base is None:
            self._on_name(self.name_edit.text())
            return
        self.name_edit.setText(base.name)
        self.unit_edit.setText(base.unit)
        self.min_spin.setValue(base.min_value)
        self.max_spin.setValue(base.max_value)
        self.clockwise_check.setChecked(base.clockwise)
        has_band = base.normal_min is not None or base.normal_max is not None
        self.band_check.setChecked(has_band)
        if base.normal_min is not None:
            self.normal_min_spin.setValue(base.normal_min)
        if base.normal_max is not None:
            self.normal_max_spin.setValue(base.normal_max)
        self.path_edit.setText(self.tr("with the route {name}").format(
            name=self.service.route_path.name))

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

    def set_points(self, centre, min_tick, max_tick) -> None:
        """Set all three points at once (image pixels)."""
        self.points = [(float(x), float(y)) for x, y in (centre, min_tick, max_tick)]
        self._refresh()

    def suggest(self) -> None:
        """Ask the reader, on a worker thread, where the pivot and scale ends are;
        ``points_suggested`` tells when it answered."""
        base = self._base_profile()
        if base is None:
            name = self.name_edit.text().strip()
            try:
                base = load_profile(self.service.profile_file(name) if self.service is not None
                                    else self.save_dir / f"{name}.json")
            except ValueError:
                self.error_label.setText(self.tr("choose an inspection point, or name a known "
                                                 "gauge type, to get a suggestion"))
                self.points_suggested.emit(False)
                return
        self.suggest_button.setEnabled(False)
        self.prompt.setText(self.tr("Looking for the pivot and the scale's ends …"))
        self._jobs.start(functools.partial(suggest_points, self.image, base),
                         self._on_suggested)

    def _on_suggested(self, pts) -> None:
        self.suggest_button.setEnabled(True)
        if pts is None:
            self.error_label.setText(self.tr("the reader found no dial here; click the points"))
            self._refresh()
            self.points_suggested.emit(False)
            return
        self.error_label.setText("")
        self.set_points(*pts)
        self.points_suggested.emit(True)

    def next_step(self) -> str | None:
        return STEPS[len(self.points)] if len(self.points) < len(STEPS) else None

    def _refresh(self) -> None:
        step = self.next_step()
        self.prompt.setText(self.tr("Click the {step}.").format(step=self.tr(step)) if step else
                            self.tr("All three points set; fill in and save."))
        ovs: list = []
        for i, (x, y) in enumerate(self.points):
            c = MARK_COLORS[i]
            ovs += [OverlayLine(x - 8, y, x + 8, y, c), OverlayLine(x, y - 8, x, y + 8, c),
                    OverlayText(x + 6, y - 6, self.tr(STEPS[i]), c)]
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
        if self.target_point() is not None:
            return self._save_point()
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

    def _save_point(self) -> Path | None:
        """Store the calibrated profile and reference frame of the chosen route point."""
        point, _gauge = self.target_point()
        try:
            if len(self.points) < 3:
                raise ValueError(f"click the {self.next_step()} first")
            base = self._base_profile()
            if base is None:
                raise ValueError(self.error_label.text() or self.tr("no profile for this gauge"))
            done = calibrate_point(self.service.route_path, point, base, self.image,
                                   *self.points, clockwise=self.clockwise_check.isChecked())
            if done.route != self.service.route_path:  # a shipped route was copied first
                self.service.set_route(done.route)
        except (ValueError, OSError) as e:
            self.error_label.setText(str(e))
            log.warning("inspection point %s not calibrated: %s", point, e)
            return None
        self.saved_path = done.profile
        self.error_label.setText("")
        self.point_calibrated.emit(point, str(done.profile))
        self.accept()
        return self.saved_path

    def done(self, result: int) -> None:  # noqa: D102 - Qt override
        self._jobs.wait(5000)  # a running suggestion finishes before we go
        super().done(result)
