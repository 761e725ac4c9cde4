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


@njit(cache=True, inline="always")
def _touch(node, gen, stamp, g, parent, pos):
    if stamp[node] != gen:
        stamp[node] = gen
        g[node] = np.inf
        parent[node] = -1
        pos[node] = -1


@njit(cache=True, inline="always")
def _h(mode, node, w, gr, gc, scale):
    r = node // w
    return heuristic(mode, r, node - r * w, gr, gc, scale)


# ---- A* ----------------------------------------------------------------------


@njit(cache=True)
def astar_kernel(gp, w, s, goal, hmode, hscale, gen, stamp, g, parent, pos, hn, hf, hg):
    """A* (eq. 24: f = g + h) on the padded, flattened 8-connected grid.

    Returns (goal_reached, expanded); the path is in ``parent``. Closed nodes
    are never reopened: exact for the consistent octile/Euclidean heuristics;
    with the inadmissible Manhattan or improved heuristic paths may be longer.
    """
    gr = goal // w
    gc = goal - gr * w
    off = np.array([-w, w, -1, 1, -w - 1, -w + 1, w - 1, w + 1])
    offv = np.array([0, 0, 0, 0, -w, -w, w, w])
    offh = np.array([0, 0, 0, 0, -1, 1, -1, 1])
    _touch(s, gen, stamp, g, parent, pos)
    g[s] = 0.0
    size = _push(hn, hf, hg, pos, 0, s, _h(hmode, s, w, gr, gc, hscale), 0.0)
    expanded = 0
    while size > 0:
        cur, size = _pop(hn, hf, hg, pos, size)
        expanded += 1
        if cur == goal:
            return True, expanded
        gcur = g[cur]
        for k in range(8):
            nb = cur + off[k]
            if gp[nb]:
                continue
            if k >= 4:
                if gp[cur + offv[k]] or gp[cur + offh[k]]:
                    continue
                ng = gcur + SQRT2
            else:
                ng = gcur + 1.0
            _touch(nb, gen, stamp, g, parent, pos)
            if pos[nb] == CLOSED or ng >= g[nb]:
                continue
            g[nb] = ng
            parent[nb] = cur
            size = _push(hn, hf, hg, pos, size, nb, ng + _h(hmode, nb, w, gr, gc, hscale), ng)
    return False, expanded


# ---- jump point search ---------------------------------------------------------


@njit(cache=True)
def _jump_straight(gp, cur, d, side, goal):
    """Walk from cur by offset d; return (jump point, steps) or (-1, 0). A cell
    is a jump point when it is the goal or has a forced neighbour: a side cell
    (offset ±side) that is free while the cell behind it is blocked — the
    rule for grids without corner cutting."""
    k = 0
    while True:
        cur += d
        k += 1
        if gp[cur]:
            return -1, 0
        if cur == goal:
            return cur, k
        if (gp[cur + side] == 0 and gp[cur + side - d] != 0) or (
            gp[cur - side] == 0 and gp[cur - side - d] != 0
        ):
            return cur, k


@njit(cache=True)
def _jump_diag(gp, w, cur, dv, dh, goal):
    """Walk diagonally (dv = ±w, dh = ±1). A cell is a jump point when it is the
    goal or a straight walk from it along either component finds one; without
    corner cutting a diagonal move has no forced neighbours of its own."""
    k = 0
    while True:
        if gp[cur + dv] or gp[cur + dh] or gp[cur + dv + dh]:
            return -1, 0
        cur += dv + dh
        k += 1
        if cur == goal:
            return cur, k
        if _jump_straight(gp, cur, dv, 1, goal)[0] >= 0:
            return cur, k
        if _jump_straight(gp, cur, dh, w, goal)[0] >= 0:
            return cur, k


@njit(cache=True)
def _relax(j, cost, cur, w, gr, gc, gen, stamp, g, parent, pos, hn, hf, hg, size):
    if j < 0:
        return size
    _touch(j, gen, stamp, g, parent, pos)
    if pos[j] == CLOSED:
        return size
    ng = g[cur] + cost
    if ng < g[j] - 1e-9:
        g[j] = ng
        parent[j] = cur
        size = _push(hn, hf, hg, pos, size, j, ng + _h(H_OCTILE, j, w, gr, gc, 1.0), ng)
    return size


@njit(cache=True)
def _sgn(x):
    return (x > 0) - (x < 0)


