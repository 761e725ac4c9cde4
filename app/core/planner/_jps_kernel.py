"""Jump point search by byte-by-byte scans, compiled (seed 004's node screening;
Harabor & Grastien's rules without corner cutting). The reference the faster
searches are checked against: JPS+ (_jps_table_kernel.py) and JPS-B (_jps_bits.py)
find exactly its jump points. Conventions, heap and search state:
:mod:`._grid_search`.
"""

from __future__ import annotations

from numba import njit

from ._grid_search import CLOSED, H_OCTILE, SQRT2, _h, _pop, _push, _sgn, _touch


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
