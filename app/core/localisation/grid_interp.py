"""Cubic interpolation of a submap's likelihood grid (submap_match.py).

Both the grid fit and the covariances read the likelihood field M between
its cell centres by cubic convolution (Catmull-Rom; R. Keys, "Cubic
convolution interpolation for digital image processing", IEEE Trans. ASSP
1981), as Hess et al. 2016 (§IV.C) interpolate their smoothed grid:

- ``_bicubic``: M itself and its gradient;
- ``_bicubic_hessian``: the squared distance each node stands for,
  G = d² = −2σ² ln M, with its gradient and Hessian (the point-to-line
  model of the grid fit and of the residual covariance).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _bicubic(grid, lox, loy, res, px, py):
    """Value and gradient (d/dx, d/dy) of the grid interpolated between cell
    centres by cubic convolution (Catmull-Rom, Keys 1981), as Hess et al.
    interpolate M_smooth: a bilinear interpolant of a peaked field has its
    maxima on the grid's nodes and pulls a wall to the nearest one (up to
    res/2). Zero outside."""
    h, w = grid.shape
    u = (px - lox) / res - 0.5
    v = (py - loy) / res - 0.5
    x0 = int(math.floor(u))
    y0 = int(math.floor(v))
    if x0 < 1 or y0 < 1 or x0 + 2 >= w or y0 + 2 >= h:
        return 0.0, 0.0, 0.0
    wx, dx = _keys(u - x0)
    wy, dy = _keys(v - y0)
    val, gx, gy = 0.0, 0.0, 0.0
    for j in range(4):
        for i in range(4):
            m = grid[y0 - 1 + j, x0 - 1 + i]
            val += wy[j] * wx[i] * m
            gx += wy[j] * dx[i] * m
            gy += dy[j] * wx[i] * m
    return val, gx / res, gy / res


@njit(cache=True)
def _keys(t):
    """Catmull-Rom weights of the four nodes round t ∈ [0, 1) and their
    derivatives in t (tuples: no allocation in the inner loops)."""
    t2 = t * t
    t3 = t2 * t
    w = (-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0,
         -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2)
    d = (-1.5 * t2 + 2.0 * t - 0.5, 4.5 * t2 - 5.0 * t,
         -4.5 * t2 + 4.0 * t + 0.5, 1.5 * t2 - t)
    return w, d



@njit(cache=True)
def _bicubic_hessian(grid, lox, loy, res, px, py, sigma):
    """Value, gradient and Hessian (gxx, gxy, gyy) of the Catmull-Rom
    interpolant of the squared distance each node of the likelihood grid
    stands for, d² = −2σ² ln M (M = exp(−d²/2σ²); 9σ² beyond 3σ); zeros
    outside."""
    h, w = grid.shape
    u = (px - lox) / res - 0.5
    v = (py - loy) / res - 0.5
    x0 = int(math.floor(u))
    y0 = int(math.floor(v))
    out = np.zeros(6)
    if x0 < 1 or y0 < 1 or x0 + 2 >= w or y0 + 2 >= h:
        return out
    floor = math.exp(-4.5)
    tx, ty = u - x0, v - y0
    wx, dx = _keys(tx)
    wy, dy = _keys(ty)
    ddx = (2.0 - 3.0 * tx, 9.0 * tx - 5.0, 4.0 - 9.0 * tx, 3.0 * tx - 1.0)
    ddy = (2.0 - 3.0 * ty, 9.0 * ty - 5.0, 4.0 - 9.0 * ty, 3.0 * ty - 1.0)
    for j in range(4):
        for i in range(4):
            m = -2.0 * sigma * sigma * math.log(max(grid[y0 - 1 + j, x0 - 1 + i], floor))
            out[0] += wy[j] * wx[i] * m
            out[1] += wy[j] * dx[i] * m
            out[2] += dy[j] * wx[i] * m
            out[3] += wy[j] * ddx[i] * m
            out[4] += dy[j] * dx[i] * m
            out[5] += ddy[j] * wx[i] * m
    out[1:3] /= res
    out[3:] /= res * res
    return out


