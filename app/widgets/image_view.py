"""ImageView: paints a numpy RGB (or grey) image scaled to fit, keeping its aspect,
with optional overlays given as plain data in image pixel coordinates.

The image is kept as a 32-bit QImage (``Format_RGB32``), converted once when it
is set: Qt's smooth scaling works on 32-bit pixels, so a 24-bit RGB image would be
converted again on every paint, which costs more than the scaling itself (a
640 x 480 camera frame drawn at 750 x 560: about 2.3 ms per paint from RGB888,
0.9 ms from RGB32, 0.06 ms for the one conversion; bench/paint_cost.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QFont, QImage, QPainter, QPen
from PySide6.QtWidgets import QSizePolicy, QWidget

__all__ = ["ImageView", "OverlayText", "OverlayRect", "OverlayLine"]


@dataclass(frozen=True)
class OverlayText:
    x: float
    y: float
    text: str
    color: str = "#ffffff"


@dataclass(frozen=True)
class OverlayRect:
    x: float
    y: float
    w: float
    h: float
    color: str = "#ffd200"
    label: str = ""


@dataclass(frozen=True)
class OverlayLine:
    x0: float
    y0: float
    x1: float
    y1: float
    color: str = "#ffd200"


Overlay = OverlayText | OverlayRect | OverlayLine


def to_paint_image(image: np.ndarray) -> QImage:
    """``image`` (as :func:`to_qimage` takes it) as a QImage of its own in the format
    the painter scales fastest (``Format_RGB32``)."""
    q, _keep = to_qimage(image)
    return q.convertToFormat(QImage.Format.Format_RGB32)


def to_qimage(image: np.ndarray) -> tuple[QImage, np.ndarray]:
    """Wrap an HxWx3 uint8 RGB or HxW uint8 grey array as a QImage (no copy).
    Returns the image and the array it points into (keep both alive)."""
    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise ValueError(f"image must be uint8, got {a.dtype}")
    if a.ndim == 3 and a.shape[2] == 3:
        fmt = QImage.Format.Format_RGB888
    elif a.ndim == 2:
        fmt = QImage.Format.Format_Grayscale8
    else:
        raise ValueError(f"image must be HxWx3 RGB or HxW grey, got shape {a.shape}")
    h, w = a.shape[:2]
    if h == 0 or w == 0:
        raise ValueError("image is empty")
    a = np.ascontiguousarray(a)
    return QImage(a.data, w, h, a.strides[0], fmt), a


class ImageView(QWidget):
    def __init__(self, parent: QWidget | None = None, *, placeholder: str = "no image",
                 background: str = "#1e1e1e") -> None:
        super().__init__(parent)
        self._qimage: QImage | None = None  # RGB32, owning its pixels (to_paint_image)
        self._overlays: list[Overlay] = []
        self._caption = ""
        self._placeholder = placeholder
        self._background = QColor(background)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setMinimumSize(160, 120)
        # every paint fills the whole widget: nothing beneath it needs painting first
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.images_shown = 0

    def set_image(self, image: np.ndarray | None) -> None:
        """Show ``image``; raises ValueError for anything but uint8 RGB/grey."""
        if image is None:
            self._qimage = None
        else:
            self._qimage = to_paint_image(image)
            self.images_shown += 1
        self.update()

    def image_size(self) -> tuple[int, int] | None:
        if self._qimage is None:
            return None
        return self._qimage.width(), self._qimage.height()

    def set_overlays(self, overlays: list[Overlay]) -> None:
        self._overlays = list(overlays)
        self.update()

    def set_caption(self, text: str) -> None:
        """A line of text in the top-left corner (in widget coordinates)."""
        self._caption = text
        self.update()

    def caption(self) -> str:
        return self._caption

    def set_placeholder(self, text: str) -> None:
        self._placeholder = text
        self.update()

    def target_rect(self) -> QRectF:
        """Where the image is painted: scaled to fit, aspect kept, centred."""
        if self._qimage is None:
            return QRectF()
        iw, ih = self._qimage.width(), self._qimage.height()
        s = min(self.width() / iw, self.height() / ih)
        w, h = iw * s, ih * s
        return QRectF((self.width() - w) / 2, (self.height() - h) / 2, w, h)

    def paintEvent(self, _event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        p.fillRect(self.rect(), self._background)
        if self._qimage is None:
            p.setPen(QColor("#b0b0b0"))
            p.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter, self._placeholder)
        else:
            p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
            target = self.target_rect()
            p.drawImage(target, self._qimage)
            self._paint_overlays(p, target)
        if self._caption:
            f = QFont(p.font())
            f.setBold(True)
            p.setFont(f)
            box = QRectF(6, 6, self.width() - 12, 22)
            p.fillRect(QRectF(4, 4, p.fontMetrics().horizontalAdvance(self._caption) + 8, 22),
                       QColor(0, 0, 0, 150))
            p.setPen(QColor("#ffffff"))
            p.drawText(box, Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
                       self._caption)
        p.end()

    def _paint_overlays(self, p: QPainter, target: QRectF) -> None:
        if not self._overlays or self._qimage is None:
            return
        sx = target.width() / self._qimage.width()
        sy = target.height() / self._qimage.height()

        def pt(x: float, y: float) -> QPointF:
            return QPointF(target.x() + x * sx, target.y() + y * sy)

        for ov in self._overlays:
            p.setPen(QPen(QColor(ov.color), 2))
            p.setBrush(Qt.BrushStyle.NoBrush)
            if isinstance(ov, OverlayRect):
                r = QRectF(pt(ov.x, ov.y), pt(ov.x + ov.w, ov.y + ov.h))
                p.drawRect(r)
                if ov.label:
                    p.drawText(r.topLeft() + QPointF(2, -4), ov.label)
            elif isinstance(ov, OverlayLine):
                p.drawLine(pt(ov.x0, ov.y0), pt(ov.x1, ov.y1))
            elif isinstance(ov, OverlayText):
                p.drawText(pt(ov.x, ov.y), ov.text)
