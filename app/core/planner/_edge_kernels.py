"""Numba kernels of the optimised A* (seed 004 §2.2): exact segment validity,
the any-direction search on cell-corner nodes, and the taut refinement.

Geometry: cell (r, c) is the unit square [r, r+1) × [c, c+1). Points are held
in half-cell integer units (row2, col2) = (2·row, 2·col), so cell corners have
even coordinates and cell centres odd ones, and every test is exact integer
arithmetic. Outside the map counts as blocked.

A segment is valid when it never enters a blocked cell's interior and never
passes the single point where two blocked cells touch diagonally (a "pinched"
corner); it may run along an edge that has a free cell on at least one side.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._grid_search import CLOSED, _pop, _push, _touch


@njit(cache=True)
def _free(grid, r, c):
    h, w = grid.shape
    return 0 <= r < h and 0 <= c < w and grid[r, c] == 0


@njit(cache=True)
def corner_free_count(grid, R, C):
    return (
        int(_free(grid, R - 1, C - 1)) + int(_free(grid, R - 1, C))
        + int(_free(grid, R, C - 1)) + int(_free(grid, R, C))
    )


@njit(cache=True)
def corner_pinched(grid, R, C):
    """True when exactly the two diagonal cells around corner (R, C) are
    blocked (or exactly the other two): the path may not pass that point."""
    a = _free(grid, R - 1, C - 1)
    b = _free(grid, R - 1, C)
    c = _free(grid, R, C - 1)
    d = _free(grid, R, C)
    return (a and d and not b and not c) or (b and c and not a and not d)


@njit(cache=True)
def corner_ok(grid, R, C):
    return corner_free_count(grid, R, C) > 0 and not corner_pinched(grid, R, C)


@njit(cache=True)
def corner_convex(grid, R, C):
    """A convex corner of the blocked set: exactly one of its four cells is
    blocked. Only at such corners can a shortest path turn (the any-angle
    form of a jump point with a forced neighbour, Fig. 7)."""
    return corner_free_count(grid, R, C) == 3


@njit(cache=True)
def _sgn(x):
    return (x > 0) - (x < 0)


@njit(cache=True)
def seg_free(grid, pr, pc, qr, qc):
    """Validity of the segment P→Q (half-cell units; each endpoint a corner or
    a centre) under the rule in the module docstring."""
    dr = qr - pr
    dc = qc - pc
    if dr == 0 and dc == 0:
        if pr % 2 == 1:
            return _free(grid, pr // 2, pc // 2)
        return corner_ok(grid, pr // 2, pc // 2)
    # Along a grid line (both ends are then corners): every unit edge needs a
    # free side, every corner passed must not be pinched.
    if dr == 0 and pr % 2 == 0:
        R = pr // 2
        c0 = min(pc, qc) // 2
        c1 = max(pc, qc) // 2
        for C in range(c0, c1):
            if not (_free(grid, R - 1, C) or _free(grid, R, C)):
                return False
        for C in range(c0 + 1, c1):
            if corner_pinched(grid, R, C):
                return False
        return True
    if dc == 0 and pc % 2 == 0:
        C = pc // 2
        r0 = min(pr, qr) // 2
        r1 = max(pr, qr) // 2
        for R in range(r0, r1):
            if not (_free(grid, R, C - 1) or _free(grid, R, C)):
                return False
        for R in range(r0 + 1, r1):
            if corner_pinched(grid, R, C):
                return False
        return True
    # General case: walk the cells whose interior the segment crosses, in
    # order of the crossing parameter t (compared exactly by cross-multiplying).
    sr = _sgn(dr)
    sc = _sgn(dc)
    adr = abs(dr)
    adc = abs(dc)
    if pr % 2 == 1:
        r = (pr - 1) // 2
    else:
        r = pr // 2 if sr > 0 else pr // 2 - 1
    if pc % 2 == 1:
        c = (pc - 1) // 2
    else:
        c = pc // 2 if sc > 0 else pc // 2 - 1
    if not _free(grid, r, c):
        return False
    ynext = 2 * (r + 1) if sr > 0 else 2 * r
    xnext = 2 * (c + 1) if sc > 0 else 2 * c
    while True:
        ay = (ynext - pr) * sr  # t_y = ay / adr (inf when adr == 0)
        ax = (xnext - pc) * sc  # t_x = ax / adc
        ty_done = adr == 0 or ay >= adr
        tx_done = adc == 0 or ax >= adc
        if ty_done and tx_done:
            return True
        if ty_done:
            step = 1  # x first
        elif tx_done:
            step = 2
        else:
            lhs = ax * adr
            rhs = ay * adc
            step = 1 if lhs < rhs else (2 if lhs > rhs else 3)
        if step == 1:
            c += sc
            xnext += 2 * sc
        elif step == 2:
            r += sr
            ynext += 2 * sr
        else:
            # Through a corner: not both side cells blocked (the pinch).
            if not _free(grid, r, c + sc) and not _free(grid, r + sr, c):
                return False
            r += sr
            c += sc
            xnext += 2 * sc
            ynext += 2 * sr
        if not _free(grid, r, c):
            return False


# ---- any-direction search on corner nodes (Figs. 5–6) ------------------------------
# Node ids: corner (R, C) -> R * (W + 1) + C; the start centre is NC, the goal
# centre NC + 1 (NC = (H + 1)(W + 1)). A node's successor may take its
# grandparent as parent when the straight segment is valid (the parent rule of
# Theta*), so paths turn at any angle.

DR8 = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC8 = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@njit(cache=True)
def _d(ar, ac, br, bc):
    return math.sqrt(float((ar - br) * (ar - br) + (ac - bc) * (ac - bc)))


@njit(cache=True)
def _step_ok(grid, R, C, k):
    """Corner (R, C) to its k-th neighbour: along an edge with a free side, or
    across a free cell; the neighbour must be a usable corner."""
    dR = DR8[k]
    dC = DC8[k]
    R2 = R + dR
    C2 = C + dC
    h, w = grid.shape
    if R2 < 0 or R2 > h or C2 < 0 or C2 > w or not corner_ok(grid, R2, C2):
        return False
    if dR == 0:
        cc = C if dC > 0 else C - 1
        return _free(grid, R - 1, cc) or _free(grid, R, cc)
    if dC == 0:
        rr = R if dR > 0 else R - 1
        return _free(grid, rr, C - 1) or _free(grid, rr, C)
    return _free(grid, R if dR > 0 else R - 1, C if dC > 0 else C - 1)


@njit(cache=True)
def _relax(grid, s, t, tr2, tc2, gr2, gc2, cr, cc, gen, stamp, g, parent, pos, hn, hf, hg, size):
    """Theta*'s UpdateVertex for successor t of s (coordinates in cr/cc)."""
    _touch(t, gen, stamp, g, parent, pos)
    if pos[t] == CLOSED:
        return size
    p = parent[s]
    pr2 = cr[p]
    pc2 = cc[p]
    if p != s and seg_free(grid, pr2, pc2, tr2, tc2):
        ng = g[p] + _d(pr2, pc2, tr2, tc2)
        par = p
    else:
        ng = g[s] + _d(cr[s], cc[s], tr2, tc2)
        par = s
    if ng < g[t] - 1e-9:
        g[t] = ng
        parent[t] = par
        f = ng + _d(tr2, tc2, gr2, gc2)
        size = _push(hn, hf, hg, pos, size, t, f, ng)
    return size