@njit(cache=True)
def jps_kernel(gp, w, s, goal, gen, stamp, g, parent, pos, hn, hf, hg):
    """Jump point search (seed 004's node screening; Harabor & Grastien's rules
    without corner cutting) with the octile heuristic. Returns
    (goal_reached, expanded) with expanded counting jump points."""
    gr = goal // w
    gc = goal - gr * w
    _touch(s, gen, stamp, g, parent, pos)
    g[s] = 0.0
    size = _push(hn, hf, hg, pos, 0, s, _h(H_OCTILE, s, w, gr, gc, 1.0), 0.0)
    expanded = 0
    st = (gen, stamp, g, parent, pos, hn, hf, hg)
    while size > 0:
        cur, size = _pop(hn, hf, hg, pos, size)
        expanded += 1
        if cur == goal:
            return True, expanded
        p = parent[cur]
        if p < 0:
            for d, side in ((-w, 1), (w, 1), (-1, w), (1, w)):
                j, k = _jump_straight(gp, cur, d, side, goal)
                size = _relax(j, float(k), cur, w, gr, gc, *st, size)
            for dv, dh in ((-w, -1), (-w, 1), (w, -1), (w, 1)):
                j, k = _jump_diag(gp, w, cur, dv, dh, goal)
                size = _relax(j, k * SQRT2, cur, w, gr, gc, *st, size)
            continue
        r = cur // w
        pr = p // w
        dr = _sgn(r - pr)
        dc = _sgn((cur - r * w) - (p - pr * w))
        if dr != 0 and dc != 0:
            j, k = _jump_diag(gp, w, cur, dr * w, dc, goal)
            size = _relax(j, k * SQRT2, cur, w, gr, gc, *st, size)
            j, k = _jump_straight(gp, cur, dr * w, 1, goal)
            size = _relax(j, float(k), cur, w, gr, gc, *st, size)
            j, k = _jump_straight(gp, cur, dc, w, goal)
            size = _relax(j, float(k), cur, w, gr, gc, *st, size)
        elif dr == 0:
            j, k = _jump_straight(gp, cur, dc, w, goal)
            size = _relax(j, float(k), cur, w, gr, gc, *st, size)
            for sv in (-w, w):
                if gp[cur + sv] == 0 and gp[cur + sv - dc] != 0:
                    j, k = _jump_straight(gp, cur, sv, 1, goal)
                    size = _relax(j, float(k), cur, w, gr, gc, *st, size)
                    j, k = _jump_diag(gp, w, cur, sv, dc, goal)
                    size = _relax(j, k * SQRT2, cur, w, gr, gc, *st, size)
        else:
            dv = dr * w
            j, k = _jump_straight(gp, cur, dv, 1, goal)
            size = _relax(j, float(k), cur, w, gr, gc, *st, size)
            for sh in (-1, 1):
                if gp[cur + sh] == 0 and gp[cur + sh - dv] != 0:
                    j, k = _jump_straight(gp, cur, sh, w, goal)
                    size = _relax(j, float(k), cur, w, gr, gc, *st, size)
                    j, k = _jump_diag(gp, w, cur, dv, sh, goal)
                    size = _relax(j, k * SQRT2, cur, w, gr, gc, *st, size)
    return False, expanded


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


# ---- jump point search with precomputed jump distances (JPS+) ---------------------
# table[node * 8 + k] for the eight moves k (order of DR/DC: up, down, left,
# right, then up-left, up-right, down-left, down-right), goal-independent:
#   > 0: the next jump point along k is that many steps away;
#   <= 0: no jump point before a wall; −value free steps are possible.
# A straight jump point has a forced neighbour (the rule of _jump_straight); a
# diagonal one is a cell from which a straight component reaches a jump point
# (the rule of _jump_diag). Built once per map in O(8 · cells); a query then
# replaces every scan with one lookup plus a check whether the goal lies on
# the ray (the goal is the only goal-dependent stop).


@njit(cache=True)
def build_jump_table(gp, w):
    n = gp.size
    t = np.zeros(n * 8, dtype=np.int32)
    offs = (-w, w, -1, 1)
    sides = (1, 1, w, w)
    for k in range(4):
        d = offs[k]
        side = sides[k]
        # the cell one step ahead must be done first
        if d < 0:
            lo, hi, step = 0, n, 1
        else:
            lo, hi, step = n - 1, -1, -1
        for c in range(lo, hi, step):
            if gp[c]:
                continue
            nb = c + d
            if nb < 0 or nb >= n or gp[nb]:
                t[c * 8 + k] = 0
            elif (gp[nb + side] == 0 and gp[nb + side - d] != 0) or (
                gp[nb - side] == 0 and gp[nb - side - d] != 0
            ):
                t[c * 8 + k] = 1
            else:
                j = t[nb * 8 + k]
                t[c * 8 + k] = j + 1 if j > 0 else j - 1
    for k in range(4, 8):
        dv = -w if k < 6 else w
        dh = -1 if (k % 2) == 0 else 1
        kv = 0 if dv < 0 else 1
        kh = 2 if dh < 0 else 3
        if dv < 0:
            lo, hi, step = 0, n, 1
        else:
            lo, hi, step = n - 1, -1, -1
        for c in range(lo, hi, step):
            if gp[c]:
                continue
            nb = c + dv + dh
            if nb < 0 or nb >= n or gp[c + dv] or gp[c + dh] or gp[nb]:
                t[c * 8 + k] = 0
            elif t[nb * 8 + kv] > 0 or t[nb * 8 + kh] > 0:
                t[c * 8 + k] = 1
            else:
                j = t[nb * 8 + k]
                t[c * 8 + k] = j + 1 if j > 0 else j - 1
    return t


