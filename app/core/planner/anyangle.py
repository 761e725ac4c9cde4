"""Any-angle paths and smoothing (seed 004 §2: "any-direction search" plus
non-uniform cubic spline smoothing; turning points 23 → 14 in its Fig. 9).

1. ``shorten``: post-smoothing of a grid path (the string-pulling form of
   Theta*): keep a vertex only where the straight segment from the last kept
   vertex would leave line of sight. Line of sight is tested on the same
   (inflated) grid, with the no-squeezing rule at cell corners.
2. ``smooth_curve``: a centripetal Catmull-Rom spline (a non-uniform cubic
   through the kept vertices) sampled every ``step`` cells. Every sample is
   checked against the grid; where one falls on a blocked cell, the nearby
   polyline corners are pinned by extra knots and the curve is rebuilt, so the
   curve keeps the clearance the inflation gave the polyline.
3. ``turning_points``: interior vertices where the heading changes.
"""

from __future__ import annotations

import logging

import numpy as np

from . import _sight_kernels as S
from ._result import as_grid_array
from .grid import GridMap

log = logging.getLogger(__name__)


def turning_points(points) -> int:
    """Interior vertices where the direction changes (collinear runs count 0)."""
    p = np.asarray(points, dtype=np.float64)
    if len(p) < 3:
        return 0
    d = np.diff(p, axis=0)
    d = d[np.any(d != 0, axis=1)]
    if len(d) < 2:
        return 0
    cross = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
    dot = np.sum(d[:-1] * d[1:], axis=1)
    norm = np.linalg.norm(d[:-1], axis=1) * np.linalg.norm(d[1:], axis=1)
    return int(np.sum((np.abs(cross) > 1e-9 * norm) | (dot < 0)))


def line_of_sight(blocked: np.ndarray | GridMap, a, b) -> bool:
    grid = as_grid_array(blocked)
    return bool(S.line_of_sight(grid, int(a[0]), int(a[1]), int(b[0]), int(b[1])))


def shorten(blocked: np.ndarray | GridMap, cells) -> list[tuple[int, int]]:
    """Any-angle vertices (row, col) of a grid path, first and last kept."""
    arr = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    if len(arr) <= 2:
        return [(int(r), int(c)) for r, c in arr]
    keep = S.shortcut_path(as_grid_array(blocked), arr)
    return [(int(arr[i, 0]), int(arr[i, 1])) for i in keep]


def polyline_length(points) -> float:
    p = np.asarray(points, dtype=np.float64)
    if len(p) < 2:
        return 0.0
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))


def _catmull_rom(pts: np.ndarray, step: float) -> np.ndarray:
    """Centripetal Catmull-Rom through pts (alpha = 0.5), sampled about every
    ``step`` units of chord length; passes through every point."""
    if len(pts) < 3:
        return pts.copy()
    ext = np.vstack([2 * pts[0] - pts[1], pts, 2 * pts[-1] - pts[-2]])
    out = [pts[:1]]
    for i in range(1, len(ext) - 2):
        p0, p1, p2, p3 = ext[i - 1], ext[i], ext[i + 1], ext[i + 2]
        t0 = 0.0
        t1 = t0 + max(np.linalg.norm(p1 - p0), 1e-9) ** 0.5
        t2 = t1 + max(np.linalg.norm(p2 - p1), 1e-9) ** 0.5
        t3 = t2 + max(np.linalg.norm(p3 - p2), 1e-9) ** 0.5
        n = max(2, int(np.ceil(np.linalg.norm(p2 - p1) / step)) + 1)
        t = np.linspace(t1, t2, n)[1:, None]
        a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1
        a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2
        a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3
        b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2
        b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3
        out.append((t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2)
    return np.vstack(out)


def _bad_samples(grid: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Indices of samples (in cell-centre coordinates) on blocked or outside cells."""
    rc = np.floor(curve + 0.5).astype(np.int64)
    h, w = grid.shape
    inside = (rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)
    bad = ~inside
    bad[inside] = grid[rc[inside, 0], rc[inside, 1]] != 0
    return np.nonzero(bad)[0]


def smooth_curve(
    blocked: np.ndarray | GridMap, vertices, step: float = 0.5, max_rounds: int = 8
) -> np.ndarray:
    """A smooth curve (N × 2 array of (row, col), cell-centre coordinates)
    through the any-angle vertices that stays on free cells of ``blocked``.

    Where a sample would leave the free space, knots are added on the two
    polyline segments around the offending corner (a quarter of the way in),
    which pulls the spline onto the polyline; after ``max_rounds`` the
    densely sampled polyline itself is returned (it is collision-free by
    line of sight).
    """
    grid = as_grid_array(blocked)
    pts = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 3:
        return densify(pts, step)
    for _ in range(max_rounds):
        curve = _catmull_rom(pts, step)
        bad = _bad_samples(grid, curve)
        if len(bad) == 0:
            return curve
        # Map each bad sample to the nearest knot and pin that corner.
        d = np.linalg.norm(curve[bad][:, None, :] - pts[None, :, :], axis=2)
        corners = sorted(set(int(i) for i in np.argmin(d, axis=1)))
        new = [pts[0]]
        for i in range(1, len(pts)):
            if i in corners or (i - 1) in corners:
                a, b = pts[i - 1], pts[i]
                if (i - 1) in corners:
                    new.append(a + 0.25 * (b - a))
                if i in corners:
                    new.append(a + 0.75 * (b - a))
            new.append(pts[i])
        pts = np.asarray(new)
    log.debug("smooth_curve: spline kept hitting obstacles; using the polyline")
    return densify(np.asarray(vertices, dtype=np.float64).reshape(-1, 2), step)


def densify(pts: np.ndarray, step: float) -> np.ndarray:
    """Points along the polyline pts, about ``step`` apart, corners kept."""
    if len(pts) < 2:
        return pts.copy()
    out = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:], strict=False):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        t = np.linspace(0, 1, n + 1)[1:, None]
        out.append(a + t * (b - a))
    return np.vstack(out)