@njit(cache=True)
def _relax_any(grid, s, t, tr2, tc2, gr2, gc2, cr, cc, gen, stamp, g, parent, pos, hn, hf, hg,
               size, lazy):
    if lazy:
        return _relax_lazy(s, t, tr2, tc2, gr2, gc2, cr, cc, gen, stamp, g, parent, pos,
                           hn, hf, hg, size)
    return _relax(grid, s, t, tr2, tc2, gr2, gc2, cr, cc, gen, stamp, g, parent, pos,
                  hn, hf, hg, size)


@njit(cache=True)
def _relax_lazy(s, t, tr2, tc2, gr2, gc2, cr, cc, gen, stamp, g, parent, pos, hn, hf, hg, size):
    """Lazy Theta*'s UpdateVertex: assume the grandparent sees t; the segment
    is checked once, when t is expanded (:func:`_set_vertex`)."""
    _touch(t, gen, stamp, g, parent, pos)
    if pos[t] == CLOSED:
        return size
    p = parent[s]
    ng = g[p] + _d(cr[p], cc[p], tr2, tc2)
    if ng < g[t] - 1e-9:
        g[t] = ng
        parent[t] = p
        size = _push(hn, hf, hg, pos, size, t, ng + _d(tr2, tc2, gr2, gc2), ng)
    return size


