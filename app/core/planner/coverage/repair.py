"""Repeats traded for turns: bringing a low-turn path within a repetition cap.

A lane tour (:mod:`.lanes`) turns little but repeats cells where its links
cannot reach the next lane in one step. The commonest case is a staircase
edge (a disc or a diagonal bar rasterised): a lane's last cell x has its
only free neighbours behind it and above it, so the link steps back over
the cell before it, p_{k−1} x p_{k−1} — a spike. :func:`repair` removes
repeats one at a time, always the one that costs the fewest added changes
of heading per repeat removed (seed 001 eq. 3: every turn leaves S_UR of
wall unprobed; Definition 7: every repeat is repetition), until at most
``target`` repeated visits are left. The moves:

- drop: a visit p_k of a cell visited elsewhere too, when p_{k−1} and
  p_{k+1} join (one repeat fewer);
- spike: p_{k−1} x p_{k−1} becomes p_{k−1} (one repeat fewer); when x is
  visited nowhere else it is put back between two consecutive cells p_j,
  p_{j+1} that both join it — a dip into the cell from a lane that passes
  beside it — where that adds the fewest turns; when x is visited
  elsewhere too, two repeats go.

"Join" is an 8-neighbour move without corner cutting, so the path stays
valid; every cell stays visited, so coverage stays complete; the first cell
stays first. No wrap (the public face does not wrap).
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
def _drop_cost(path, n, w, k):
    """Turns added by dropping p_k (p_{k−1} and p_{k+1} join, or k is last)."""
    a, x = path[k - 1], path[k]
    pa, y, ny = _at(path, n, k - 2), _at(path, n, k + 1), _at(path, n, k + 2)
    if y < 0:
        return -_t(pa, a, x, w)
    old = _t(pa, a, x, w) + _t(a, x, y, w) + _t(x, y, ny, w)
    return _t(pa, a, y, w) + _t(a, y, ny, w) - old


@njit(cache=True)
def _spike_cost(path, n, w, k):
    """Turns added by cutting p_k and p_{k+1} (= p_{k−1}) out of the path."""
    p3, p2, a = _at(path, n, k - 3), _at(path, n, k - 2), path[k - 1]
    x, b = path[k], path[k + 1]
    q2, q3 = _at(path, n, k + 2), _at(path, n, k + 3)
    old = _t(p3, p2, a, w) + _t(p2, a, x, w) + _t(a, x, b, w) + _t(x, b, q2, w)
    old += _t(b, q2, q3, w)
    new = _t(p3, p2, a, w) + _t(p2, a, q2, w) + _t(a, q2, q3, w)
    return new - old


@njit(cache=True)
def _best_insert(free, path, n, w, x, k, first, nxt):
    """Cheapest place (turns added, j) to put x between p_j and p_{j+1} (or
    after the last cell), away from the spike at k; (big, −1) when none."""
    h = free.shape[0]
    best, bj = 1 << 30, -1
    xr, xc = x // w, x % w
    for d in range(8):
        qr, qc = xr + DR8[d], xc + DC8[d]
        if qr < 0 or qr >= h or qc < 0 or qc >= w or free[qr, qc] == 0:
            continue
        q = qr * w + qc
        if not _move_ok(free, q, x, w):
            continue
        j = first[q]
        while j >= 0:
            if j <= k - 4 or j >= k + 3:
                y = _at(path, n, j + 1)
                if y < 0 or _move_ok(free, x, y, w):
                    pj, ny = _at(path, n, j - 1), _at(path, n, j + 2)
                    old = _t(pj, q, y, w) + _t(q, y, ny, w)
                    new = _t(pj, q, x, w) + _t(q, x, y, w) + _t(x, y, ny, w)
                    if new - old < best:
                        best, bj = new - old, j
            j = nxt[j]
    return best, bj


@njit(cache=True)
def _apply(path, n, kind, k, j, out):
    """Write the changed path into out; returns its length. kind 0: drop p_k;
    1: cut the spike p_k p_{k+1}; 2: the same, x put back after p_j."""
    x = path[k]
    m = 0
    for q in range(n):
        if q == k or (kind >= 1 and q == k + 1):
            continue
        out[m] = path[q]
        m += 1
        if kind == 2 and q == j:
            out[m] = x
            m += 1
    return m


@njit(cache=True)
def repair(free, path, target, max_moves):
    """The path with at most ``target`` repeated visits (or as few as the
    moves reach), each move the one adding the fewest turns per repeat
    removed; moves that remove turns too are taken regardless of target.
    Returns a new array."""
    w = free.shape[1]
    cur = path.copy()
    n = len(cur)
    out = np.empty(n, dtype=np.int64)
    count = np.zeros(free.size, dtype=np.int64)
    for v in cur:
        count[v] += 1
    repeats = n - np.count_nonzero(count)
    first = np.full(free.size, -1, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    for _ in range(max_moves):
        _index(cur, n, first, nxt)
        best, bkind, bk, bj, bgain = 1e18, -1, -1, -1, 0
        for k in range(1, n):
            x = cur[k]
            if count[x] > 1 and (k == n - 1 or _move_ok(free, cur[k - 1], cur[k + 1], w)):
                c = _drop_cost(cur, n, w, k)
                if c < best:
                    best, bkind, bk, bj, bgain = c, 0, k, -1, 1
            if k + 1 < n and cur[k + 1] == cur[k - 1]:
                c = _spike_cost(cur, n, w, k)
                if count[x] > 1:
                    if c / 2.0 < best:
                        best, bkind, bk, bj, bgain = c / 2.0, 1, k, -1, 2
                else:
                    add, j = _best_insert(free, cur, n, w, x, k, first, nxt)
                    if j >= 0 and c + add < best:
                        best, bkind, bk, bj, bgain = c + add, 2, k, j, 1
        if bkind < 0 or (repeats <= target and best >= 0):
            break
        count[cur[bk]] -= 1
        if bkind >= 1:
            count[cur[bk + 1]] -= 1
        if bkind == 2:
            count[cur[bk]] += 1
        n = _apply(cur, n, bkind, bk, bj, out)
        cur[:n] = out[:n]
        repeats -= bgain
    return cur[:n].copy()
