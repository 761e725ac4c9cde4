"""Turn-exact links between lanes (seed 001 eq. 3: each turn costs wall).

A lane tour (:mod:`.lanes`) joins the end of one lane to the start of the
next by a fewest-step path. :func:`link_cost` (below) knows the changes of
heading of a one-step link exactly but prices every longer link at a flat
3 turns + λ per cell crossed, and the tour then joins the lanes by
whichever fewest-step path the breadth-first search meets first. Yet a
link of a few steps can turn once (a reversal back along the lane it
leaves), twice (up the lane's side and into the next one) or four times
(a zigzag), and which of these it is decides how the lane order compares.

Here, for link lengths 2 ≤ d ≤ ``radius``:

1. :func:`link_turns`: the fewest changes of heading of a link among the
   fewest-step paths from end x (leaving along its lane's outward heading)
   to end y (entering along its lane's heading), counting the turn off the
   lane at x and onto the lane at y. Dynamic programming over the
   breadth-first layers from x, state (cell, heading of the last step):
   T(u, k) = min over the cells v one layer nearer with u = v + step k of
   T(v, k′) + [k′ ≠ k]. A lane of one cell has no heading: half a turn at
   that end, as in :func:`link_cost`.
2. :func:`link_paths`: the same programme for the tour's links, with parents, so
   the tour is joined by the path that the cost priced.

Moves come from a neighbour table (:func:`._kernels.neighbour_table`:
no corner cutting, across the seam when it was built with wrap); headings
are the eight moves of ``_kernels.DR``/``DC``, so a step across the seam has
the heading of the same step elsewhere. The visits are the same as with any
fewest-step link (d − 1 cells crossed), so only turns change.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import DC, DR, bfs_layers

NO_DIR = 9  # a one-cell lane's ends have no heading (.lanes)
BIG = 1 << 20


@njit(cache=True)
def _off(ur, uc, k):
    """Changes of heading on the first step k of a link leaving an end whose
    outward heading is (ur, uc): 0 straight on, 1 otherwise, 0.5 with none."""
    if ur == NO_DIR:
        return 0.5
    return 0.0 if DR[k] == ur and DC[k] == uc else 1.0


@njit(cache=True)
def _on(ur, uc, k):
    """Changes of heading entering a lane at an end of outward heading
    (ur, uc) by a last step k: the lane runs the other way, (−ur, −uc)."""
    if ur == NO_DIR:
        return 0.5
    return 0.0 if DR[k] == -ur and DC[k] == -uc else 1.0


@njit(cache=True)
def _programme(nbr, src, ur, uc, radius, dist, queue, best, parent):
    """Fewest turns T(u, k) over the fewest-step paths from ``src`` leaving
    along (ur, uc) (see the module), for every cell within ``radius``;
    ``best`` (cells, 8) must be BIG on entry, ``parent`` (cells, 8) gets the
    heading of the step before (−1: the first step). Returns the number of
    cells reached (queue[:n], their dist set; the caller resets both)."""
    n = bfs_layers(nbr, src, radius, dist, queue)
    for k in range(8):
        u = nbr[src, k]
        if u >= 0:
            best[u, k] = _off(ur, uc, k)
            parent[u, k] = -1
    for t in range(1, n):
        v = queue[t]
        if dist[v] >= radius:
            continue
        for k in range(8):
            tv = best[v, k]
            if tv >= BIG:
                continue
            for k2 in range(8):
                u = nbr[v, k2]
                if u < 0 or dist[u] != dist[v] + 1:
                    continue
                tu = tv + (0.0 if k2 == k else 1.0)
                if tu < best[u, k2]:
                    best[u, k2] = tu
                    parent[u, k2] = k
    return n


@njit(cache=True)
def link_turns(nbr, cell, ur, uc, radius):
    """(m, m) fewest changes of heading of a fewest-step link from end x to
    end y (lane ends: cells ``cell``, outward headings ur/uc) when their
    distance d is 2 ≤ d ≤ ``radius``; −1 elsewhere (d = 0, 1 or beyond)."""
    m = len(cell)
    size = nbr.shape[0]
    out = np.full((m, m), -1.0)
    dist = np.full(size, -1, dtype=np.int64)
    queue = np.empty(size, dtype=np.int64)
    best = np.full((size, 8), float(BIG))
    parent = np.empty((size, 8), dtype=np.int64)
    for x in range(m):
        n = _programme(nbr, cell[x], ur[x], uc[x], radius, dist, queue, best, parent)
        for y in range(m):
            d = dist[cell[y]]
            if d < 2:
                continue
            low = float(BIG)
            for k in range(8):
                tk = best[cell[y], k]
                if tk < BIG:
                    tk += _on(ur[y], uc[y], k)
                    if tk < low:
                        low = tk
            out[x, y] = low
        for t in range(n):  # reset only what this search touched
            v = queue[t]
            dist[v] = -1
            for k in range(8):
                best[v, k] = BIG
    return out


@njit(cache=True)
def link_paths(nbr, src, sur, suc, dst, dur, duc, radius):
    """The links :func:`link_turns` priced, for each i: from src[i] (outward
    heading sur/suc[i]) to dst[i] (outward heading dur/duc[i], entered the
    other way) by fewest steps and, among those, fewest changes of heading.
    Returns (cells, offsets): link i is cells[offsets[i]:offsets[i + 1]],
    without its first cell, with its last; empty when dst[i] is not within
    ``radius`` steps."""
    size = nbr.shape[0]
    dist = np.full(size, -1, dtype=np.int64)
    queue = np.empty(size, dtype=np.int64)
    best = np.full((size, 8), float(BIG))
    parent = np.empty((size, 8), dtype=np.int64)
    offsets = np.zeros(len(src) + 1, dtype=np.int64)
    cells = np.empty(0, dtype=np.int64)
    parts = []
    for i in range(len(src)):
        n = _programme(nbr, src[i], sur[i], suc[i], radius, dist, queue, best, parent)
        d = dist[dst[i]]
        low, kb = float(BIG), -1
        if d >= 1:
            for k in range(8):
                tk = best[dst[i], k]
                if tk < BIG:
                    tk += _on(dur[i], duc[i], k)
                    if tk < low:
                        low, kb = tk, k
        out = np.empty(max(d, 0) if kb >= 0 else 0, dtype=np.int64)
        v, k = dst[i], kb
        for j in range(len(out) - 1, -1, -1):
            out[j] = v
            pk = parent[v, k]
            v = _back(nbr, v, k)  # the cell one step back along heading k
            k = pk
        parts.append(out)
        offsets[i + 1] = offsets[i] + len(out)
        for t in range(n):  # reset only what this search touched
            v = queue[t]
            dist[v] = -1
            for k in range(8):
                best[v, k] = BIG
    if offsets[-1] > 0:
        cells = np.empty(offsets[-1], dtype=np.int64)
        for i in range(len(parts)):
            cells[offsets[i] : offsets[i + 1]] = parts[i]
    return cells, offsets


@njit(cache=True)
def _back(nbr, v, k):
    """The cell from which step k leads to v (moves are symmetric: the
    reverse step, k ^ 1 for straight moves and 11 − k for diagonal ones in
    DR/DC order)."""
    rk = k ^ 1 if k < 4 else 11 - k
    return nbr[v, rk]


@njit(cache=True)
def _dcol(dc, w):
    """A one-step column change, also across the seam (W−1 → 0 is +1)."""
    if dc > 1:
        return dc - w
    if dc < -1:
        return dc + w
    return dc


@njit(cache=True)
def link_cost(dist, cell, ur, uc, w, x, y, lam):
    """Cost of leaving a lane at end x and entering one at end y: changes of
    heading for a one-step link (ur/uc: the outward direction at each end),
    3 + lam per cell crossed for a longer one."""
    d = dist[x, y]
    if d == 0:
        return 0.0
    if d > 1:
        return 3.0 + lam * (d - 1)
    sr = cell[y] // w - cell[x] // w
    sc = _dcol(cell[y] % w - cell[x] % w, w)
    t = 0.0
    if ur[x] == NO_DIR:
        t += 0.5
    elif ur[x] != sr or uc[x] != sc:
        t += 1.0
    if ur[y] == NO_DIR:
        t += 0.5
    elif -ur[y] != sr or -uc[y] != sc:
        t += 1.0
    return t
