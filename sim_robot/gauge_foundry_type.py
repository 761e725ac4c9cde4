"""The ``foundry`` gauge family's printing: its own typeface, and ink laid down as a mask.

Qt-free: numpy + OpenCV only.  The typeface, "grotesk", is a skeleton font drawn with an
elliptical pen: every glyph is a few strokes (straight runs and elliptical arcs) in a box
one unit high (y down, the baseline at 1, lower-case x-height at 0.42), and each stroke is
swept by an ellipse wider than it is tall, so that upright strokes print heavier than
horizontal ones, as on printed dials.  Nothing here uses OpenCV's Hershey fonts.

Print goes onto a :class:`Ink` mask (0..1, one per colour) and is laid on the face at
once by :meth:`Ink.lay`, with a slight spread of the ink into the paper.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .gauge_draw import SC, SH, p

__all__ = ["Ink", "rule", "text_width", "typeset"]


def _arc(cx, cy, rx, ry, t0, t1, step=12.0) -> list[tuple[float, float]]:
    """Points of an elliptical arc, ``t`` in degrees (y down: increasing t turns clockwise)."""
    n = max(2, int(abs(t1 - t0) / step) + 1)
    return [(cx + rx * math.cos(math.radians(t)), cy + ry * math.sin(math.radians(t)))
            for t in np.linspace(t0, t1, n)]


def _map(strokes, fx) -> list[list[tuple[float, float]]]:
    return [[fx(x, y) for x, y in s] for s in strokes]


_G: dict[str, list[list[tuple[float, float]]]] = {
    "0": [_arc(0.28, 0.5, 0.26, 0.5, 0, 360)],
    "1": [[(0.08, 0.2), (0.32, 0.0), (0.32, 1.0)]],
    "2": [_arc(0.28, 0.27, 0.26, 0.27, 195, 385) + [(0.02, 1.0), (0.56, 1.0)]],
    "3": [_arc(0.27, 0.25, 0.24, 0.25, 200, 450), _arc(0.28, 0.74, 0.27, 0.26, -90, 160)],
    "4": [[(0.42, 1.0), (0.42, 0.0), (0.0, 0.7), (0.58, 0.7)]],
    "5": [[(0.52, 0.0), (0.1, 0.0), (0.06, 0.45)] + _arc(0.28, 0.68, 0.27, 0.32, 235, 520)],
    "6": [_arc(0.3, 0.56, 0.27, 0.56, -55, -180) + [(0.03, 0.7)],
          _arc(0.29, 0.71, 0.26, 0.29, 0, 360)],
    "7": [[(0.0, 0.0), (0.56, 0.0), (0.2, 1.0)]],
    "8": [_arc(0.28, 0.25, 0.22, 0.25, 0, 360), _arc(0.28, 0.74, 0.27, 0.26, 0, 360)],
    "-": [[(0.08, 0.58), (0.44, 0.58)]],
    ".": [[(0.08, 0.96), (0.08, 0.96)]],
    "/": [[(0.0, 1.0), (0.38, 0.0)]],
    " ": [],
    "A": [[(0.0, 1.0), (0.3, 0.0), (0.6, 1.0)], [(0.1, 0.67), (0.5, 0.67)]],
    "B": [[(0.05, 0.5), (0.05, 0.0), (0.33, 0.0)] + _arc(0.33, 0.25, 0.22, 0.25, -90, 90)
          + [(0.05, 0.5), (0.36, 0.5)] + _arc(0.36, 0.75, 0.24, 0.25, -90, 90)
          + [(0.05, 1.0), (0.05, 0.5)]],
    "C": [_arc(0.31, 0.5, 0.29, 0.5, -40, -320)],
    "D": [[(0.05, 0.0), (0.05, 1.0), (0.24, 1.0)] + _arc(0.24, 0.5, 0.32, 0.5, 90, -90)
          + [(0.05, 0.0)]],
    "E": [[(0.52, 0.0), (0.05, 0.0), (0.05, 1.0), (0.52, 1.0)], [(0.05, 0.5), (0.42, 0.5)]],
    "G": [_arc(0.31, 0.5, 0.29, 0.5, -40, -335) + [(0.6, 0.56), (0.36, 0.56)]],
    "H": [[(0.05, 0.0), (0.05, 1.0)], [(0.55, 0.0), (0.55, 1.0)], [(0.05, 0.5), (0.55, 0.5)]],
    "I": [[(0.08, 0.0), (0.08, 1.0)]],
    "K": [[(0.05, 0.0), (0.05, 1.0)], [(0.55, 0.0), (0.05, 0.62)], [(0.22, 0.44), (0.58, 1.0)]],
    "L": [[(0.05, 0.0), (0.05, 1.0), (0.5, 1.0)]],
    "M": [[(0.05, 1.0), (0.05, 0.0), (0.36, 0.72), (0.67, 0.0), (0.67, 1.0)]],
    "N": [[(0.05, 1.0), (0.05, 0.0), (0.55, 1.0), (0.55, 0.0)]],
    "O": [_arc(0.32, 0.5, 0.3, 0.5, 0, 360)],
    "P": [[(0.05, 1.0), (0.05, 0.0), (0.32, 0.0)] + _arc(0.32, 0.26, 0.24, 0.26, -90, 90)
          + [(0.05, 0.52)]],
    "R": [[(0.05, 1.0), (0.05, 0.0), (0.32, 0.0)] + _arc(0.32, 0.26, 0.24, 0.26, -90, 90)
          + [(0.05, 0.52)], [(0.3, 0.52), (0.58, 1.0)]],
    "S": [_arc(0.29, 0.26, 0.25, 0.26, -25, -270) + _arc(0.31, 0.75, 0.27, 0.25, -90, 160)],
    "T": [[(0.0, 0.0), (0.6, 0.0)], [(0.3, 0.0), (0.3, 1.0)]],
    "U": [[(0.05, 0.0), (0.05, 0.68)] + _arc(0.3, 0.68, 0.25, 0.32, 180, 0) + [(0.55, 0.0)]],
    "V": [[(0.0, 0.0), (0.3, 1.0), (0.6, 0.0)]],
    "W": [[(0.0, 0.0), (0.2, 1.0), (0.4, 0.3), (0.6, 1.0), (0.8, 0.0)]],
    "Y": [[(0.0, 0.0), (0.3, 0.5), (0.6, 0.0)], [(0.3, 0.5), (0.3, 1.0)]],
    "a": [_arc(0.25, 0.72, 0.21, 0.28, 0, 360), [(0.46, 0.42), (0.46, 1.0)]],
    "b": [[(0.05, 0.0), (0.05, 1.0)], _arc(0.27, 0.72, 0.21, 0.28, 0, 360)],
    "c": [_arc(0.26, 0.72, 0.22, 0.28, -40, -320)],
    "f": [_arc(0.3, 0.13, 0.13, 0.12, -20, -180) + [(0.17, 1.0)], [(0.02, 0.45), (0.34, 0.45)]],
    "g": [_arc(0.25, 0.7, 0.21, 0.27, 0, 360), [(0.46, 0.42), (0.46, 1.08)]
          + _arc(0.25, 1.08, 0.21, 0.16, 0, 160)],
    "i": [[(0.08, 0.42), (0.08, 1.0)], [(0.08, 0.2), (0.08, 0.2)]],
    "k": [[(0.05, 0.0), (0.05, 1.0)], [(0.42, 0.42), (0.05, 0.8)], [(0.17, 0.68), (0.45, 1.0)]],
    "l": [[(0.08, 0.0), (0.08, 1.0)]],
    "m": [[(0.05, 0.42), (0.05, 1.0)], _arc(0.19, 0.62, 0.14, 0.18, 180, 360) + [(0.33, 1.0)],
          _arc(0.47, 0.62, 0.14, 0.18, 180, 360) + [(0.61, 1.0)]],
    "n": [[(0.05, 0.42), (0.05, 1.0)], _arc(0.26, 0.63, 0.21, 0.2, 180, 360) + [(0.47, 1.0)]],
    "p": [[(0.05, 0.42), (0.05, 1.25)], _arc(0.27, 0.71, 0.21, 0.29, 0, 360)],
    "r": [[(0.05, 0.42), (0.05, 1.0)], _arc(0.25, 0.63, 0.2, 0.2, 180, 300)],
    "s": [],
    "t": [[(0.15, 0.18), (0.15, 0.9)] + _arc(0.28, 0.9, 0.13, 0.1, 180, 60),
          [(0.02, 0.45), (0.34, 0.45)]],
}
_G["9"] = _map(_G["6"], lambda x, y: (0.58 - x, 1.0 - y))
_G["s"] = _map(_G["S"], lambda x, y: (0.78 * x, 0.42 + 0.58 * y))
_G["\u00b2"] = _map(_G["2"], lambda x, y: (0.05 + 0.5 * x, 0.45 * y))  # superscript two
_FALLBACK = [[(0.05, 0.0), (0.5, 0.0), (0.5, 1.0), (0.05, 1.0), (0.05, 0.0)]]
_DIGIT_ADVANCE = 0.74  # tabular figures
_GAP = 0.2


def _advance(ch: str) -> float:
    if ch.isdigit():
        return _DIGIT_ADVANCE
    if ch == " ":
        return 0.38
    xs = [x for s in _G.get(ch, _FALLBACK) for x, _ in s]
    return (max(xs) if xs else 0.2) + _GAP


def text_width(txt: str, height_px: float) -> float:
    """The printed width of ``txt`` at cap height ``height_px`` (pixels)."""
    return max(0.0, sum(_advance(ch) for ch in txt) - _GAP) * height_px


def _nib(weight: float) -> np.ndarray:
    """The pen: an ellipse of full width ``weight`` and 0.7 of that height (glyph units)."""
    t = np.linspace(0, 2 * np.pi, 10, endpoint=False)
    return np.stack([0.5 * weight * np.cos(t), 0.35 * weight * np.sin(t)], axis=1)


class Ink:
    """One colour of print on a square face of ``size`` pixels: a coverage mask."""

    def __init__(self, size: int, colour: tuple[int, int, int]):
        self.colour = colour
        self.mask = np.zeros((size, size), np.uint8)

    def poly(self, pts) -> None:
        """Fill a polygon given in image pixels (floats)."""
        q = np.round(np.asarray(pts, np.float64) * SC).astype(np.int32)
        cv2.fillPoly(self.mask, [q], 255, cv2.LINE_AA, SH)

    def disc(self, c: tuple[float, float], r: float) -> None:
        cv2.circle(self.mask, p(*c), int(r * SC), 255, -1, cv2.LINE_AA, SH)

    def circle_arc(self, c: tuple[float, float], r: float, a0: float, a1: float,
                   width: float) -> None:
        """An arc of a circle about ``c``, dial angles (clockwise from 12 o'clock)."""
        lo, hi = sorted((a0, a1))
        qs = np.linspace(lo, hi, max(3, int((hi - lo) / 2) + 2))
        outer = [(c[0] + (r + width / 2) * math.sin(math.radians(q)),
                  c[1] - (r + width / 2) * math.cos(math.radians(q))) for q in qs]
        inner = [(c[0] + (r - width / 2) * math.sin(math.radians(q)),
                  c[1] - (r - width / 2) * math.cos(math.radians(q))) for q in qs[::-1]]
        self.poly(outer + inner)

    def lay(self, face: np.ndarray, density: float = 0.95, spread_px: float = 0.35) -> None:
        """Print the mask onto ``face`` (float32 BGR, in place): the ink soaks in a little."""
        a = self.mask.astype(np.float32) / 255.0
        if spread_px > 0:
            a = np.maximum(a, cv2.GaussianBlur(a, (0, 0), spread_px))
        a = (a * density)[..., None]
        face *= 1 - a
        face += a * np.array(self.colour, np.float32)


def typeset(ink: Ink, txt: str, x: float, y: float, height_px: float, weight: float = 0.13,
            angle_deg: float = 0.0) -> None:
    """``txt`` centred on ``(x, y)`` at cap height ``height_px``, turned ``angle_deg``
    clockwise; ``weight`` is the pen's width as a fraction of the cap height."""
    ca, sa = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    u = -text_width(txt, 1.0) / 2
    nib = _nib(weight)
    for ch in txt:
        for stroke in _G.get(ch, _FALLBACK):
            pts = np.array(stroke, np.float64) + [u, -0.5]
            for a, b in zip(pts, pts[1:] if len(pts) > 1 else pts, strict=False):
                hull = cv2.convexHull(np.vstack([nib + a, nib + b]).astype(np.float32))[:, 0]
                gx, gy = hull[:, 0] * height_px, hull[:, 1] * height_px
                ink.poly(np.stack([x + gx * ca - gy * sa, y + gx * sa + gy * ca], axis=1))
        u += _advance(ch)


def rule(ink: Ink, a, b, width: float) -> None:
    """A printed straight rule of ``width`` pixels from ``a`` to ``b``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    n = max(math.hypot(dx, dy), 1e-6)
    nx, ny = -dy / n * width / 2, dx / n * width / 2
    ink.poly([(a[0] + nx, a[1] + ny), (b[0] + nx, b[1] + ny), (b[0] - nx, b[1] - ny),
              (a[0] - nx, a[1] - ny)])
