"""The true shortest any-angle path for the benchmarks: A* over the
visibility graph of the blocked cells' convex corners (plus start and goal),
with edges found lazily and checked by the same segment rule as any_angle.
O(N²) segment tests in the worst case — for small and medium maps only."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from app.core.planner import _edge_kernels as E


@njit(cache=True)
def convex_corners(grid):
    h, w = grid.shape
    out = []
    for R in range(h + 1):
        for C in range(w + 1):
            if E.corner_free_count(grid, R, C) == 3:
                out.append((2 * R, 2 * C))
    return out


@njit(cache=True)
def _vg_astar(grid, nodes, s, t, bound):
    n = nodes.shape[0]
    g = np.full(n, np.inf)
    closed = np.zeros(n, dtype=np.bool_)
    g[s] = 0.0
    h = np.empty(n)
    for i in range(n):
        h[i] = math.hypot(nodes[i, 0] - nodes[t, 0], nodes[i, 1] - nodes[t, 1])
    while True:
        u = -1
        best = np.inf
        for i in range(n):  # O(N) selection: N is small here
            if not closed[i] and g[i] + h[i] < best:
                best = g[i] + h[i]
                u = i
        if u < 0 or best > bound:
            return np.inf
        if u == t:
            return g[t]
        closed[u] = True
        for v in range(n):
            if closed[v]:
                continue
            d = math.hypot(nodes[u, 0] - nodes[v, 0], nodes[u, 1] - nodes[v, 1])
            nv = g[u] + d
            if nv < g[v] - 1e-9 and nv + h[v] <= bound + 1e-9:
                if E.seg_free(grid, nodes[u, 0], nodes[u, 1], nodes[v, 0], nodes[v, 1]):
                    g[v] = nv


def true_shortest(grid: np.ndarray, start, goal, corners: np.ndarray, bound: float) -> float:
    """Length (cells) of the shortest valid path between two cell centres;
    ``bound`` (cells): a known path length, prunes the search (ellipse)."""
    s = np.array([[2 * start[0] + 1, 2 * start[1] + 1]], dtype=np.int64)
    t = np.array([[2 * goal[0] + 1, 2 * goal[1] + 1]], dtype=np.int64)
    # Only corners inside the ellipse |s p| + |p t| <= bound can be on the path.
    d = np.hypot(*(corners - s).T) + np.hypot(*(corners - t).T)
    nodes = np.vstack([s, t, corners[d <= 2 * bound + 1e-6]])
    return float(_vg_astar(grid, nodes, 0, 1, 2 * bound + 1e-6)) / 2.0