@njit(cache=True, inline="always")
def _tj_straight(t, w, cur, k, r, c, gr, gc, goal):
    """Straight jump along move k (0..3) by table; (node, steps) or (-1, 0)."""
    gd = 0
    if k == 0:
        if gc == c and gr < r:
            gd = r - gr
    elif k == 1:
        if gc == c and gr > r:
            gd = gr - r
    elif k == 2:
        if gr == r and gc < c:
            gd = c - gc
    else:
        if gr == r and gc > c:
            gd = gc - c
    j = t[cur * 8 + k]
    if gd > 0 and gd <= abs(j):
        return goal, gd
    if j > 0:
        if k == 0:
            return cur - j * w, j
        if k == 1:
            return cur + j * w, j
        if k == 2:
            return cur - j, j
        return cur + j, j
    return -1, 0


@njit(cache=True, inline="always")
def _tj_diag(t, w, cur, k, r, c, gr, gc, goal):
    """Diagonal jump along move k (4..7) by table; (node, steps) or (-1, 0)."""
    sv = -1 if k < 6 else 1
    sh = -1 if (k % 2) == 0 else 1
    d = t[cur * 8 + k]
    reach = d if d > 0 else -d
    ddr = (gr - r) * sv
    ddc = (gc - c) * sh
    if ddr > 0 and ddc > 0:
        m = ddr if ddr < ddc else ddc
        if m <= reach and (d <= 0 or m < d):
            x = cur + m * (sv * w + sh)
            if ddr == ddc:
                return goal, m
            if ddr > ddc:
                kk = 0 if sv < 0 else 1
                rest = ddr - m
            else:
                kk = 2 if sh < 0 else 3
                rest = ddc - m
            if rest <= -t[x * 8 + kk]:
                return x, m
    if d > 0:
        return cur + d * (sv * w + sh), d
    return -1, 0


@njit(cache=True)
def jps_table_kernel(gp, t, w, s, goal, gen, stamp, g, parent, pos, hn, hf, hg, inc):
    """jps_kernel with every jump read from the precomputed table: the same
    jump points, successor order, expansions and path. inc[node] keeps the
    move that reached the node and each successor's (row, col) follows from
    the jump, so the loop needs no integer division beyond one per expansion."""
    gr = goal // w
    gc = goal - gr * w
    _touch(s, gen, stamp, g, parent, pos)
    g[s] = 0.0
    size = _push(hn, hf, hg, pos, 0, s, _h(H_OCTILE, s, w, gr, gc, 1.0), 0.0)
    expanded = 0
    succ = np.empty(8, dtype=np.int64)
    while size > 0:
        cur, size = _pop(hn, hf, hg, pos, size)
        expanded += 1
        if cur == goal:
            return True, expanded
        r = cur // w
        c = cur - r * w
        ns = 0
        if parent[cur] < 0:
            for k in range(8):
                succ[k] = k
            ns = 8
        else:
            k = inc[cur]
            if k >= 4:  # diagonal: itself, then its vertical and horizontal parts
                succ[0] = k
                succ[1] = 0 if k < 6 else 1
                succ[2] = 2 if (k % 2) == 0 else 3
                ns = 3
            elif k >= 2:  # horizontal, plus forced neighbours above / below
                dc = -1 if k == 2 else 1
                succ[0] = k
                ns = 1
                for sv in (-1, 1):
                    if gp[cur + sv * w] == 0 and gp[cur + sv * w - dc] != 0:
                        succ[ns] = 0 if sv < 0 else 1
                        succ[ns + 1] = (4 if sv < 0 else 6) + (0 if dc < 0 else 1)
                        ns += 2
            else:  # vertical, plus forced neighbours left / right
                dr = -1 if k == 0 else 1
                succ[0] = k
                ns = 1
                for sh in (-1, 1):
                    if gp[cur + sh] == 0 and gp[cur + sh - dr * w] != 0:
                        succ[ns] = 2 if sh < 0 else 3
                        succ[ns + 1] = (4 if dr < 0 else 6) + (0 if sh < 0 else 1)
                        ns += 2
        gcur = g[cur]
        for i in range(ns):
            k = succ[i]
            if k < 4:
                j, n = _tj_straight(t, w, cur, k, r, c, gr, gc, goal)
                cost = float(n)
            else:
                j, n = _tj_diag(t, w, cur, k, r, c, gr, gc, goal)
                cost = n * SQRT2
            if j < 0:
                continue
            _touch(j, gen, stamp, g, parent, pos)
            if pos[j] == CLOSED:
                continue
            ng = gcur + cost
            if ng < g[j] - 1e-9:
                g[j] = ng
                parent[j] = cur
                inc[j] = k
                adr = abs(r + DR[k] * n - gr)
                adc = abs(c + DC[k] * n - gc)
                if adr < adc:
                    hv = adc + (SQRT2 - 1.0) * adr
                else:
                    hv = adr + (SQRT2 - 1.0) * adc
                size = _push(hn, hf, hg, pos, size, j, ng + hv, ng)
    return False, expanded
