"""Gauges drawn directly with OpenCV for the calibrated-reading tests: what real gauges
have and the project's renderer does not draw (two-ended needles, arrow tails, a stop pin,
anticlockwise scales, a red set-point pointer, glare, printed text)."""

from __future__ import annotations

import math

import cv2
import numpy as np

SIZE = 320
C = SIZE / 2.0
R_TICK = 120.0  # the end marks' distance from the pivot


def _dir(a: float) -> tuple[float, float]:
    r = math.radians(a)
    return math.sin(r), -math.cos(r)


def _pt(x: float, y: float) -> tuple[int, int]:
    return int(round(x * 16)), int(round(y * 16))


def end_mark(angle: float, r: float = R_TICK) -> tuple[float, float]:
    dx, dy = _dir(angle)
    return C + r * dx, C + r * dy


def draw_face(a_min: float, span: float, clockwise: bool = True, *, face=(236, 238, 240),
              ink=(30, 30, 30), n_ticks: int = 41, text: bool = True) -> np.ndarray:
    """A dial face (no needle) with its scale from ``a_min`` over ``span`` degrees."""
    img = np.full((SIZE, SIZE, 3), 90, np.uint8)
    cv2.circle(img, _pt(C, C), int(152 * 16), (60, 60, 60), -1, cv2.LINE_AA, 4)
    cv2.circle(img, _pt(C, C), int(145 * 16), face, -1, cv2.LINE_AA, 4)
    sign = 1.0 if clockwise else -1.0
    for k in range(n_ticks):
        a = a_min + sign * span * k / (n_ticks - 1)
        major = k % 5 == 0
        dx, dy = _dir(a)
        r0 = R_TICK - (14 if major else 7)
        cv2.line(img, _pt(C + r0 * dx, C + r0 * dy), _pt(C + (R_TICK + 6) * dx,
                 C + (R_TICK + 6) * dy), ink, 3 if major else 1, cv2.LINE_AA, 4)
        if major and text:
            tx, ty = C + 88 * dx, C + 88 * dy
            cv2.putText(img, str(k // 5 * 10), (int(tx - 9), int(ty + 5)),
                        cv2.FONT_HERSHEY_SIMPLEX, 0.45, ink, 1, cv2.LINE_AA)
    if text:  # a maker's logo and unit text, which are not radial lines through the pivot
        cv2.putText(img, "ACME", (int(C - 30), int(C - 40)), cv2.FONT_HERSHEY_DUPLEX, 0.8, ink,
                    2, cv2.LINE_AA)
        cv2.putText(img, "kPa  CL1.6", (int(C - 42), int(C + 55)), cv2.FONT_HERSHEY_SIMPLEX,
                    0.5, ink, 1, cv2.LINE_AA)
    return img


def draw_needle(img: np.ndarray, angle: float, *, colour=(25, 25, 25), length: float = 112,
                width: float = 5.0, tail: float = 22.0, tail_width: float | None = None,
                style: str = "needle", hub: float = 11.0) -> np.ndarray:
    """A needle at image angle ``angle`` (clockwise from up) turning about the centre.

    ``style``: "needle" (tapered, short tail), "two-ended" (the tail is ``tail`` long and
    ``tail_width`` wide), "arrow-tail" (a wide arrow-shaped counterweight)."""
    dx, dy = _dir(angle)
    nx, ny = -dy, dx
    tw = width * 1.2 if tail_width is None else tail_width

    def P(s, t):
        return _pt(C + dx * s + nx * t, C + dy * s + ny * t)

    w = width / 2
    if style == "arrow-tail":
        poly = [P(0, -w), P(length, -0.4), P(length, 0.4), P(0, w), P(-tail + 14, w),
                P(-tail + 14, tw / 2), P(-tail, 0), P(-tail + 14, -tw / 2), P(-tail + 14, -w)]
    else:
        poly = [P(0, -w), P(length, -0.4), P(length, 0.4), P(0, w), P(-tail, tw / 2),
                P(-tail, -tw / 2)]
    cv2.fillPoly(img, [np.array(poly, np.int32)], colour, cv2.LINE_AA, 4)
    cv2.circle(img, _pt(C, C), int(hub * 16), colour, -1, cv2.LINE_AA, 4)
    return img


def add_glare(img: np.ndarray, centre, sx: float, sy: float, strength: float) -> np.ndarray:
    """A white veil on the glass: I = I0 (1 - a) + 255 a with a Gaussian opacity a."""
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]].astype(np.float32)
    a = strength * np.exp(-0.5 * (((xx - centre[0]) / sx) ** 2 + ((yy - centre[1]) / sy) ** 2))
    out = img.astype(np.float32) * (1 - a[..., None]) + 255.0 * a[..., None]
    return np.clip(out, 0, 255).astype(np.uint8)


def base_profile(**kw) -> dict:
    d = {"name": "drawn", "unit": "kPa", "min_value": 0.0, "max_value": 80.0}
    d.update(kw)
    return d


def calibration(a_min: float, a_max: float, clockwise: bool = True, **kw) -> dict:
    return {"center": [C, C], "min_point": list(end_mark(a_min)),
            "max_point": list(end_mark(a_max)), "clockwise": clockwise, **kw}
