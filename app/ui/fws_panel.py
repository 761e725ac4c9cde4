"""The four-wheel-steer robot on the desk: the wheel display in the control
panel's row (the chassis from above, front up, each wheel turned by its steering
angle with its speed as an arrow, the figures in a list below, and the steering
mode) and the
TEB local plan on the map.

Thin views over :class:`app.core.desk.fws.FwsModel` (the pipeline's, no Qt):
they draw what :meth:`~FwsModel.wheels_view` and :meth:`~FwsModel.teb_view`
give for the freshness the window's :class:`~app.ui.freshness_model.FreshnessModel`
judges (sources ``wheels`` and ``teb``). Stale (link lost, or the robot quiet):
the wheels are drawn grey and hatched with "last known HH:MM:SS, N s ago", the
TEB plan grey and dashed; a stale value is never drawn as live. Both stay
hidden until a 4WS robot reports its wheels.
"""

from __future__ import annotations

import math
from datetime import datetime
from typing import Any

from PySide6.QtCore import QObject, QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QGroupBox, QSizePolicy, QSplitter, QVBoxLayout, QWidget

from app.core.desk.fws import FwsModel, WheelsView
from app.core.freshness import Age, Freshness
from app.core.i18n import translate
from app.widgets.stale import HATCH_COLOR, paint_hatch

__all__ = ["FwsViewModel", "WheelDisplay", "install_fws_view"]

LIVE_COLOR = "#2b2b2b"
ARROW_COLOR = "#1f6fb2"
STALE_COLOR = "#9a9a9a"
TEB_COLOR = "#c2185b"
FULL_SPEED_MPS = 1.0  # an arrow's length for this speed: half the wheelbase


def _arg(text: str, *values: Any) -> str:
    """Qt's placeholders %1, %2, … (a translation may reorder them) filled in."""
    for i, v in reversed(list(enumerate(values, 1))):
        text = text.replace(f"%{i}", str(v))
    return text


class FwsViewModel(QObject):
    """The pipeline's 4WS model with a signal per message (``changed(kind)``,
    kind "wheels" or "teb")."""

    changed = Signal(str)

    def __init__(self, pipeline: Any = None, parent: QObject | None = None) -> None:
        super().__init__(parent)
        if pipeline is None:
            from app.core.desk import DeskPipeline
            pipeline = DeskPipeline()
        self.pipeline = pipeline
        pipeline.listen("fws", self.changed.emit)

    @property
    def fws(self) -> FwsModel:
        return self.pipeline.fws


