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

from ._kernels import _step_ok

DR8 = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC8 = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@njit(cache=True)
def _turn(rows, cols, b, prev, nxt):
    """1 when the path turns at cell b coming from cell prev and going to
    nxt (−1 = no such cell: path end); rows/cols: each flat cell's row and
    column, looked up (a division per coordinate costs more than the rest
    of the test)."""
    if prev < 0 or nxt < 0:
        return 0
    rb, cb = rows[b], cols[b]
    if rb - rows[prev] != rows[nxt] - rb or cb - cols[prev] != cols[nxt] - cb:
        return 1
    return 0


@njit(cache=True)
def move_masks(free):
    """Each flat cell's valid moves as 8 bits (bit d: the move DR8[d],
    DC8[d] stays on free cells and cuts no corner); 0 on blocked cells."""
    h, w = free.shape
    out = np.zeros(h * w, dtype=np.int64)
    for r in range(h):
        for c in range(w):
            if free[r, c] == 0:
                continue
            m = 0
            for d in range(8):
                if _step_ok(free, r, c, DR8[d], DC8[d], False) >= 0:
                    m |= 1 << d
            out[r * w + c] = m
    return out


# Index d of the move (dr, dc) in DR8/DC8, at [dr + 1, dc + 1]; −1: no move.
_DIR = np.array([[4, 0, 5], [2, -1, 3], [6, 1, 7]], dtype=np.int64)


@njit(cache=True)
def _joined(moves, rows, cols, a, b):
    """True when b is one valid move from a (:func:`move_masks`)."""
    dr, dc = rows[b] - rows[a], cols[b] - cols[a]
    if dr < -1 or dr > 1 or dc < -1 or dc > 1:
        return False
    d = _DIR[dr + 1, dc + 1]
    return d >= 0 and (moves[a] >> d) & 1 == 1


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
def _touch(path, count, moves, w, i0, j0, ev, dirty_at, checked_at):
    """After reversing p_i0 … p_j0: the checks that may now find a move are
    due again (see :func:`two_opt_masked`)."""
    n = path.shape[0]
    for t in range(max(1, i0 - 1), min(n, j0 + 3)):
        checked_at[t] = -1
    for t in range(max(0, i0 - 2), min(n, j0 + 2)):
        y = path[t]
        if count[y] != 1:
            continue
        my = moves[y]
        for e in range(8):
            if (my >> e) & 1:
                dirty_at[y + DR8[e] * w + DC8[e]] = ev


@njit(cache=True)
def two_opt(free, path, passes):
    """Reverse stretches of ``path`` (flat cell indices, modified in place)
    while that removes turns; returns the number of turns removed. Only
    cells visited once are taken as the far end p_j of a stretch."""
    return two_opt_masked(free, move_masks(free), path, passes)


@njit(cache=True)
def two_opt_masked(free, moves, path, passes):
    """:func:`two_opt` with the map's :func:`move_masks` given (built once per
    map by a caller that untwists many paths).

    Each pass looks at every i in order, as the plain sweep does, but skips
    a check whose inputs no reversal has touched since it last found
    nothing: a check at i reads p_{i−2} … p_{i+1} and, for each once-visited
    neighbour q of p_{i−1}, q's position j and p_{j−1} … p_{j+2}. So after
    reversing p_i0 … p_j0 the checks at i0 − 1 … j0 + 2 are due again, and
    so are those whose p_{i−1} neighbours a once-visited cell now at
    i0 − 2 … j0 + 1 (moves are symmetric): ``dirty_at`` keeps, per cell, the
    last reversal near it, ``checked_at``, per position, when it was last
    checked (−1: due). The same reversals in the same order: the same path."""
    h, w = free.shape
    n = path.shape[0]
    count = np.zeros(h * w, dtype=np.int64)
    pos = np.full(h * w, -1, dtype=np.int64)
    for k in range(n):
        count[path[k]] += 1
    for k in range(n):
        if count[path[k]] == 1:
            pos[path[k]] = k
    rows = np.arange(h * w) // w
    cols = np.arange(h * w) % w
    dirty_at = np.zeros(h * w, dtype=np.int64)
    checked_at = np.full(n, -1, dtype=np.int64)
    ev = 0
    gained = 0
    for _ in range(passes):
        changed = False
        for i in range(1, n - 1):
            a = path[i - 1]
            if checked_at[i] >= 0 and dirty_at[a] <= checked_at[i]:
                continue  # nothing it reads has changed since it found nothing
            checked_at[i] = ev
            ma = moves[a]
            if ma == 0:
                continue
            pa = path[i - 2] if i >= 2 else -1
            for d in range(8):
                if not (ma >> d) & 1:
                    continue
                q = a + DR8[d] * w + DC8[d]
                j = pos[q]
                if j <= i or count[q] != 1:
                    continue
                after = path[j + 1] if j + 1 < n else -1
                if after >= 0 and not _joined(moves, rows, cols, path[i], after):
                    continue
                after2 = path[j + 2] if j + 2 < n else -1
                old = (
                    _turn(rows, cols, a, pa, path[i])
                    + _turn(rows, cols, path[i], a, path[i + 1])
                    + _turn(rows, cols, path[j], path[j - 1], after)
                    + (_turn(rows, cols, after, path[j], after2) if after >= 0 else 0)
                )
                if old == 0:  # nothing to remove here
                    continue
                new = (
                    _turn(rows, cols, a, pa, q)
                    + _turn(rows, cols, path[j], a, path[j - 1])
                    + _turn(rows, cols, path[i], path[i + 1], after)
                    + (_turn(rows, cols, after, path[i], after2) if after >= 0 else 0)
                )
                if new < old:
                    _reverse(path, pos, count, i, j)
                    ev += 1
                    _touch(path, count, moves, w, i, j, ev, dirty_at, checked_at)
                    gained += old - new
                    changed = True
                    break
        if not changed:
            break
    return gained
