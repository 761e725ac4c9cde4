"""What the compiled grid searches share: conventions, heuristics, the indexed
binary heap, per-query state and path tracing (astar.py, jps.py and the kernels of
_astar_kernel.py, _jps_kernel.py, _jps_table_kernel.py, _jps_bits.py and
_edge_kernels.py).

Why compiled: a pure-Python A* spends ~1 µs per heap operation and ~5 µs per
expansion; the Moving AI queries expand 10^4–10^5 nodes and a station-sized
map (10^6 cells) up to 10^6, which puts pure Python at seconds per query.
The kernels run the same algorithm on flat numpy arrays with an indexed
binary heap (decrease-key, no duplicate entries), compiled once with
``njit(cache=True)`` so later processes load machine code from __pycache__.
Numba checks a cached kernel against its own file only: after an edit here,
delete this folder's ``__pycache__/*.nbi`` and ``*.nbc`` so the kernels of the
other modules, which compile these functions into themselves, are built again.

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

# exp() argument cap for the improved heuristic: e^600 * 1e6 cells < 1.8e308.
_EXP_CAP = 600.0


@njit(cache=True)
def heuristic(mode, r, c, gr, gc, scale):
    """h(n) to the goal: octile, Euclidean (seed 000 eq. 26), Manhattan (eq. 25) or
    the improved weight (e^h − 1)·h of eq. 27, with h Euclidean and the exponent
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
# Keys live in the heap arrays themselves (hf, hg beside hn) so a sift touches
# contiguous memory; pos[node] is the node's heap slot, -1 when it is not in
# the heap and CLOSED once expanded. Ties on f go to the larger g (deeper node).

CLOSED = -2


@njit(cache=True)
def _sift_up(hn, hf, hg, pos, i):
    n = hn[i]
    fv = hf[i]
    gv = hg[i]
    while i > 0:
        p = (i - 1) >> 1
        if fv < hf[p] or (fv == hf[p] and gv > hg[p]):
            hn[i] = hn[p]
            hf[i] = hf[p]
            hg[i] = hg[p]
            pos[hn[i]] = i
            i = p
        else:
            break
    hn[i] = n
    hf[i] = fv
    hg[i] = gv
    pos[n] = i


@njit(cache=True)
def _sift_down(hn, hf, hg, pos, size):
    i = 0
    n = hn[0]
    fv = hf[0]
    gv = hg[0]
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        r = c + 1
        if r < size and (hf[r] < hf[c] or (hf[r] == hf[c] and hg[r] > hg[c])):
            c = r
        if hf[c] < fv or (hf[c] == fv and hg[c] > gv):
            hn[i] = hn[c]
            hf[i] = hf[c]
            hg[i] = hg[c]
            pos[hn[i]] = i
            i = c
        else:
            break
    hn[i] = n
    hf[i] = fv
    hg[i] = gv
    pos[n] = i


@njit(cache=True)
def _push(hn, hf, hg, pos, size, node, fv, gv):
    """Insert node with key (fv, gv), or lower its key if already queued."""
    i = pos[node]
    if i < 0:
        i = size
        size += 1
    hn[i] = node
    hf[i] = fv
    hg[i] = gv
    _sift_up(hn, hf, hg, pos, i)
    return size


@njit(cache=True)
def _pop(hn, hf, hg, pos, size):
    top = hn[0]
    size -= 1
    if size > 0:
        hn[0] = hn[size]
        hf[0] = hf[size]
        hg[0] = hg[size]
        _sift_down(hn, hf, hg, pos, size)
    pos[top] = CLOSED
    return top, size


# ---- search state ---------------------------------------------------------------
# The kernels work on the map padded with one blocked cell all round (no bound
# checks) and flattened: node = r * W + c with W = width + 2. The per-node
# arrays are reused between queries; stamp[node] == gen marks the entries
# written by the current query, so nothing is cleared per query.


@njit(cache=True)
def _touch(node, gen, stamp, g, parent, pos):
    if stamp[node] != gen:
        stamp[node] = gen
        g[node] = np.inf
        parent[node] = -1
        pos[node] = -1


@njit(cache=True)
def _h(mode, node, w, gr, gc, scale):
    r = node // w
    return heuristic(mode, r, node - r * w, gr, gc, scale)


# ---- paths -----------------------------------------------------------------------


@njit(cache=True)
def _sgn(x):
    return (x > 0) - (x < 0)


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