@njit(cache=True)
def _set_vertex(grid, s, sr, sc, gr, gc, W1, S, T, gen, stamp, g, parent, cr, cc, pos):
    """If the assumed parent does not see s, take the best expanded neighbour."""
    p = parent[s]
    if p == s or seg_free(grid, cr[p], cc[p], cr[s], cc[s]):
        return
    best = np.inf
    bp = -1
    if s == T:
        for dR in range(2):
            for dC in range(2):
                q = (gr + dR) * W1 + gc + dC
                if stamp[q] == gen and pos[q] == CLOSED:
                    v = g[q] + _d(cr[q], cc[q], cr[s], cc[s])
                    if v < best:
                        best = v
                        bp = q
    else:
        R = s // W1
        C = s - R * W1
        for k in range(8):
            if _step_ok(grid, R, C, k):
                q = (R + DR8[k]) * W1 + C + DC8[k]
                if stamp[q] == gen and pos[q] == CLOSED:
                    v = g[q] + _d(cr[q], cc[q], cr[s], cc[s])
                    if v < best:
                        best = v
                        bp = q
        if (R == sr or R == sr + 1) and (C == sc or C == sc + 1):
            v = _d(cr[S], cc[S], cr[s], cc[s])
            if v < best:
                best = v
                bp = S
    g[s] = best
    parent[s] = bp


@njit(cache=True)
def theta_kernel(grid, sr, sc, gr, gc, gen, stamp, g, parent, pos, hn, hf, hg, cr, cc, lazy):
    """Search from the centre of cell (sr, sc) to the centre of (gr, gc).
    Returns (found, expanded); parents in ``parent`` (ids above)."""
    h, w = grid.shape
    W1 = w + 1
    NC = (h + 1) * W1
    S = NC
    T = NC + 1
    sr2, sc2 = 2 * sr + 1, 2 * sc + 1
    gr2, gc2 = 2 * gr + 1, 2 * gc + 1
    cr[S] = sr2
    cc[S] = sc2
    cr[T] = gr2
    cc[T] = gc2
    _touch(S, gen, stamp, g, parent, pos)
    _touch(T, gen, stamp, g, parent, pos)
    g[S] = 0.0
    parent[S] = S
    if seg_free(grid, sr2, sc2, gr2, gc2):
        g[T] = _d(sr2, sc2, gr2, gc2)
        parent[T] = S
        return True, 1
    size = _push(hn, hf, hg, pos, 0, S, _d(sr2, sc2, gr2, gc2), 0.0)
    expanded = 0
    while size > 0:
        s, size = _pop(hn, hf, hg, pos, size)
        expanded += 1
        if lazy:
            _set_vertex(grid, s, sr, sc, gr, gc, W1, S, T, gen, stamp, g, parent, cr, cc, pos)
        if s == T:
            return True, expanded
        if s == S:
            for dR in range(2):
                for dC in range(2):
                    R = sr + dR
                    C = sc + dC
                    if corner_ok(grid, R, C):
                        t = R * W1 + C
                        cr[t] = 2 * R
                        cc[t] = 2 * C
                        size = _relax_any(grid, s, t, 2 * R, 2 * C, gr2, gc2, cr, cc, gen,
                                          stamp, g, parent, pos, hn, hf, hg, size, lazy)
            continue
        R = s // W1
        C = s - R * W1
        for k in range(8):
            if _step_ok(grid, R, C, k):
                R2 = R + DR8[k]
                C2 = C + DC8[k]
                t = R2 * W1 + C2
                cr[t] = 2 * R2
                cc[t] = 2 * C2
                size = _relax_any(grid, s, t, 2 * R2, 2 * C2, gr2, gc2, cr, cc, gen,
                                  stamp, g, parent, pos, hn, hf, hg, size, lazy)
        # A corner of the goal cell sees the goal centre across that free cell.
        if (R == gr or R == gr + 1) and (C == gc or C == gc + 1):
            size = _relax_any(grid, s, T, gr2, gc2, gr2, gc2, cr, cc, gen,
                              stamp, g, parent, pos, hn, hf, hg, size, lazy)
    return False, expanded


