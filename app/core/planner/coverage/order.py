"""The order in which the sub-regions are swept (seed 001 §3.3, Figs. 9–10).

Each sub-region's centre is a vertex; adjacent sub-regions (Definition 2)
are joined by an edge weighted by the distance between the centres. The
weighted adjacency matrix is eq. 5:

    a_ij = ω_ij   if i and j are adjacent,
           0      if i = j,
           ∞      otherwise.

The order is the greedy depth-first walk of Fig. 10: from the start vertex,
go to the nearest unvisited vertex in the current vertex's row of A; when
there is none, step back to the previous vertex and scan its row again.

PAPER_MATRIX is the 7 × 7 matrix printed under eq. 5, in units of D. The
text copy lost its column layout; it is read column by column and made
symmetric. Two entries are not legible: a_13 (blank in column 1; 9.66 D,
the first entry of column 3) and a_34 (printed as 0 off the diagonal in
column 4; 20.5 D from column 3). The order the paper states,
①→③→②→④→⑥→⑦→⑤, follows from this matrix for any a_13 < 19.24 D and any
a_34, and needs a_23 = 9.66 D (column 2) rather than 20.5 D (column 3): with
20.5 D the walk would go ③→⑤.
"""

from __future__ import annotations

import math

import numpy as np

from .decompose import adjacent_pairs, centroids

INF = math.inf

PAPER_MATRIX = np.array(
    [
        [0.0, 19.24, 9.66, INF, INF, INF, INF],
        [19.24, 0.0, 9.66, 17.1, INF, INF, INF],
        [9.66, 9.66, 0.0, 20.5, 16.8, 17.1, INF],
        [INF, 17.1, 20.5, 0.0, 20.5, 12.18, 20.11],
        [INF, INF, 16.8, 20.5, 0.0, INF, 12.18],
        [INF, INF, 17.1, 12.18, INF, 0.0, 20.5],
        [INF, INF, INF, 20.11, 12.18, 20.5, 0.0],
    ]
)
"""Seed 001, the matrix under eq. 5 (units of D); see the module note."""

PAPER_ORDER = (0, 2, 1, 3, 5, 6, 4)
"""①→③→②→④→⑥→⑦→⑤ (§3.3), zero-based."""


def adjacency_matrix(labels: np.ndarray, count: int | None = None) -> np.ndarray:
    """Eq. 5 for a decomposition: centre-to-centre distance (in cells) between
    adjacent regions, 0 on the diagonal, ∞ between regions not adjacent."""
    if count is None:
        count = int(labels.max()) + 1
    cen = centroids(labels, count)
    a = np.full((count, count), INF)
    np.fill_diagonal(a, 0.0)
    for i, j in adjacent_pairs(labels):
        a[i, j] = a[j, i] = float(np.hypot(*(cen[i] - cen[j])))
    return a


def dfs_order(a: np.ndarray, start: int = 0) -> list[int]:
    """Depth-first order of Fig. 10 on the weighted adjacency matrix ``a``.

    Visits every vertex of start's connected component; if the graph is not
    connected, the walk carries on from the unvisited vertex of least index
    (each component in turn), so every vertex appears exactly once."""
    n = a.shape[0]
    if not 0 <= start < n:
        raise ValueError(f"start vertex {start} outside 0..{n - 1}")
    seen = np.zeros(n, dtype=bool)
    order: list[int] = []
    roots = [start] + [v for v in range(n) if v != start]
    for root in roots:
        if seen[root]:
            continue
        seen[root] = True
        order.append(root)
        stack = [root]
        while stack:
            row = a[stack[-1]].copy()
            row[seen] = INF
            nxt = int(np.argmin(row))
            if not math.isfinite(row[nxt]):
                stack.pop()  # no unvisited neighbour: back to the previous vertex
                continue
            seen[nxt] = True
            order.append(nxt)
            stack.append(nxt)
    return order