class WheelDisplay(QWidget):
    """The four wheels. ``show_freshness(f)`` sets how current the last state is;
    the view redraws on every new state and every change of freshness."""

    def __init__(self, model: FwsViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.freshness = Freshness(Age.NONE)
        self.view: WheelsView = model.fws.wheels_view(self.freshness)
        self.setMinimumSize(140, 150)
        self.setSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Expanding)
        self.setToolTip(self.tr("The four wheels as the robot last reported them: steering "
                                "angle (anticlockwise positive) and rolling speed"))
        model.changed.connect(self._on_changed)

    def _on_changed(self, kind: str) -> None:
        if kind == "wheels":
            if self.freshness.age is Age.NONE:  # the first state: live until judged
                self.freshness = Freshness(Age.LIVE, 0.0)
            self._refresh()

    def show_freshness(self, f: Freshness) -> None:
        self.freshness = f
        self._refresh()

    def _refresh(self) -> None:
        self.view = self.model.fws.wheels_view(self.freshness)
        self.update()

    # ---- texts (translatable) ---------------------------------------------------------
    def mode_text(self) -> str:
        names = {"stopped": self.tr("stopped"), "front": self.tr("front steer"),
                 "counter": self.tr("counter-phase"), "crab": self.tr("crab"),
                 "pivot": self.tr("turn in place")}
        if not self.view.shown:
            return self.tr("no wheel data")
        return _arg(self.tr("mode: %1"), names.get(self.view.mode, self.view.mode))

    def stale_text(self) -> str:
        """"" while live; else "last known HH:MM:SS, N s ago"."""
        f = self.freshness
        if not (self.view.stale and f.received_utc_s is not None and f.age_s is not None):
            return ""
        s = int(max(0.0, f.age_s))
        if s < 60:
            ago = _arg(self.tr("%1 s ago"), s)
        elif s < 3600:
            ago = _arg(self.tr("%1 min ago"), s // 60)
        else:
            ago = _arg(self.tr("%1 h %2 min ago"), s // 3600, s % 3600 // 60)
        hms = datetime.fromtimestamp(f.received_utc_s).strftime("%H:%M:%S")
        return _arg(self.tr("last known %1, %2"), hms, ago)

    def wheel_short(self, i: int) -> str:
        return (self.tr("FL"), self.tr("FR"), self.tr("RL"), self.tr("RR"))[i]

    def wheel_text(self, i: int) -> str:
        w = self.view.wheels[i]
        return _arg(self.tr("%1° · %2 m/s"), f"{w.angle_deg:+.0f}", f"{w.speed_mps:+.2f}")

    # ---- painting -----------------------------------------------------------------
    def paintEvent(self, _ev) -> None:  # noqa: N802 - Qt's name
        v = self.view
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        ink = QColor(STALE_COLOR if v.stale else LIVE_COLOR)
        p.setPen(ink)
        fm = p.fontMetrics()
        line = fm.height()
        p.drawText(QRectF(0, 0, self.width(), line), Qt.AlignmentFlag.AlignHCenter,
                   self.mode_text())
        if not v.shown:
            p.end()
            return
        if v.stale:  # the age right under the mode, where it cannot be cut off
            p.setPen(QColor(LIVE_COLOR))
            p.drawText(QRectF(0, line, self.width(), line), Qt.AlignmentFlag.AlignHCenter,
                       self.stale_text())
            p.setPen(ink)
        top, bottom = (2 * line if v.stale else line) + 4, self.height() - 4
        # the four wheels' figures in a list under the chassis (a narrow panel too)
        bottom -= 4 * line + 4
        scale = max(8.0, min((bottom - top) / 2.9, self.width() / 2.6))
        cx, cy = self.width() / 2, (top + bottom) / 2

        def at(x: float, y: float) -> QPointF:  # chassis frame (forward up) -> widget
            return QPointF(cx - y * scale, cy - x * scale)

        p.setPen(QPen(ink, 1.5, Qt.PenStyle.DashLine if v.stale else Qt.PenStyle.SolidLine))
        p.setBrush(Qt.BrushStyle.NoBrush)
        p.drawRect(QRectF(at(1.0, 0.9), at(-1.0, -0.9)).normalized())
        p.drawLine(at(1.15, 0.0), at(0.85, 0.0))  # the front
        arrow = QColor(STALE_COLOR if v.stale else ARROW_COLOR)
        for i, w in enumerate(v.wheels):
            c = at(w.x, w.y)
            p.save()
            p.translate(c)
            p.rotate(-w.angle_deg)  # anticlockwise on the map = anticlockwise on screen
            p.setPen(QPen(ink, 1.2))
            p.setBrush(QColor("#d0d0d0" if v.stale else "#5a5a5a"))
            p.drawRoundedRect(QRectF(-0.12 * scale, -0.3 * scale, 0.24 * scale, 0.6 * scale),
                              3, 3)
            length = max(-1.0, min(1.0, w.speed_mps / FULL_SPEED_MPS)) * scale
            if abs(length) > 1.0:
                p.setPen(QPen(arrow, 2.5))
                p.drawLine(QPointF(0, 0), QPointF(0, -length))
                tip, s = QPointF(0, -length), math.copysign(6.0, length)
                p.drawLine(tip, QPointF(-4, -length + s))
                p.drawLine(tip, QPointF(4, -length + s))
            p.restore()
            p.setPen(ink)
            p.drawText(QRectF(c.x() + (0.15 if w.y > 0 else -0.6) * scale,
                              c.y() - line / 2, 0.45 * scale, line),
                       Qt.AlignmentFlag.AlignCenter, self.wheel_short(i))
        for i in range(len(v.wheels)):
            p.drawText(QRectF(2, bottom + 4 + i * line, self.width() - 4, line),
                       Qt.AlignmentFlag.AlignHCenter,
                       f"{self.wheel_short(i)}  {self.wheel_text(i)}")
        p.end()
        if v.stale:
            paint_hatch(self, HATCH_COLOR)


def install_fws_view(win: Any) -> WheelDisplay:
    """The wheel display beside the control panel and the TEB plan on the map of a
    main window; both hidden until a 4WS robot reports its wheels."""
    model = FwsViewModel(win.pipeline, win)
    display = WheelDisplay(model)
    # beside the control panel, in the bottom row (below it the window would grow taller)
    box = QGroupBox(translate("WheelDisplay", "Wheels"))
    lay = QVBoxLayout(box)
    lay.setContentsMargins(4, 8, 4, 4)
    lay.addWidget(display)
    control_box = win.control_panel.parentWidget()
    row = control_box.parentWidget() if control_box is not None else None
    if isinstance(row, QSplitter):
        row.insertWidget(row.indexOf(control_box) + 1, box)
    else:  # a window laid out otherwise: under the control panel
        win.control_panel.layout().addWidget(box)
    box.setVisible(False)
    fresh = win.freshness
    mv = win.map_panel.view

    def draw_teb() -> None:
        tv = model.fws.teb_view(fresh.freshness("teb"))
        live = None if tv is None or tv.stale else tv.xy
        mv.set_polyline("teb", live, color=TEB_COLOR, width=2.5)
        mv.set_polyline("teb_stale", None if tv is None or not tv.stale else tv.xy,
                        color=STALE_COLOR, width=2.0, dashed=True)

    def on_fws(kind: str) -> None:
        fresh.note(kind)
        if kind == "wheels" and not box.isVisible():
            box.setVisible(True)
        if kind == "teb":
            draw_teb()

    def on_freshness(_snap: dict) -> None:
        display.show_freshness(fresh.freshness("wheels"))
        draw_teb()

    model.changed.connect(on_fws)
    fresh.changed.connect(on_freshness)
    win.fws_model, win.wheel_display = model, display
    return display
