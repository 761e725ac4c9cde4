"""Numba-compiled grid search kernels shared by astar.py, jps.py and anyangle.py.

Why compiled: a pure-Python A* spends ~1 µs per heap operation and ~5 µs per
expansion; the Moving AI queries expand 10^4–10^5 nodes and a station-sized
map (10^6 cells) up to 10^6, which puts pure Python at seconds per query.
These kernels run the same algorithm on flat numpy arrays with an indexed
binary heap (decrease-key, no duplicate entries), compiled once with
``njit(cache=True)`` so later processes load machine code from __pycache__.

Conventions: the grid is a C-contiguous uint8 array, 1 = blocked; a cell is
addressed by its flat index ``r * W + c``; out of the map counts as blocked.
Cost model (Moving AI "octile"): straight step 1, diagonal step √2, and a
diagonal step only when both orthogonal cells it passes are free.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SQRT2 = math.sqrt(2.0)

H_OCTILE = 0
H_EUCLIDEAN = 1
H_MANHATTAN = 2
H_IMPROVED = 3

# The eight moves: four straight, then four diagonal.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)

# exp() argument cap for the improved heuristic: e^600 * 1e6 cells < 1.8e308.
_EXP_CAP = 600.0


@njit(cache=True, inline="always")
def _free(grid, r, c):
    h, w = grid.shape
    return 0 <= r < h and 0 <= c < w and grid[r, c] == 0


@njit(cache=True)
def heuristic(mode, r, c, gr, gc, scale):
    """h(n) to the goal: octile, Euclidean (eq. 26), Manhattan (eq. 25) or the
    improved weight (e^h − 1)·h of eq. 27, with h Euclidean and the exponent
    taken as min(h/scale, 600) so it never overflows."""
    dr = abs(r - gr)
    dc = abs(c - gc)
    if mode == H_OCTILE:
        if dr < dc:
            return dc + (SQRT2 - 1.0) * dr
        return dr + (SQRT2 - 1.0) * dc
    if mode == H_MANHATTAN:
        return float(dr + dc)
    e = math.sqrt(float(dr * dr + dc * dc))
    if mode == H_EUCLIDEAN:
        return e
    x = e / scale
    if x > _EXP_CAP:
        x = _EXP_CAP
    return math.expm1(x) * e


# ---- indexed binary heap ordered by (f ascending, g descending) -------------


@njit(cache=True, inline="always")
def _less(a, b, f, g):
    return f[a] < f[b] or (f[a] == f[b] and g[a] > g[b])


@njit(cache=True)
def _sift_up(heap, pos, i, f, g):
    n = heap[i]
    while i > 0:
        p = (i - 1) >> 1
        m = heap[p]
        if _less(n, m, f, g):
            heap[i] = m
            pos[m] = i
            i = p
        else:
            break
    heap[i] = n
    pos[n] = i


@njit(cache=True)
def _sift_down(heap, pos, i, size, f, g):
    n = heap[i]
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        right = left + 1
        if right < size and _less(heap[right], heap[left], f, g):
            child = right
        if _less(heap[child], n, f, g):
            heap[i] = heap[child]
            pos[heap[i]] = i
            i = child
        else:
            break
    heap[i] = n
    pos[n] = i


@njit(cache=True)
def _push_or_decrease(heap, pos, size, node, f, g):
    """Insert node, or restore order after its key fell; returns the new size."""
    if pos[node] >= 0:
        _sift_up(heap, pos, pos[node], f, g)
        return size
    heap[size] = node
    pos[node] = size
    _sift_up(heap, pos, size, f, g)
    return size + 1


@njit(cache=True)
def _pop(heap, pos, size, f, g):
    top = heap[0]
    pos[top] = -1
    size -= 1
    if size > 0:
        heap[0] = heap[size]
        pos[heap[0]] = 0
        _sift_down(heap, pos, 0, size, f, g)
    return top, size


# ---- A* ----------------------------------------------------------------------


@njit(cache=True)
def astar_kernel(grid, sr, sc, gr, gc, hmode, hscale):
    """A* (eq. 24: f = g + h) on the 8-connected grid.

    Returns (parent, g, goal_reached, expanded). Closed nodes are never
    reopened: exact for the consistent octile/Euclidean heuristics; with the
    inadmissible Manhattan or improved heuristic the path may be longer.
    """
    h, w = grid.shape
    n = h * w
    g = np.full(n, np.inf)
    f = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int32)
    pos = np.full(n, -1, dtype=np.int32)
    closed = np.zeros(n, dtype=np.uint8)
    heap = np.empty(n, dtype=np.int32)
    s = sr * w + sc
    goal = gr * w + gc
    g[s] = 0.0
    f[s] = heuristic(hmode, sr, sc, gr, gc, hscale)
    size = _push_or_decrease(heap, pos, 0, s, f, g)
    expanded = 0
    while size > 0:
        cur, size = _pop(heap, pos, size, f, g)
        closed[cur] = 1
        expanded += 1
        if cur == goal:
            return parent, g, True, expanded
        r = cur // w
        c = cur - r * w
        gcur = g[cur]
        for k in range(8):
            nr = r + DR[k]
            nc = c + DC[k]
            if not _free(grid, nr, nc):
                continue
            if k >= 4:
                if grid[nr, c] != 0 or grid[r, nc] != 0:
                    continue
                step = SQRT2
            else:
                step = 1.0
            nb = nr * w + nc
            if closed[nb]:
                continue
            ng = gcur + step
            if ng < g[nb]:
                g[nb] = ng
                f[nb] = ng + heuristic(hmode, nr, nc, gr, gc, hscale)
                parent[nb] = cur
                size = _push_or_decrease(heap, pos, size, nb, f, g)
    return parent, g, False, expanded


# ---- jump point search ---------------------------------------------------------


@njit(cache=True)
def _jump_straight(grid, r, c, dr, dc, gr, gc):
    """Walk straight from (r, c); return the first jump point's flat index
    and its distance, or (-1, 0). A cell is a jump point when it is the goal
    or has a forced neighbour: a side cell free whose cell behind is blocked
    (the rule for grids without corner cutting)."""
    h, w = grid.shape
    k = 0
    while True:
        r += dr
        c += dc
        k += 1
        if not _free(grid, r, c):
            return -1, 0
        if r == gr and c == gc:
            return r * w + c, k
        if dr == 0:
            if (_free(grid, r - 1, c) and not _free(grid, r - 1, c - dc)) or (
                _free(grid, r + 1, c) and not _free(grid, r + 1, c - dc)
            ):
                return r * w + c, k
        else:
            if (_free(grid, r, c - 1) and not _free(grid, r - dr, c - 1)) or (
                _free(grid, r, c + 1) and not _free(grid, r - dr, c + 1)
            ):
                return r * w + c, k


@njit(cache=True)
def _jump_diag(grid, r, c, dr, dc, gr, gc):
    """Walk diagonally; a cell is a jump point when it is the goal or a
    straight walk from it along either component finds a jump point. Without
    corner cutting a diagonal move has no forced neighbours."""
    h, w = grid.shape
    k = 0
    while True:
        if not (_free(grid, r + dr, c) and _free(grid, r, c + dc) and _free(grid, r + dr, c + dc)):
            return -1, 0
        r += dr
        c += dc
        k += 1
        if r == gr and c == gc:
            return r * w + c, k
        j, _ = _jump_straight(grid, r, c, dr, 0, gr, gc)
        if j >= 0:
            return r * w + c, k
        j, _ = _jump_straight(grid, r, c, 0, dc, gr, gc)
        if j >= 0:
            return r * w + c, k


@njit(cache=True)
def _relax(j, cost, cur, gr, gc, w, g, f, parent, pos, closed, heap, size):
    if j < 0 or closed[j]:
        return size
    ng = g[cur] + cost
    if ng < g[j] - 1e-9:
        g[j] = ng
        jr = j // w
        f[j] = ng + heuristic(H_OCTILE, jr, j - jr * w, gr, gc, 1.0)
        parent[j] = cur
        size = _push_or_decrease(heap, pos, size, j, f, g)
    return size


@njit(cache=True)
def _sgn(x):
    return (x > 0) - (x < 0)


@njit(cache=True)
def jps_kernel(grid, sr, sc, gr, gc):
    """Jump point search (seed 004's node screening, Harabor & Grastien's
    rules without corner cutting) with the octile heuristic.
    Returns (parent, g, goal_reached, expanded) over jump points only."""
    h, w = grid.shape
    n = h * w
    g = np.full(n, np.inf)
    f = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int32)
    pos = np.full(n, -1, dtype=np.int32)
    closed = np.zeros(n, dtype=np.uint8)
    heap = np.empty(n, dtype=np.int32)
    s = sr * w + sc
    goal = gr * w + gc
    g[s] = 0.0
    f[s] = heuristic(H_OCTILE, sr, sc, gr, gc, 1.0)
    size = _push_or_decrease(heap, pos, 0, s, f, g)
    expanded = 0
    while size > 0:
        cur, size = _pop(heap, pos, size, f, g)
        closed[cur] = 1
        expanded += 1
        if cur == goal:
            return parent, g, True, expanded
        r = cur // w
        c = cur - r * w
        p = parent[cur]
        if p < 0:
            for k in range(4):
                j, d = _jump_straight(grid, r, c, DR[k], DC[k], gr, gc)
                size = _relax(j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            for k in range(4, 8):
                j, d = _jump_diag(grid, r, c, DR[k], DC[k], gr, gc)
                size = _relax(j, d * SQRT2, cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            continue
        pr = p // w
        dr = _sgn(r - pr)
        dc = _sgn(c - (p - pr * w))
        if dr != 0 and dc != 0:
            j, d = _jump_diag(grid, r, c, dr, dc, gr, gc)
            size = _relax(j, d * SQRT2, cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            j, d = _jump_straight(grid, r, c, dr, 0, gr, gc)
            size = _relax(j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            j, d = _jump_straight(grid, r, c, 0, dc, gr, gc)
            size = _relax(j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
        elif dr == 0:
            j, d = _jump_straight(grid, r, c, 0, dc, gr, gc)
            size = _relax(j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            for s_ in (-1, 1):
                if _free(grid, r + s_, c) and not _free(grid, r + s_, c - dc):
                    j, d = _jump_straight(grid, r, c, s_, 0, gr, gc)
                    size = _relax(
                        j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size
                    )
                    j, d = _jump_diag(grid, r, c, s_, dc, gr, gc)
                    size = _relax(
                        j, d * SQRT2, cur, gr, gc, w, g, f, parent, pos, closed, heap, size
                    )
        else:
            j, d = _jump_straight(grid, r, c, dr, 0, gr, gc)
            size = _relax(j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size)
            for s_ in (-1, 1):
                if _free(grid, r, c + s_) and not _free(grid, r - dr, c + s_):
                    j, d = _jump_straight(grid, r, c, 0, s_, gr, gc)
                    size = _relax(
                        j, float(d), cur, gr, gc, w, g, f, parent, pos, closed, heap, size
                    )
                    j, d = _jump_diag(grid, r, c, dr, s_, gr, gc)
                    size = _relax(
                        j, d * SQRT2, cur, gr, gc, w, g, f, parent, pos, closed, heap, size
                    )
    return parent, g, False, expanded


@njit(cache=True)
def trace_cells(parent, goal, w):
    """Follow parents back from goal and fill the straight or diagonal run
    between consecutive nodes, so the result is a cell-by-cell path."""
    count = 1
    cur = goal
    while parent[cur] >= 0:
        p = parent[cur]
        r, c = cur // w, cur % w
        pr, pc = p // w, p % w
        count += max(abs(r - pr), abs(c - pc))
        cur = p
    out = np.empty((count, 2), dtype=np.int64)
    i = count - 1
    cur = goal
    out[i, 0] = cur // w
    out[i, 1] = cur % w
    while parent[cur] >= 0:
        p = parent[cur]
        r, c = cur // w, cur % w
        pr, pc = p // w, p % w
        dr = _sgn(pr - r)
        dc = _sgn(pc - c)
        while r != pr or c != pc:
            r += dr
            c += dc
            i -= 1
            out[i, 0] = r
            out[i, 1] = c
        cur = p
    return out


# ---- line of sight and post-smoothing ----------------------------------------


@njit(cache=True)
def line_of_sight(grid, r0, c0, r1, c1):
    """True when the segment between the two cell centres crosses only free
    cells; passing exactly through a cell corner needs both side cells free
    (the same no-squeezing rule as the diagonal step). Exact integer walk."""
    if not _free(grid, r0, c0) or not _free(grid, r1, c1):
        return False
    dr = r1 - r0
    dc = c1 - c0
    sr = _sgn(dr)
    sc = _sgn(dc)
    adr = abs(dr)
    adc = abs(dc)
    r = r0
    c = c0
    i = 0
    j = 0
    while i < adc or j < adr:
        lhs = (2 * i + 1) * adr
        rhs = (2 * j + 1) * adc
        if i < adc and (j >= adr or lhs < rhs):
            c += sc
            i += 1
        elif j < adr and (i >= adc or lhs > rhs):
            r += sr
            j += 1
        else:
            if not _free(grid, r, c + sc) or not _free(grid, r + sr, c):
                return False
            r += sr
            c += sc
            i += 1
            j += 1
        if not _free(grid, r, c):
            return False
    return True


@njit(cache=True)
def shortcut_path(grid, cells):
    """Post-smoothing: from each kept vertex jump to the farthest later cell of
    the path still in line of sight. Returns the kept rows of ``cells``."""
    n = cells.shape[0]
    keep = np.empty(n, dtype=np.int64)
    if n == 0:
        return keep[:0]
    m = 0
    keep[m] = 0
    m += 1
    a = 0
    while a < n - 1:
        b = a + 1
        best = b
        # Scan forward; allow a few failures so a visible cell past a short
        # occluded stretch is still found.
        misses = 0
        while b < n:
            if line_of_sight(grid, cells[a, 0], cells[a, 1], cells[b, 0], cells[b, 1]):
                best = b
                misses = 0
            else:
                misses += 1
                if misses > 8:
                    break
            b += 1
        keep[m] = best
        m += 1
        a = best
    return keep[:m]
