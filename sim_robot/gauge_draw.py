"""Drawing helpers shared by the gauge renderers (stock, styled and the atlas family).

cv2 draws with sub-pixel precision when given integer points scaled by ``2**SH`` and
``shift=SH``; :func:`p` makes such a point.  Angles are in degrees, clockwise from 12
o'clock, as every gauge profile gives them; :func:`direction` is that angle's unit
vector in image coordinates (y down).  :func:`project` maps a point through a 3 x 3
homography.
"""

from __future__ import annotations

import math

import numpy as np

SH = 4  # sub-pixel bits for cv2 drawing
SC = 1 << SH


def p(x: float, y: float) -> tuple[int, int]:
    """An image point as cv2's fixed-point integers (``shift=SH``)."""
    return int(round(x * SC)), int(round(y * SC))


def direction(angle_deg: float) -> tuple[float, float]:
    """Unit vector of a dial angle (clockwise from 12 o'clock), image coordinates."""
    a = math.radians(angle_deg)
    return math.sin(a), -math.cos(a)


def project(hm: np.ndarray, x: float, y: float) -> tuple[float, float]:
    """The point (x, y) through the homography ``hm``."""
    v = hm @ np.array([x, y, 1.0])
    return float(v[0] / v[2]), float(v[1] / v[2])
