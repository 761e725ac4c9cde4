"""Fewer turns with the same visits: 2-opt reversals of a coverage path.

A coverage path p_0 … p_{n−1} may have a stretch p_i … p_j reversed when
the ends still join: p_{i−1} next to p_j and p_i next to p_{j+1} (8-adjacent,
no corner cutting), or j = n − 1 (the tail). The cells and how often each
is visited do not change, so coverage and repetition (Definition 7) stay
exactly as they were; only the changes of heading move. Inside the reversed
stretch every step is negated, so its turns stay; only the four cells at the
two joins can gain or lose a turn, and a reversal is taken when they lose.

This is the classic 2-opt move of tour improvement, applied with the turn
count (seed 001 eq. 3: every turn leaves S_UR of wall unprobed) as the
cost. It lifts the low-repetition walks of :mod:`._kernels` towards
boustrophedon-like lanes: a stretch swept the "wrong" way round is turned
into a straight continuation. No wrap (the public face does not wrap).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _heading_change, _move_ok

DR8 = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC8 = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@njit(cache=True, inline="always")
def _turn(path, n, w, k, prev, nxt):
    """1 when the path turns at p_k coming from cell prev and going to nxt
    (−1 = no such cell: path end)."""
    if prev < 0 or nxt < 0:
        return 0
    return 1 if _heading_change(prev, path[k], nxt, w) else 0


@njit(cache=True)
def _reverse(path, pos, count, i, j):
    a, b = i, j
    while a < b:
        t = path[a]
        path[a] = path[b]
        path[b] = t
        a += 1
        b -= 1
    for k in range(i, j + 1):
        if count[path[k]] == 1:
            pos[path[k]] = k


@njit(cache=True)
def two_opt(free, path, passes):
    """Reverse stretches of ``path`` (flat cell indices, modified in place)
    while that removes turns; returns the number of turns removed. Only
    cells visited once are taken as the far end p_j of a stretch."""
    h, w = free.shape
    n = path.shape[0]
    count = np.zeros(h * w, dtype=np.int64)
    pos = np.full(h * w, -1, dtype=np.int64)
    for k in range(n):
        count[path[k]] += 1
    for k in range(n):
        if count[path[k]] == 1:
            pos[path[k]] = k
    gained = 0
    for _ in range(passes):
        changed = False
        for i in range(1, n - 1):
            a = path[i - 1]
            ar, ac = a // w, a % w
            pa = path[i - 2] if i >= 2 else -1
            for d in range(8):
                qr, qc = ar + DR8[d], ac + DC8[d]
                if qr < 0 or qr >= h or qc < 0 or qc >= w or free[qr, qc] == 0:
                    continue
                q = qr * w + qc
                j = pos[q]
                if j <= i or count[q] != 1 or not _move_ok(free, a, q, w):
                    continue
                after = path[j + 1] if j + 1 < n else -1
                if after >= 0 and not _move_ok(free, path[i], after, w):
                    continue
                after2 = path[j + 2] if j + 2 < n else -1
                old = (
                    _turn(path, n, w, i - 1, pa, path[i])
                    + _turn(path, n, w, i, path[i - 1], path[i + 1])
                    + _turn(path, n, w, j, path[j - 1], after)
                    + (_turn(path, n, w, j + 1, path[j], after2) if after >= 0 else 0)
                )
                new = (
                    _turn(path, n, w, i - 1, pa, q)
                    + _turn(path, n, w, j, a, path[j - 1])
                    + _turn(path, n, w, i, path[i + 1], after)
                    + (_turn(path, n, w, j + 1, path[i], after2) if after >= 0 else 0)
                )
                if new < old:
                    _reverse(path, pos, count, i, j)
                    gained += old - new
                    changed = True
                    break
        if not changed:
            break
    return gained
