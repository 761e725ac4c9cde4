"""Nearest visible reference point on a bucket grid, compiled (numba).

A map's reference (icp.Reference with ``facing``) is fixed for the robot's
whole patrol, and ICP asks it for the nearest point of ~180 scan points some
seven times per match. A k-d tree answers, but each query pays Python and
array overhead twice when a wall's far face is nearest (the second query, for
the ``VISIBLE_K`` nearest). Here the points are sorted once into square
buckets (cells of ``cell_m``; CSR layout: ``order`` holds point indices
bucket by bucket, ``starts`` where each bucket begins) and one compiled loop
answers the same question as icp._correspond's two k-d queries:

- the nearest point at a distance < ``gate`` (none: distance inf, index N);
- when its face looks away from the sensor (f · ray > ``max_cos``, see
  icp.py's module docstring), the nearest *seen* point among the ``k``
  nearest within the gate, or none.

Only the buckets that a disc of radius ``gate`` round the query can touch are
visited (one bucket of margin either side against rounding), so the answer
equals the k-d tree's up to ties in distance.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


class BucketGrid:
    """Points sorted into square buckets of ``cell_m`` (CSR layout)."""

    def __init__(self, points: np.ndarray, cell_m: float) -> None:
        pts = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
        self.cell = float(cell_m)
        self.lo = pts.min(axis=0) - cell_m
        c = np.floor((pts - self.lo) / self.cell).astype(np.int64)
        self.nx, self.ny = int(c[:, 0].max()) + 2, int(c[:, 1].max()) + 2
        key = c[:, 1] * self.nx + c[:, 0]
        self.order = np.argsort(key, kind="stable").astype(np.int64)
        counts = np.bincount(key, minlength=self.nx * self.ny)
        self.starts = np.zeros(self.nx * self.ny + 1, np.int64)
        np.cumsum(counts, out=self.starts[1:])

    def nearest_visible(self, points: np.ndarray, facing: np.ndarray, moved: np.ndarray,
                        origin: np.ndarray, gate: float, k: int,
                        max_cos: float) -> tuple[np.ndarray, np.ndarray]:
        """(distance, index) of each moved point's nearest visible point
        (module docstring); ``facing`` zero rows are seen from anywhere."""
        return _nearest_visible(np.ascontiguousarray(moved, dtype=float), float(origin[0]),
                                float(origin[1]), points, facing, self.starts, self.order,
                                float(self.lo[0]), float(self.lo[1]), self.cell, self.nx,
                                self.ny, float(gate), int(k), float(max_cos))


@njit(cache=True)
def _window(v: float, lo: float, cell: float, gate: float, n: int) -> tuple[int, int]:
    a = int(math.floor((v - gate - lo) / cell)) - 1
    b = int(math.floor((v + gate - lo) / cell)) + 1
    return max(a, 0), min(b, n - 1)


@njit(cache=True)
def _nearest_one(qx, qy, ox, oy, pts, facing, starts, order, lox, loy, cell, nx, ny, gate, k,
                 max_cos, cand_d, cand_i):
    """(distance, index) of the nearest visible point of (qx, qy); (inf, N)
    if none. ``cand_d``, ``cand_i``: scratch buffers of N entries."""
    npts = pts.shape[0]
    x0, x1 = _window(qx, lox, cell, gate, nx)
    y0, y1 = _window(qy, loy, cell, gate, ny)
    g2 = gate * gate
    best, bj, m = np.inf, npts, 0
    for cy in range(y0, y1 + 1):
        for cx in range(x0, x1 + 1):
            b = cy * nx + cx
            for s in range(starts[b], starts[b + 1]):
                j = order[s]
                dx, dy = pts[j, 0] - qx, pts[j, 1] - qy
                d2 = dx * dx + dy * dy
                if d2 < g2:
                    cand_d[m], cand_i[m] = d2, j
                    m += 1
                    if d2 < best:
                        best, bj = d2, j
    if m == 0:
        return np.inf, npts
    rx, ry = qx - ox, qy - oy
    rn = max(math.hypot(rx, ry), 1e-9)
    rx, ry = rx / rn, ry / rn
    if facing[bj, 0] * rx + facing[bj, 1] * ry <= max_cos:
        return math.sqrt(best), bj
    # the nearest face looks away: the nearest seen one among the k nearest
    sel = np.argsort(cand_d[:m], kind="mergesort")
    for t in range(min(k, m)):
        j = cand_i[sel[t]]
        if facing[j, 0] * rx + facing[j, 1] * ry <= max_cos:
            return math.sqrt(cand_d[sel[t]]), j
    return np.inf, npts


@njit(cache=True)
def _nearest_visible(moved, ox, oy, pts, facing, starts, order, lox, loy, cell, nx, ny,
                     gate, k, max_cos):
    n = moved.shape[0]
    dist = np.empty(n)
    idx = np.empty(n, np.int64)
    cand_d = np.empty(pts.shape[0])
    cand_i = np.empty(pts.shape[0], np.int64)
    for i in range(n):
        dist[i], idx[i] = _nearest_one(moved[i, 0], moved[i, 1], ox, oy, pts, facing, starts,
                                       order, lox, loy, cell, nx, ny, gate, k, max_cos,
                                       cand_d, cand_i)
    return dist, idx
