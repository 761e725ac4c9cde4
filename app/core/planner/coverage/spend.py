"""Repeats spent for turns: a plan under its repetition cap turns less.

best_plan keeps the plan with the fewest changes of heading among those
whose repetition (Definition 7) is within the cap, and that plan often
leaves part of the cap unused: its rivals with fewer turns repeat more.
Here the unused repeats are spent where each saves the most turns (seed 001
eq. 3: every turn leaves S_UR of wall unprobed), one move at a time.

The move is a bridged 2-opt reversal: the stretch p_i … p_j is reversed
(as in :mod:`.untwist`) when its new joins p_{i−1} → p_j and p_i → p_{j+1}
are each one step, or two steps through a bridge cell m (8-neighbour moves
without corner cutting; m is free, hence already covered, so each bridge
is one more visit: one repeat). Inside the stretch every step is negated,
so only the turns at the joins change. Of all such moves the one saving
the most turns per repeat added is taken (a plain reversal, no bridge,
first; among equal ratios the larger gain), while it saves at least
``min_gain`` turns per repeat and the repeats stay within ``target``.

Every visit stays, so coverage stays complete; the first cell stays first
and the path stays valid. No wrap (the public face does not wrap).
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
def _join(free, a, b, prev, nxt, w):
    """The join a → b: (changes of heading at a, at the bridge and at b,
    given the cell ``prev`` before a and ``nxt`` after b (−1: none), and
    the bridge cell, −1 when a and b join in one step); the bridge with the
    fewest turns. Turns −1 when they do not join in at most two steps."""
    if _move_ok(free, a, b, w):
        return _t(prev, a, b, w) + _t(a, b, nxt, w), -1
    h = free.shape[0]
    ar, ac = a // w, a % w
    br, bc = b // w, b % w
    if abs(ar - br) > 2 or abs(ac - bc) > 2:
        return -1, -1
    best, bm = 1 << 30, -1
    for d in range(8):
        mr, mc = ar + DR8[d], ac + DC8[d]
        if mr < 0 or mr >= h or mc < 0 or mc >= w or free[mr, mc] == 0:
            continue
        if abs(mr - br) > 1 or abs(mc - bc) > 1:
            continue
        m = mr * w + mc
        if m == b or not _move_ok(free, a, m, w) or not _move_ok(free, m, b, w):
            continue
        t = _t(prev, a, m, w) + _t(a, m, b, w) + _t(m, b, nxt, w)
        if t < best:
            best, bm = t, m
    if bm < 0:
        return -1, -1
    return best, bm


@njit(cache=True)
def _better(gain, added, bg, ba):
    """Does (gain, added) save more turns per repeat than (bg, ba)? ba < 0:
    nothing yet; added 0 (a plain reversal) beats any bridged move."""
    if ba < 0:
        return True
    if added == 0 or ba == 0:
        return added == 0 and (ba > 0 or gain > bg)
    return gain * ba > bg * added or (gain * ba == bg * added and gain > bg)


@njit(cache=True)
def best_move(free, path, n, w, first, nxt, budget):
    """The bridged reversal of path[:n] saving the most turns per repeat
    added with at most ``budget`` bridges (see the module): (gain, bridges,
    i, j, m1, m2), m1/m2 the bridges before p_j and after p_i (−1: none);
    bridges −1 when no move saves a turn. first/nxt: the positions of each
    cell (:func:`.relocate._index`)."""
    h = free.shape[0]
    bg, ba, bi, bj, b1, b2 = 0, -1, -1, -1, -1, -1
    for i in range(1, n - 1):
        a, pi = path[i - 1], path[i]
        ar, ac = a // w, a % w
        pa = _at(path, n, i - 2)
        for qr in range(max(0, ar - 2), min(h, ar + 3)):
            for qc in range(max(0, ac - 2), min(w, ac + 3)):
                j = first[qr * w + qc]
                while j >= 0:
                    if j <= i:
                        j = nxt[j]
                        continue
                    pj = path[j]
                    y, ny = _at(path, n, j + 1), _at(path, n, j + 2)
                    old = _t(pa, a, pi, w) + _t(a, pi, path[i + 1], w)
                    old += _t(path[j - 1], pj, y, w) + _t(pj, y, ny, w)
                    if old == 0:  # no turn to remove at the joins: no gain (exact)
                        j = nxt[j]
                        continue
                    t1, m1 = _join(free, a, pj, pa, path[j - 1], w)
                    if t1 < 0 or t1 >= old:  # the second join cannot make it gain
                        j = nxt[j]
                        continue
                    t2, m2 = 0, -1
                    if y >= 0 and t1 >= 0:
                        t2, m2 = _join(free, pi, y, path[i + 1], ny, w)
                    added = (m1 >= 0) + (m2 >= 0)
                    gain = old - t1 - t2
                    if t1 >= 0 and t2 >= 0 and gain > 0 and added <= budget:
                        if _better(gain, added, bg, ba):
                            bg, ba, bi, bj, b1, b2 = gain, added, i, j, m1, m2
                    j = nxt[j]
    return bg, ba, bi, bj, b1, b2


@njit(cache=True)
def spend(free, path, target, min_gain=1.0, max_moves=50, until_spent=False):
    """The path with turns bought by repeats (see the module) while it has
    at most ``target`` repeated visits and each move saves at least
    ``min_gain`` turns per repeat added; at most ``max_moves`` moves; with
    ``until_spent``, none once the repeats reach ``target`` (the plain
    reversals left are 2-opt's, :mod:`.untwist`). Returns a new array."""
    w = free.shape[1]
    n = len(path)
    seen = np.zeros(free.size, dtype=np.int64)
    for v in path:
        seen[v] = 1
    repeats = n - int(seen.sum())
    size = n + 2 * max_moves
    first = np.full(free.size, -1, dtype=np.int64)
    nxt = np.empty(size, dtype=np.int64)
    out = np.empty(size, dtype=np.int64)
    cur = np.empty(size, dtype=np.int64)
    cur[:n] = path
    for _ in range(max_moves):
        if until_spent and repeats >= target:
            break
        _index(cur, n, first, nxt)
        gain, added, i, j, m1, m2 = best_move(free, cur, n, w, first, nxt, target - repeats)
        if added < 0 or gain < min_gain * added:
            break
        out[:i] = cur[:i]
        m = i
        if m1 >= 0:
            out[m] = m1
            m += 1
        out[m : m + j - i + 1] = cur[i : j + 1][::-1]
        m += j - i + 1
        if m2 >= 0:
            out[m] = m2
            m += 1
        out[m : m + n - j - 1] = cur[j + 1 : n]
        n = m + n - j - 1
        cur[:n] = out[:n]
        repeats += added
    return cur[:n].copy()
