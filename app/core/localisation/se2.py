"""Planar rigid motions (x, y, θ): composition ⊕, relative pose ⊖, angle wrap.

``compose(a, b)`` is pose b expressed in a's frame carried into the world;
``relative(a, b)`` is b seen from a, so compose(a, relative(a, b)) == b.
"""

from __future__ import annotations

import math

import numpy as np


def wrap(a):
    """Angle(s) to [−π, π)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def wrap_pose(v) -> np.ndarray:
    """A copy of (x, y, θ) with θ wrapped."""
    out = np.array(v, float)
    out[2] = float(wrap(out[2]))
    return out


def compose(a, b) -> np.ndarray:
    x, y, t = a
    c, s = math.cos(t), math.sin(t)
    return np.array([x + c * b[0] - s * b[1], y + s * b[0] + c * b[1], float(wrap(t + b[2]))])


def relative(a, b) -> np.ndarray:
    x, y, t = a
    c, s = math.cos(t), math.sin(t)
    dx, dy = b[0] - x, b[1] - y
    return np.array([c * dx + s * dy, -s * dx + c * dy, float(wrap(b[2] - t))])


def transform_points(pose, pts: np.ndarray) -> np.ndarray:
    """Points (N, 2) in the frame ``pose`` carried into the world."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return pts @ np.array([[c, s], [-s, c]]) + np.asarray(pose[:2], float)


def rotation(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])