@njit(cache=True)
def trace(parent, cr, cc, S, T):
    n = 1
    v = T
    while v != S:
        v = parent[v]
        n += 1
    out = np.empty((n, 2), dtype=np.int64)
    v = T
    for i in range(n - 1, -1, -1):
        out[i, 0] = cr[v]
        out[i, 1] = cc[v]
        v = parent[v]
    return out


# ---- taut refinement --------------------------------------------------------------------


@njit(cache=True)
def _cross(ar, ac, br, bc, pr, pc):
    """z of (B − A) × (P − A) in (col, row) order; > 0: P left of A→B."""
    return (bc - ac) * (pr - ar) - (br - ar) * (pc - ac)


@njit(cache=True)
def drop_vertices(grid, pts):
    """Remove each vertex whose neighbours see each other (string pulling)."""
    n = pts.shape[0]
    keep = np.ones(n, dtype=np.bool_)
    last = 0
    for i in range(1, n - 1):
        if seg_free(grid, pts[last, 0], pts[last, 1], pts[i + 1, 0], pts[i + 1, 1]):
            keep[i] = False
        else:
            last = i
    return pts[keep]


@njit(cache=True)
def hull_chain(grid, a, v, b, screen):
    """The shortest path from a to b homotopic to a→v→b: the convex chain, on
    v's side of ab, over the blocked-cell corners inside triangle (a, v, b).
    With ``screen`` only convex corners (jump corners) are candidates.
    Returns the interior chain vertices (k × 2, half-cell units)."""
    side = _cross(a[0], a[1], b[0], b[1], v[0], v[1])
    if side == 0:
        return np.empty((0, 2), dtype=np.int64)
    sg = 1 if side > 0 else -1
    h, w = grid.shape
    R0 = max(0, min(a[0], v[0], b[0]) // 2)
    R1 = min(h, (max(a[0], v[0], b[0]) + 1) // 2)
    C0 = max(0, min(a[1], v[1], b[1]) // 2)
    C1 = min(w, (max(a[1], v[1], b[1]) + 1) // 2)
    cap = (R1 - R0 + 1) * (C1 - C0 + 1)
    cand = np.empty((cap, 2), dtype=np.int64)
    m = 0
    for R in range(R0, R1 + 1):
        for C in range(C0, C1 + 1):
            nf = corner_free_count(grid, R, C)
            if nf == 4 or nf == 0 or (screen and nf != 3):
                continue
            # A corner constrains the chain only when one of its blocked cells
            # reaches into the triangle there: test a point just inside each
            # blocked cell (coordinates × 8, offset one unit along the diagonal).
            hit = False
            for q in range(4):
                qr = q // 2
                qc = q % 2
                if _free(grid, R - 1 + qr, C - 1 + qc):
                    continue
                pr = 16 * R + 2 * qr - 1
                pc = 16 * C + 2 * qc - 1
                s1 = _cross(8 * a[0], 8 * a[1], 8 * b[0], 8 * b[1], pr, pc) * sg
                s2 = _cross(8 * b[0], 8 * b[1], 8 * v[0], 8 * v[1], pr, pc) * sg
                s3 = _cross(8 * v[0], 8 * v[1], 8 * a[0], 8 * a[1], pr, pc) * sg
                if s1 > 0 and s2 > 0 and s3 > 0:
                    hit = True
                    break
            if hit:
                cand[m, 0] = 2 * R
                cand[m, 1] = 2 * C
                m += 1
    if m == 0:
        return np.empty((0, 2), dtype=np.int64)
    # Gift wrapping from a to b: each edge keeps every candidate on the ab side
    # (the chain bulges towards v just enough to enclose the corners).
    chain = np.empty((m + 1, 2), dtype=np.int64)
    k = 0
    cr_ = a[0]
    cc_ = a[1]
    for _ in range(m + 1):
        br_ = b[0]
        bc_ = b[1]
        for i in range(m):
            pr = cand[i, 0]
            pc = cand[i, 1]
            if pr == cr_ and pc == cc_:
                continue
            x = _cross(cr_, cc_, br_, bc_, pr, pc) * sg
            if x > 0:
                br_ = pr
                bc_ = pc
            elif x == 0:
                d1 = (pr - cr_) * (br_ - cr_) + (pc - cc_) * (bc_ - cc_)
                far = (pr - cr_) ** 2 + (pc - cc_) ** 2 > (br_ - cr_) ** 2 + (bc_ - cc_) ** 2
                if d1 > 0 and far:
                    br_ = pr
                    bc_ = pc
        if br_ == b[0] and bc_ == b[1]:
            break
        chain[k, 0] = br_
        chain[k, 1] = bc_
        k += 1
        cr_ = br_
        cc_ = bc_
    return chain[:k].copy()


@njit(cache=True)
def path_len(pts):
    s = 0.0
    for i in range(pts.shape[0] - 1):
        s += _d(pts[i, 0], pts[i, 1], pts[i + 1, 0], pts[i + 1, 1])
    return s


@njit(cache=True)
def tauten(grid, pts, screen, max_passes):
    """Replace every vertex by the taut chain of its triangle until a pass
    shortens nothing (each replacement is kept only when all its segments are
    valid and it is shorter)."""
    for _ in range(max_passes):
        changed = False
        i = 1
        while i < pts.shape[0] - 1:
            a = pts[i - 1]
            v = pts[i]
            b = pts[i + 1]
            ch = hull_chain(grid, a, v, b, screen)
            new = np.empty((ch.shape[0] + 2, 2), dtype=np.int64)
            new[0] = a
            new[1:-1] = ch
            new[-1] = b
            old_len = _d(a[0], a[1], v[0], v[1]) + _d(v[0], v[1], b[0], b[1])
            ok = path_len(new) < old_len - 1e-9
            if ok:
                for j in range(new.shape[0] - 1):
                    if not seg_free(grid, new[j, 0], new[j, 1], new[j + 1, 0], new[j + 1, 1]):
                        ok = False
                        break
            if ok:
                out = np.empty((pts.shape[0] + ch.shape[0] - 1, 2), dtype=np.int64)
                out[:i] = pts[:i]
                out[i:i + ch.shape[0]] = ch
                out[i + ch.shape[0]:] = pts[i + 1:]
                pts = out
                changed = True
                i += max(ch.shape[0], 1)
            else:
                i += 1
        if not changed:
            break
    return pts
