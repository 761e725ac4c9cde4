"""The reading by tick interval and Euclidean interpolation, eq. 21."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["eq21_reading", "find_interval"]


def find_interval(point, ticks_xy) -> tuple[int, float]:
    """Index i of the tick interval [i, i+1] that holds ``point`` and the position t in it.

    The interval is the consecutive tick pair whose segment is closest to the point; t is the
    projection parameter (0 at tick i, 1 at tick i+1), clipped to [0, 1].
    """
    t_xy = np.asarray(ticks_xy, float)
    p = np.asarray(point, float)
    a = t_xy[:-1]
    d = t_xy[1:] - a
    ll = (d**2).sum(axis=1)
    t = np.clip(((p - a) * d).sum(axis=1) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
    dist = np.hypot(*(a + t[:, None] * d - p).T)
    i = int(np.argmin(dist))
    return i, float(t[i])


def eq21_reading(point, ticks_xy, values) -> tuple[float, float, float, int]:
    """Eq. 21: v = v_i + k * l / L for the intersection point P = (x_p, y_p).

    l = |P - (a_i, b_i)| is the distance to the smaller tick of the interval, L the distance
    between the interval's two ticks, k = v_{i+1} - v_i the value of one tick interval.
    Returns (v, l, L, i).
    """
    i, _ = find_interval(point, ticks_xy)
    ax, ay = ticks_xy[i]
    bx, by = ticks_xy[i + 1]
    l_ = math.hypot(point[0] - ax, point[1] - ay)
    big_l = math.hypot(ax - bx, ay - by)
    k = values[i + 1] - values[i]
    return values[i] + k * l_ / big_l, l_, big_l, i
