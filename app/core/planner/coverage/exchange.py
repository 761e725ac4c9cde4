"""Fewer turns with the same visits: two neighbouring stretches exchanged.

The segment-exchange (3-opt) move of tour improvement, with the turn count
as the cost (seed 001 eq. 3: every turn leaves S_UR of wall unprobed). The
path A · B · C · D, with B = p_i … p_j and C = p_{j+1} … p_k (each at least
two cells, of any length), becomes one of

- A · C · B · D     (p_{i−1}→p_{j+1}, p_k→p_i, p_j→p_{k+1}),
- A · C · B' · D    (p_{i−1}→p_{j+1}, p_k→p_j, p_i→p_{k+1}),
- A · C' · B · D    (p_{i−1}→p_k, p_{j+1}→p_i, p_j→p_{k+1}),
- A · B' · C' · D   (p_{i−1}→p_j, p_i→p_k, p_{j+1}→p_{k+1}),

(' = reversed) when the three joins are moves (8-adjacent, no corner
cutting) and the turns at the six cells beside them fall. The remaining
reorders of the two stretches are 2-opt reversals (:mod:`.untwist`), and
:mod:`.relocate` moves only stretches of up to 30 cells; here both may be
whole groups of lanes, so a lane tour's order is repaired where no
short move reaches. Inside a stretch every step is kept or negated, so its
turns stay; the multiset of visited cells does not change, so coverage and
repetition (Definition 7) stay exactly as they were. No wrap (the public
face does not wrap).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _move_ok, _t
from .relocate import DC8, DR8, _index


@njit(cache=True)
def _at(path, n, k):
    return path[k] if 0 <= k < n else -1


@njit(cache=True)
def _gain(path, n, w, i, j, k, kind):
    """Turns removed by the exchange ``kind`` (0: A C B D, 1: A C B' D,
    2: A C' B D, 3: A B' C' D) of B = p_i … p_j and C = p_{j+1} … p_k."""
    old = 0
    for q in (i - 1, i, j, j + 1, k, k + 1):
        if q >= n:
            continue
        old += _t(_at(path, n, q - 1), path[q], _at(path, n, q + 1), w)
    # each stretch as (first, second, second-last, last) in its new direction
    bf, bs, bt, bl = path[i], path[i + 1], path[j - 1], path[j]
    cf, cs, ct, cl = path[j + 1], path[j + 2], path[k - 1], path[k]
    if kind == 1 or kind == 3:
        bf, bs, bt, bl = bl, bt, bs, bf
    if kind == 2 or kind == 3:
        cf, cs, ct, cl = cl, ct, cs, cf
    if kind == 3:  # B' first, then C'
        f1, s1, t1, l1, f2, s2, t2, l2 = bf, bs, bt, bl, cf, cs, ct, cl
    else:  # C (or C') first, then B (or B')
        f1, s1, t1, l1, f2, s2, t2, l2 = cf, cs, ct, cl, bf, bs, bt, bl
    pa, a = _at(path, n, i - 2), path[i - 1]
    d, nd = _at(path, n, k + 1), _at(path, n, k + 2)
    new = _t(pa, a, f1, w) + _t(a, f1, s1, w) + _t(t1, l1, f2, w) + _t(l1, f2, s2, w)
    new += _t(t2, l2, d, w) + _t(l2, d, nd, w)
    return old - new


@njit(cache=True)
def _joins(free, path, n, w, i, j, k, kind):
    """Are the three new joins of exchange ``kind`` moves? (p_{k+1} may be
    past the end: no third join.)"""
    a, d = path[i - 1], _at(path, n, k + 1)
    if kind == 0:
        x, y, z = path[j + 1], path[k], path[i]
        last = path[j]
    elif kind == 1:
        x, y, z = path[j + 1], path[k], path[j]
        last = path[i]
    elif kind == 2:
        x, y, z = path[k], path[j + 1], path[i]
        last = path[j]
    else:
        x, y, z = path[j], path[i], path[k]
        last = path[j + 1]
    if not _move_ok(free, a, x, w) or not _move_ok(free, y, z, w):
        return False
    return d < 0 or _move_ok(free, last, d, w)


@njit(cache=True)
def _apply(path, n, i, j, k, kind, out):
    m = 0
    for q in range(i):
        out[m] = path[q]
        m += 1
    if kind == 3:
        for q in range(j, i - 1, -1):
            out[m] = path[q]
            m += 1
        for q in range(k, j, -1):
            out[m] = path[q]
            m += 1
    else:
        if kind == 2:
            for q in range(k, j, -1):
                out[m] = path[q]
                m += 1
        else:
            for q in range(j + 1, k + 1):
                out[m] = path[q]
                m += 1
        if kind == 1:
            for q in range(j, i - 1, -1):
                out[m] = path[q]
                m += 1
        else:
            for q in range(i, j + 1):
                out[m] = path[q]
                m += 1
    for q in range(k + 1, n):
        out[m] = path[q]
        m += 1
    path[:n] = out[:n]


# rows of improving exchanges at one i that _best_at can hold: every (first
# join, second join, kind) at most once, a cell visited at most 4 times
MOVES_AT_MOST = 8 * 4 * 4 * 8 * 4


@njit(cache=True)
def _best_at(free, path, n, w, i, first, nxt, buf):
    """The exchange with B starting at p_i that removes the most turns:
    (gain, j, k, kind); gain 0 when none removes any. :func:`moves_at`'s
    rows with a gain of 1 or more (``buf``: room for them), the first of the
    largest gain."""
    m = moves_at(free, path, n, w, i, first, nxt, buf, 1)
    best, bj, bk, bkind = 0, -1, -1, -1
    for r in range(m):
        if buf[r, 3] > best:
            best, bj, bk, bkind = buf[r, 3], buf[r, 0], buf[r, 1], buf[r, 2]
    return best, bj, bk, bkind


@njit(cache=True)
def exchange(free, path, passes):
    """Exchange neighbouring stretches of ``path`` (flat cell indices,
    changed in place) while that removes turns (see the module); returns
    the number of turns removed."""
    w = free.shape[1]
    n = path.shape[0]
    first = np.full(free.size, -1, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    out = np.empty(n, dtype=np.int64)
    buf = np.empty((MOVES_AT_MOST, 4), dtype=np.int64)
    _index(path, n, first, nxt)
    gained = 0
    for _ in range(passes):
        changed = False
        for i in range(1, n - 3):
            g, j, k, kind = _best_at(free, path, n, w, i, first, nxt, buf)
            if g > 0:
                _apply(path, n, i, j, k, kind, out)
                _index(path, n, first, nxt)
                gained += g
                changed = True
        if not changed:
            break
    return gained


@njit(cache=True)
def moves_at(free, path, n, w, i, first, nxt, out, floor):
    """Every exchange with B starting at p_i whose gain is at least
    ``floor`` (may be negative: a kick), written as rows (j, k, kind, gain)
    into ``out`` (as many as fit; in the order they are found); returns how
    many were written. The first join fixes where C (or B') starts among the
    neighbours of p_{i−1}; the second where the other stretch's far end lies
    among the neighbours of the cell it joins; the third is then tested."""
    h = free.shape[0]
    m, j = 0, -1
    a = path[i - 1]
    ar, ac = a // w, a % w
    for d1 in range(8):
        qr, qc = ar + DR8[d1], ac + DC8[d1]
        if qr < 0 or qr >= h or qc < 0 or qc >= w or free[qr, qc] == 0:
            continue
        p = first[qr * w + qc]
        while p >= 0:
            if p > i:
                for kind in range(4):
                    # kind 0/1: p = j + 1 (C starts there); 2: p = k (C' starts
                    # there); 3: p = j (B' starts there)
                    if kind <= 1:
                        j = p - 1
                        pivot = path[i] if kind == 0 else path[j]  # joins p_k
                    elif kind == 2:
                        pivot = path[i]  # joins p_{j+1}
                    else:
                        j = p
                        pivot = path[i]  # joins p_k
                    pr, pc = pivot // w, pivot % w
                    for d2 in range(8):
                        sr, sc = pr + DR8[d2], pc + DC8[d2]
                        if sr < 0 or sr >= h or sc < 0 or sc >= w or free[sr, sc] == 0:
                            continue
                        q = first[sr * w + sc]
                        while q >= 0:
                            if kind == 2:
                                k, j = p, q - 1
                            else:
                                k = q
                            ok = j >= i + 1 and k >= j + 2
                            if ok and _joins(free, path, n, w, i, j, k, kind):
                                g = _gain(path, n, w, i, j, k, kind)
                                if g >= floor and m < out.shape[0]:
                                    out[m, 0], out[m, 1], out[m, 2], out[m, 3] = j, k, kind, g
                                    m += 1
                            q = nxt[q]
            p = nxt[p]
    return m
