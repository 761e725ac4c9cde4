"""Jump point search with precomputed jump distances (JPS+, Rabin), compiled: the
jump table of a map and the search that reads every jump from it (jps.py's
:class:`JumpTable`), with exactly the jump points and paths of
_jps_kernel.jps_kernel. Conventions, heap and search state: :mod:`._grid_search`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._grid_search import CLOSED, H_OCTILE, SQRT2, _h, _pop, _push, _touch

# The eight moves: four straight, then four diagonal.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)

# table[node * 8 + k] for the eight moves k (order of DR/DC: up, down, left,
# right, then up-left, up-right, down-left, down-right), goal-independent:
#   > 0: the next jump point along k is that many steps away;
#   <= 0: no jump point before a wall; −value free steps are possible.
# A straight jump point has a forced neighbour (the rule of
# _jps_kernel._jump_straight); a diagonal one is a cell from which a straight
# component reaches a jump point (the rule of _jps_kernel._jump_diag). Built
# once per map in O(8 · cells); a query then replaces every scan with one
# lookup plus a check whether the goal lies on the ray (the goal is the only
# goal-dependent stop).


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


@njit(cache=True)
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


@njit(cache=True)
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
    """_jps_kernel.jps_kernel with every jump read from the precomputed table: the same
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
