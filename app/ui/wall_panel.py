"""WallPanel: the tank wall a climber inspects, unrolled — obstacles, sub-regions
and their order, the planned path, the robot, covered cells and the thickness
heat map from the probe — with coverage %, repetition % and the thinnest spots
live, and the inspection's commands.

A thin Qt view over :class:`app.core.desk.wall.WallModel` (the pipeline's, no
Qt): :class:`WallViewModel` turns the pipeline's ``wall`` listener calls into a
``changed`` signal; the view redraws at most 5 times a second. The panel only
emits intents: ``command_requested(name, args)`` with ``start_inspection``,
``pause_inspection``, ``resume_inspection``, ``abort_inspection``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QPointF, QRectF, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QImage, QPainter, QPainterPath, QPen, QPolygonF
from PySide6.QtWidgets import (
    QCheckBox,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from app.core.desk.wall import WallModel, region_centres, wall_picture

__all__ = ["WallPanel", "WallView", "WallViewModel", "install_wall_tab"]

REDRAW_MS = 200


class WallViewModel(QObject):
    """The pipeline's wall model, with a signal per change (``changed(kind)``)."""

    changed = Signal(str)

    def __init__(self, pipeline: Any = None, parent: QObject | None = None) -> None:
        super().__init__(parent)
        if pipeline is None:
            from app.core.desk import DeskPipeline
            pipeline = DeskPipeline()
        self.pipeline = pipeline
        pipeline.listen("wall", self.changed.emit)

    @property
    def wall(self) -> WallModel:
        return self.pipeline.wall


