"""MapView: a zoomable, pannable 2-D map in world coordinates (metres, y up).

Layers, bottom to top, each set with plain arrays (the view computes nothing):

* an image (a grey grid) placed on a world rectangle — :meth:`set_image`
* named polylines, solid or dashed — :meth:`set_polyline`
* circles with velocity arrows — :meth:`set_circles`
* a point cloud — :meth:`set_points`
* labelled markers, each with a state naming its style — :meth:`set_markers`
* a target mark (a cross) — :meth:`set_target`
* a pose marker (an arrow with a heading) — :meth:`set_pose`

Mouse: the wheel zooms, a left drag pans, a click (press and release without a
drag) emits ``clicked(x, y)`` in world coordinates. In drag mode
(``set_drag_mode``) a left drag does not pan: it emits
``dragged(x0, y0, x1, y1)`` from press to release. ``fit_action`` (Ctrl+0)
frames the image, or everything drawn when there is no image.

Colours follow ISA-101: greys for what is normal, one restrained accent for
"current", red only for what went wrong (marker states "skipped" / "failed").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QEvent, QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QAction, QKeySequence, QPainterPath, QTransform
from PySide6.QtWidgets import QGraphicsItem, QGraphicsPathItem, QVBoxLayout, QWidget

from app.widgets import palette

__all__ = ["MapView", "MarkerStyle", "MARKER_STYLES"]

_GREY_DARK = palette.GREY_DARK
_GREY_MID = palette.GREY_MID
_ACCENT = palette.ACCENT  # "current": the pose, the target
_RED = palette.ALARM_HIGH


@dataclass(frozen=True)
class MarkerStyle:
    fill: str | None  # None: hollow
    edge: str
    size: float = 11.0
    text: str = _GREY_DARK


MARKER_STYLES: dict[str, MarkerStyle] = {
    "pending": MarkerStyle(None, _GREY_MID),
    "done": MarkerStyle(_GREY_MID, _GREY_DARK),
    "current": MarkerStyle(_ACCENT, _ACCENT, 14.0, _ACCENT),
    "skipped": MarkerStyle(_RED, _RED, 11.0, _RED),
    "failed": MarkerStyle(_RED, _RED, 11.0, _RED),
}


def _arrow_path() -> QPainterPath:
    """An arrow pointing along +x, about one unit long, centred on the origin."""
    p = QPainterPath()
    # a plain narrow triangle: a notched back reads as a second arrowhead
    p.moveTo(0.7, 0.0)  # the tip, clearly farthest from the centre
    p.lineTo(-0.3, 0.3)
    p.lineTo(-0.3, -0.3)
    p.closeSubpath()
    return p


def circle_polyline(rows: np.ndarray, segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """x, y of closed circles (x, y, r per row) separated by NaN (one curve for all)."""
    rows = np.asarray(rows, float).reshape(-1, 3)
    t = np.linspace(0.0, 2 * np.pi, segments + 1)
    xs = rows[:, :1] + rows[:, 2:3] * np.cos(t)[None, :]
    ys = rows[:, 1:2] + rows[:, 2:3] * np.sin(t)[None, :]
    nan = np.full((len(rows), 1), np.nan)
    return np.hstack([xs, nan]).ravel(), np.hstack([ys, nan]).ravel()


class MapView(QWidget):
    """A 2-D world-coordinate view over pyqtgraph's ViewBox (aspect locked)."""

    clicked = Signal(float, float)  # world x, y of a left click (not a drag)
    # world x, y of a left press and of its release, while drag_mode is on
    dragged = Signal(float, float, float, float)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.plot = pg.PlotWidget(self)
        self.plot.setMenuEnabled(False)
        self.plot.hideButtons()
        self.plot.showGrid(x=True, y=True, alpha=0.15)
        self.plot.setLabel("bottom", "x", units="m")
        self.plot.setLabel("left", "y", units="m")
        self.vb: pg.ViewBox = self.plot.getViewBox()
        self.vb.setAspectLocked(True, ratio=1.0)
        self.vb.setMouseMode(pg.ViewBox.PanMode)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.plot)

        self.image_item = pg.ImageItem(axisOrder="row-major")
        self.image_item.setZValue(-10)
        self.plot.addItem(self.image_item)
        self._image_rect: QRectF | None = None
        self._lines: dict[str, pg.PlotDataItem] = {}

        self.circle_item = pg.PlotDataItem(pen=pg.mkPen(_GREY_DARK, width=2), connect="finite")
        self.velocity_item = pg.PlotDataItem(pen=pg.mkPen(_GREY_DARK, width=1.5),
                                             connect="finite")
        self.points_item = pg.ScatterPlotItem(size=3, pen=None, brush=pg.mkBrush(_GREY_DARK),
                                              pxMode=True)
        self.marker_item = pg.ScatterPlotItem(pxMode=True, symbol="s")
        self.target_item = pg.ScatterPlotItem(pxMode=True, symbol="x", size=16,
                                              pen=pg.mkPen(_ACCENT, width=2),
                                              brush=pg.mkBrush(_ACCENT))
        # the pose arrow keeps its size in pixels (ItemIgnoresTransformations): it is
        # drawn in screen coordinates, y down, so the heading turns it clockwise
        self.pose_item = QGraphicsPathItem(QTransform().scale(22, 22).map(_arrow_path()))
        self.pose_item.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
        self.pose_item.setPen(pg.mkPen("#101010"))
        self.pose_item.setBrush(pg.mkBrush(_ACCENT))
        self.pose_item.setVisible(False)
        self.pose_stale = False
        for z, it in enumerate((self.circle_item, self.velocity_item, self.points_item,
                                self.marker_item, self.target_item)):
            it.setZValue(10 + z)
            self.plot.addItem(it)
        self.pose_item.setZValue(20)
        self.plot.addItem(self.pose_item, ignoreBounds=True)
        self._labels: list[pg.TextItem] = []
        self.pose: tuple[float, float, float] | None = None
        self.target: tuple[float, float] | None = None
        self.markers: list[tuple[float, float, str, str]] = []

        self.plot.scene().sigMouseClicked.connect(self._on_scene_click)
        # drag mode: a left press-drag-release is reported (dragged), not panned
        self.drag_mode = False
        self._press: tuple[float, float] | None = None
        self.plot.viewport().installEventFilter(self)

        self.fit_action = QAction(self.tr("Fit map"), self)
        self.fit_action.setShortcut(QKeySequence("Ctrl+0"))
        self.fit_action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)  # while shown
        self.fit_action.triggered.connect(self.fit)
        self.addAction(self.fit_action)
        self._fitted_once = False

    # ------------------------------------------------------------ layers
    def set_image(self, image: np.ndarray | None, rect: tuple[float, float, float, float]
                  | None = None, *, levels: tuple[float, float] = (0, 255)) -> None:
        """Show ``image`` (rows x cols, row 0 at the *top*) on the world rectangle
        ``rect`` = (x_min, y_min, width, height). None clears it. The view fits the
        first image it gets."""
        if image is None:
            self.image_item.clear()
            self._image_rect = None
            return
        img = np.flipud(np.asarray(image))  # row-major ImageItem draws row 0 at y_min
        self.image_item.setImage(img, levels=levels, autoLevels=False)
        x, y, w, h = rect if rect is not None else (0.0, 0.0, img.shape[1], img.shape[0])
        self._image_rect = QRectF(x, y, w, h)
        self.image_item.setRect(self._image_rect)
        if not self._fitted_once:
            self._fitted_once = True
            self.fit()

    def image_rect(self) -> tuple[float, float, float, float] | None:
        r = self._image_rect
        return None if r is None else (r.x(), r.y(), r.width(), r.height())

    def set_polyline(self, name: str, xy: np.ndarray | None, *, color: str = _GREY_DARK,
                     width: float = 2.0, dashed: bool = False) -> None:
        """Create or update the polyline ``name`` ((N, 2) world points; None or
        empty hides it)."""
        item = self._lines.get(name)
        if item is None:
            style = Qt.PenStyle.DashLine if dashed else Qt.PenStyle.SolidLine
            item = pg.PlotDataItem(pen=pg.mkPen(color, width=width, style=style))
            item.setZValue(5)
            self.plot.addItem(item)
            self._lines[name] = item
        a = np.zeros((0, 2)) if xy is None else np.asarray(xy, float).reshape(-1, 2)
        item.setData(a[:, 0], a[:, 1])

    def polyline(self, name: str) -> np.ndarray:
        item = self._lines.get(name)
        if item is None or item.xData is None:
            return np.zeros((0, 2))
        return np.column_stack([item.xData, item.yData])

    def set_circles(self, rows: np.ndarray | None, *, arrow_s: float = 1.0) -> None:
        """Circles with velocity arrows: rows of (x, y, vx, vy, radius); each arrow
        shows where the centre would be ``arrow_s`` seconds on."""
        r = np.zeros((0, 5)) if rows is None else np.asarray(rows, float).reshape(-1, 5)
        cx, cy = circle_polyline(r[:, [0, 1, 4]])
        self.circle_item.setData(cx, cy)
        if len(r):
            x0, y0 = r[:, 0], r[:, 1]
            x1, y1 = x0 + r[:, 2] * arrow_s, y0 + r[:, 3] * arrow_s
            # a shaft and a two-stroke head per arrow, NaN between arrows
            ang = np.arctan2(y1 - y0, x1 - x0)
            head = np.minimum(np.hypot(x1 - x0, y1 - y0) * 0.4, 0.3)  # metres
            hx1 = x1 - head * np.cos(ang - 0.5)
            hy1 = y1 - head * np.sin(ang - 0.5)
            hx2 = x1 - head * np.cos(ang + 0.5)
            hy2 = y1 - head * np.sin(ang + 0.5)
            nan = np.full_like(x0, np.nan)
            vx = np.column_stack([x0, x1, hx1, nan, x1, hx2, nan]).ravel()
            vy = np.column_stack([y0, y1, hy1, nan, y1, hy2, nan]).ravel()
            self.velocity_item.setData(vx, vy)
        else:
            self.velocity_item.setData([], [])

    def circles_count(self) -> int:
        x = self.circle_item.xData
        return 0 if x is None else int(np.isnan(x).sum())

    def set_points(self, xy: np.ndarray | None) -> None:
        a = np.zeros((0, 2)) if xy is None else np.asarray(xy, float).reshape(-1, 2)
        self.points_item.setData(x=a[:, 0], y=a[:, 1])

    def points_count(self) -> int:
        return len(self.points_item.data)

    def set_markers(self, markers: list[tuple[float, float, str, str]]) -> None:
        """Labelled markers: (x, y, label, state); state picks a MARKER_STYLES entry
        (unknown states look "pending"). The same markers again draw nothing."""
        if list(markers) == self.markers:
            return
        self.markers = list(markers)
        spots = []
        for x, y, _label, state in self.markers:
            st = MARKER_STYLES.get(state, MARKER_STYLES["pending"])
            spots.append({"pos": (x, y), "size": st.size, "pen": pg.mkPen(st.edge, width=2),
                          "brush": pg.mkBrush(st.fill) if st.fill else pg.mkBrush(0, 0, 0, 0)})
        self.marker_item.setData(spots)
        while len(self._labels) > len(self.markers):
            self.plot.removeItem(self._labels.pop())
        while len(self._labels) < len(self.markers):
            t = pg.TextItem(anchor=(0, 1))
            t.setZValue(14)
            self.plot.addItem(t)
            self._labels.append(t)
        for t, (x, y, label, state) in zip(self._labels, self.markers, strict=True):
            st = MARKER_STYLES.get(state, MARKER_STYLES["pending"])
            t.setText(label, color=st.text)
            t.setPos(x, y)

    def set_target(self, xy: tuple[float, float] | None) -> None:
        self.target = None if xy is None else (float(xy[0]), float(xy[1]))
        if self.target is None:
            self.target_item.setData([], [])
        else:
            self.target_item.setData([self.target[0]], [self.target[1]])

    def set_pose(self, x: float | None, y: float = 0.0, heading_rad: float = 0.0) -> None:
        """Place the arrow at (x, y) pointing at ``heading_rad``; x None hides it."""
        if x is None:
            self.pose = None
            self.pose_item.setVisible(False)
            return
        self.pose = (float(x), float(y), float(heading_rad))
        self.pose_item.setPos(float(x), float(y))
        self.pose_item.setRotation(-math.degrees(heading_rad))
        self.pose_item.setVisible(True)

    def set_pose_stale(self, stale: bool) -> None:
        """A pose no longer current: the arrow hollow, with a dashed grey outline."""
        if stale == self.pose_stale:
            return
        self.pose_stale = stale
        if stale:
            self.pose_item.setPen(pg.mkPen("#6a6a6a", width=1.5, style=Qt.PenStyle.DashLine))
            self.pose_item.setBrush(pg.mkBrush(None))
        else:
            self.pose_item.setPen(pg.mkPen("#101010"))
            self.pose_item.setBrush(pg.mkBrush(_ACCENT))

    # ------------------------------------------------------------ view
    def fit(self) -> None:
        """Frame the image (or everything drawn when there is none)."""
        if self._image_rect is not None:
            self.vb.setRange(rect=self._image_rect, padding=0.02)
        else:
            self.vb.autoRange(padding=0.05)

    def view_rect(self) -> tuple[float, float, float, float]:
        r = self.vb.viewRect()
        return (r.x(), r.y(), r.width(), r.height())

    def map_to_widget(self, x: float, y: float) -> QPointF:
        """Widget (viewport) pixel position of world point (x, y) — for tests and
        tooltips."""
        scene = self.vb.mapViewToScene(QPointF(x, y))
        return QPointF(self.plot.mapFromScene(scene))

    def set_drag_mode(self, on: bool) -> None:
        self.drag_mode = bool(on)
        self._press = None

    def _world_at(self, pos) -> tuple[float, float]:
        p = self.vb.mapSceneToView(self.plot.mapToScene(pos.toPoint()))
        return float(p.x()), float(p.y())

    def eventFilter(self, obj, ev) -> bool:  # noqa: N802 - Qt's name
        if not self.drag_mode or ev.type() not in (QEvent.Type.MouseButtonPress,
                                                   QEvent.Type.MouseButtonRelease):
            return super().eventFilter(obj, ev)
        if ev.button() != Qt.MouseButton.LeftButton:
            return False
        if ev.type() == QEvent.Type.MouseButtonPress:
            self._press = self._world_at(ev.position())
            return True
        if self._press is not None:
            x0, y0 = self._press
            self._press = None
            self.dragged.emit(x0, y0, *self._world_at(ev.position()))
        return True

    def _on_scene_click(self, ev) -> None:
        if ev.button() != Qt.MouseButton.LeftButton or ev.double():
            return
        if not self.vb.sceneBoundingRect().contains(ev.scenePos()):
            return  # on an axis
        p = self.vb.mapSceneToView(ev.scenePos())
        ev.accept()
        self.clicked.emit(float(p.x()), float(p.y()))
