"""Fewer turns with the same visits: moving stretches of a coverage path.

The or-opt move of tour improvement (Or 1976), with the turn count as the
cost (seed 001 eq. 3: every turn leaves S_UR of wall unprobed). A stretch
p_i … p_j is cut out when its neighbours still join (p_{i−1} next to
p_{j+1}) and put back between p_k and p_{k+1}, forwards (p_k next to p_i,
p_j next to p_{k+1}) or reversed (p_k next to p_j, p_i next to p_{k+1}).
The multiset of visited cells does not change, so coverage and repetition
(Definition 7) stay exactly as they were; the move is taken when the turns
at the two cuts and the two joins fall. Where 2-opt (:mod:`.untwist`) only
turns a stretch round in place, this carries a short lane left behind by
the walker to the lane it continues. "Next to" is an 8-neighbour move
without corner cutting; no wrap (the public face does not wrap).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _move_ok, _t

DR8 = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC8 = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@njit(cache=True)
def _index(path, n, first, nxt):
    """first[cell]: a position of the cell in path (−1: none); nxt[pos]: the
    next position of the same cell (−1: none)."""
    for k in range(n):
        first[path[k]] = -1
    for k in range(n - 1, -1, -1):
        nxt[k] = first[path[k]]
        first[path[k]] = k


@njit(cache=True)
def _gain(path, n, w, i, j, k, rev):
    """Turns removed by moving p_i … p_j between p_k and p_{k+1} (reversed
    when rev); both cuts lie inside the path (1 ≤ i, j ≤ n − 2, k + 1 ≤ n − 1)
    and k ∉ [i − 2, j + 1]."""
    a, b = path[i - 1], path[j + 1]
    pa = path[i - 2] if i >= 2 else -1
    nb = path[j + 2] if j + 2 < n else -1
    pk = path[k - 1] if k >= 1 else -1
    x, y = path[k], path[k + 1]
    ny = path[k + 2] if k + 2 < n else -1
    si, sj = path[i], path[j]
    ii = path[i + 1] if i < j else y  # inner neighbour of p_i in the stretch
    jj = path[j - 1] if i < j else x
    old = _t(pa, a, si, w) + _t(sj, b, nb, w) + _t(pk, x, y, w) + _t(x, y, ny, w)
    old += _t(a, si, path[i + 1], w)
    if i < j:
        old += _t(path[j - 1], sj, b, w)
    new = _t(pa, a, b, w) + _t(a, b, nb, w)
    if not rev:
        if i < j:
            new += _t(pk, x, si, w) + _t(x, si, ii, w) + _t(jj, sj, y, w) + _t(sj, y, ny, w)
        else:
            new += _t(pk, x, si, w) + _t(x, si, y, w) + _t(si, y, ny, w)
    else:
        if i < j:
            new += _t(pk, x, sj, w) + _t(x, sj, path[j - 1], w)
            new += _t(path[i + 1], si, y, w) + _t(si, y, ny, w)
        else:
            new += _t(pk, x, si, w) + _t(x, si, y, w) + _t(si, y, ny, w)
    return old - new


@njit(cache=True)
def _apply(path, n, i, j, k, rev, out):
    """Write the moved path into out, then back into path."""
    m = 0
    for q in range(n):
        if i <= q <= j:
            continue
        out[m] = path[q]
        m += 1
        if q == k:
            if rev:
                for s in range(j, i - 1, -1):
                    out[m] = path[s]
                    m += 1
            else:
                for s in range(i, j + 1):
                    out[m] = path[s]
                    m += 1
    path[:n] = out[:n]


@njit(cache=True)
def relocate(free, path, max_len, passes):
    """Move stretches of up to ``max_len`` cells of ``path`` (flat cell
    indices, changed in place) while that removes turns; returns the number
    of turns removed."""
    h, w = free.shape
    n = path.shape[0]
    first = np.full(h * w, -1, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    out = np.empty(n, dtype=np.int64)
    _index(path, n, first, nxt)
    gained = 0
    for _ in range(passes):
        changed = False
        i = 1
        while i < n - 1:
            moved = False
            for j in range(i, min(n - 2, i + max_len - 1) + 1):
                if not _move_ok(free, path[i - 1], path[j + 1], w):
                    continue
                best, bk, brev = 0, -1, False
                for end in range(2):  # 0: p_k next to p_i (forwards); 1: next to p_j
                    s = path[i] if end == 0 else path[j]
                    sr, sc = s // w, s % w
                    for d in range(8):
                        qr, qc = sr + DR8[d], sc + DC8[d]
                        if qr < 0 or qr >= h or qc < 0 or qc >= w or free[qr, qc] == 0:
                            continue
                        k = first[qr * w + qc]
                        while k >= 0:
                            if (k < i - 2 or k > j + 1) and k + 1 < n:
                                rev = end == 1
                                tail = path[i] if rev else path[j]
                                if _move_ok(free, path[k], s, w) and _move_ok(
                                    free, tail, path[k + 1], w
                                ):
                                    g = _gain(path, n, w, i, j, k, rev)
                                    if g > best:
                                        best, bk, brev = g, k, rev
                            k = nxt[k]
                if best > 0:
                    _apply(path, n, i, j, bk, brev, out)
                    _index(path, n, first, nxt)
                    gained += best
                    changed = True
                    moved = True
                    break
            if not moved:
                i += 1
        if not changed:
            break
    return gained