class WallView(QWidget):
    """The unrolled wall, scaled to the widget (x round the tank to the right, y up)."""

    def __init__(self, model: WallViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.layers = {"regions": True, "path": True, "covered": True, "heat": True}
        self._image: QImage | None = None
        self._buf: np.ndarray | None = None
        self._dirty = True
        self.redraws = 0
        self.setMinimumSize(320, 140)
        self._timer = QTimer(self)
        self._timer.setInterval(REDRAW_MS)
        self._timer.timeout.connect(self._refresh)
        self._timer.start()
        model.changed.connect(self._mark)

    def _mark(self, _kind: str = "") -> None:
        self._dirty = True

    def set_layer(self, name: str, on: bool) -> None:
        self.layers[name] = bool(on)
        self._mark()
        self._refresh()

    def _refresh(self) -> None:
        if not self._dirty:
            return
        self._dirty = False
        w = self.model.wall
        rgb = wall_picture(w, self.layers["regions"], self.layers["covered"],
                           self.layers["heat"])
        self._buf = np.ascontiguousarray(rgb[::-1])  # row 0 is the wall's bottom
        h, wd = self._buf.shape[:2]
        self._image = QImage(self._buf.data, wd, h, 3 * wd, QImage.Format.Format_RGB888)
        self.redraws += 1
        self.update()

    def cell_rect(self) -> QRectF:
        """Where the wall is drawn: the widget's area at the wall's aspect ratio."""
        w = self.model.wall
        if not w.ready:
            return QRectF(self.rect())
        rows, cols = w.blocked.shape
        s = min(self.width() / cols, self.height() / rows)
        return QRectF((self.width() - s * cols) / 2, (self.height() - s * rows) / 2,
                      s * cols, s * rows)

    def to_widget(self, x_m: float, y_m: float) -> QPointF:
        w = self.model.wall
        r = self.cell_rect()
        d = w.info.cell_m
        rows, cols = w.blocked.shape
        return QPointF(r.left() + (x_m % (cols * d)) / (cols * d) * r.width(),
                       r.bottom() - y_m / (rows * d) * r.height())

    def paintEvent(self, _event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        p.fillRect(self.rect(), QColor(250, 250, 250))
        w = self.model.wall
        if not w.ready or self._image is None:
            p.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter, "No wall climber connected")
            return
        r = self.cell_rect()
        p.drawImage(r, self._image)
        d = w.info.cell_m
        if self.layers["path"] and len(w.path):
            self._draw_path(p, w, d)
        if self.layers["regions"]:
            p.setPen(QColor(40, 60, 110))
            for i, (_k, row, col) in enumerate(region_centres(w)):
                p.drawText(self.to_widget((col + 0.5) * d, (row + 0.5) * d), str(i + 1))
        p.setPen(QPen(QColor(200, 0, 0), 2))
        for s in w.alarmed:
            c = self.to_widget(s.x_m, s.y_m)
            p.drawEllipse(c, 7, 7)
        if w.pose is not None:
            self._draw_robot(p, w.pose)
        p.end()

    def _draw_path(self, p: QPainter, w: WallModel, d: float) -> None:
        path = QPainterPath()
        prev = None
        for row, col in w.path:
            pt = self.to_widget((col + 0.5) * d, (row + 0.5) * d)
            if prev is None or abs(col - prev) > 1:  # start, or across the shell's seam
                path.moveTo(pt)
            else:
                path.lineTo(pt)
            prev = col
        p.setPen(QPen(QColor(30, 70, 160, 150), 1))
        p.drawPath(path)

    def _draw_robot(self, p: QPainter, pose) -> None:
        c = self.to_widget(pose.x_m, pose.y_m)
        a = pose.theta_rad
        s = 9.0
        tri = QPolygonF([QPointF(c.x() + s * math.cos(a), c.y() - s * math.sin(a)),
                         QPointF(c.x() + s * math.cos(a + 2.5), c.y() - s * math.sin(a + 2.5)),
                         QPointF(c.x() + s * math.cos(a - 2.5), c.y() - s * math.sin(a - 2.5))])
        p.setPen(QPen(QColor(0, 0, 0), 1))
        p.setBrush(QColor(255, 140, 0))
        p.drawPolygon(tri)


class WallPanel(QWidget):
    command_requested = Signal(str, object)  # command name, args dict

    def __init__(self, model: WallViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.view = WallView(model, self)
        self.coverage_label = QLabel("coverage —")
        self.repetition_label = QLabel("repetition —")
        self.state_label = QLabel("inspection —")
        self.readings_label = QLabel("readings 0")
        self.thinnest_label = QLabel("thinnest —")
        self.thinnest_label.setWordWrap(True)
        self.pose_label = QLabel("pose —")
        self.buttons: dict[str, QPushButton] = {}
        row = QHBoxLayout()
        for name, text in (("start_inspection", "Start"), ("pause_inspection", "Pause"),
                           ("resume_inspection", "Resume"), ("abort_inspection", "Abort")):
            b = QPushButton(text, self)
            b.setToolTip(f"{text} the wall inspection")
            b.clicked.connect(lambda _=False, n=name: self.command_requested.emit(n, {}))
            self.buttons[name] = b
            row.addWidget(b)
        self.checks: dict[str, QCheckBox] = {}
        for name, text in (("heat", "Thickness"), ("covered", "Covered"),
                           ("regions", "Sub-regions"), ("path", "Plan")):
            cb = QCheckBox(text, self)
            cb.setChecked(True)
            cb.toggled.connect(lambda on, n=name: self.view.set_layer(n, on))
            self.checks[name] = cb
            row.addWidget(cb)
        row.addStretch(1)
        figures = QGridLayout()
        for i, lab in enumerate((self.coverage_label, self.repetition_label, self.state_label,
                                 self.readings_label, self.pose_label)):
            figures.addWidget(lab, 0, i)
        lay = QVBoxLayout(self)
        lay.addLayout(row)
        lay.addWidget(self.view, 1)
        lay.addLayout(figures)
        lay.addWidget(self.thinnest_label)
        model.changed.connect(self._show)

    def set_read_only(self, ro: bool) -> None:
        for b in self.buttons.values():
            b.setEnabled(not ro)

    def _show(self, kind: str) -> None:
        w = self.model.wall
        if kind == "pose" and w.pose is not None:
            self.pose_label.setText(f"x {w.pose.x_m:.2f} m · y {w.pose.y_m:.2f} m "
                                    f"· ±{w.pose.sigma_m:.2f} m")
            return
        self.coverage_label.setText(f"coverage {w.coverage_pct:.1f} %")
        self.repetition_label.setText(f"repetition {w.repetition_pct:.1f} %")
        self.state_label.setText(f"inspection {w.state}")
        self.readings_label.setText(f"readings {w.readings}")
        spots = w.thinnest(3)
        if spots:
            lim = w.limit_mm

            def one(s) -> str:
                below = f" (below {lim:g} mm)" if s.thickness_mm < lim else ""
                return f"{s.thickness_mm:.2f} mm{below} at {s.where()}"

            self.thinnest_label.setText("thinnest: " + "; ".join(one(s) for s in spots))


def install_wall_tab(win: Any) -> WallPanel:
    """Add the tank-wall tab to a main window, hidden until a wall climber describes
    its wall; then it is shown and made current, and the patrol robot's camera,
    station-map and meter tabs are hidden (a climber streams no video, has no
    station map and reads no gauges)."""
    model = WallViewModel(win.pipeline, win)
    panel = WallPanel(model, win)
    index = win.views.addTab(panel, "Tank wall")
    win.views.setTabVisible(index, False)

    def on_wall(kind: str) -> None:
        if kind != "info" or win.views.isTabVisible(index):
            return
        win.views.setTabVisible(index, True)
        win.views.setCurrentIndex(index)
        for other in (win.video_panel, win.map_panel, win.meter_panel):
            i = win.views.indexOf(other)
            if i >= 0:
                win.views.setTabVisible(i, False)

    model.changed.connect(on_wall)
    panel.command_requested.connect(lambda n, a: win._intent("send_command", n, a))
    win.wall_model, win.wall_panel = model, panel
    return panel
