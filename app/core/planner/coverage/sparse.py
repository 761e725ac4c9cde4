"""Lane orders on neighbour lists: the tours of :mod:`.lanes` for sets of many short lanes.

Scattered obstacles cut a map into thousands of lanes of one to five cells. The dense
search of :mod:`.lanes` prices every pair of lane ends in a (2n)² table and runs 2-opt
and or-opt passes of O(n²) each; here each lane end keeps only its ``k`` cheapest links
(:func:`neighbour_lists`, made symmetric by :func:`symmetric_lists`), and a move is
tried only where one of its new links is on a list — or where the link it replaces is
dearer than the end's ``k``-th cheapest (:func:`kth_costs`), when the whole row is
scanned, so that no gaining 2-opt reversal is missed. A pass costs ∝ n · k (and n per
such long link) instead of n². The costs are :func:`.links.link_cost`'s, as in the dense
search; which sets go here is :func:`.lanes.sparse_set`'s choice.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .links import link_cost


@njit(cache=True)
def neighbour_lists(dist, cell, ur, uc, w, lam, k):
    """(2n, k) for each lane end x its k cheapest links x → y to the ends of
    other lanes (:func:`link_cost`), cheapest first, ties by the lower end;
    −1 where fewer ends lie within the distances searched. The cost grows
    with the ends' distance (0, at most 2 for one step, 3 + lam·(d − 1)
    beyond), so only the ends up to the k-th nearest distance are priced."""
    m = len(cell)
    nb = np.full((m, k), -1, dtype=np.int64)
    top = 66
    hist = np.zeros(top, dtype=np.int64)
    ys = np.empty(m, dtype=np.int64)
    cs = np.empty(m, dtype=np.float64)
    for x in range(m):
        hist[:] = 0
        for y in range(m):
            d = dist[x, y]
            if y // 2 != x // 2 and d < top:
                hist[d] += 1
        reach, total = top - 1, 0
        for d in range(top):
            total += hist[d]
            if total >= k:
                reach = d
                break
        c = 0
        for y in range(m):
            if y // 2 != x // 2 and dist[x, y] <= reach:
                ys[c] = y
                cs[c] = link_cost(dist, cell, ur, uc, w, x, y, lam)
                c += 1
        order = np.argsort(cs[:c], kind="mergesort")  # stable: ties by the lower end
        for t in range(min(k, c)):
            nb[x, t] = ys[order[t]]
    return nb


@njit(cache=True)
def symmetric_lists(nb, dist, cell, ur, uc, w, lam):
    """The lists of :func:`neighbour_lists` made symmetric (y in x's list
    when x is in y's or y in x's), as (offsets, ends): x's ends are
    ends[offsets[x]:offsets[x + 1]], cheapest first, ties by the lower end."""
    m, k = nb.shape
    deg = np.zeros(m + 1, dtype=np.int64)
    for x in range(m):
        for q in range(k):
            y = nb[x, q]
            if y >= 0:
                deg[x + 1] += 1
                deg[y + 1] += 1
    raw = np.cumsum(deg)
    fill = raw[:-1].copy()
    items = np.empty(raw[-1], dtype=np.int64)
    for x in range(m):
        for q in range(k):
            y = nb[x, q]
            if y >= 0:
                items[fill[x]] = y
                fill[x] += 1
                items[fill[y]] = x
                fill[y] += 1
    offs = np.zeros(m + 1, dtype=np.int64)
    out = np.empty(raw[-1], dtype=np.int64)
    for x in range(m):
        row = np.unique(items[raw[x] : raw[x + 1]])  # sorted by end, no repeats
        cs = np.empty(len(row), dtype=np.float64)
        for t in range(len(row)):
            cs[t] = link_cost(dist, cell, ur, uc, w, x, row[t], lam)
        order = np.argsort(cs, kind="mergesort")
        for t in range(len(row)):
            out[offs[x] + t] = row[order[t]]
        offs[x + 1] = offs[x] + len(row)
    return offs, out[: offs[m]].copy()


@njit(cache=True)
def kth_costs(nb, dist, cell, ur, uc, w, lam):
    """For each end, the cost of the last end in its list (:func:`neighbour_lists`;
    every cheaper link is in the list); infinite when the list is short (it
    holds every end within reach)."""
    m, k = nb.shape
    out = np.full(m, np.inf)
    for x in range(m):
        if nb[x, k - 1] >= 0:
            out[x] = link_cost(dist, cell, ur, uc, w, x, nb[x, k - 1], lam)
    return out


@njit(cache=True)
def nearest_tour_s(nb, dist, cell, ur, uc, w, lam, first):
    """:func:`nearest_tour_t` on neighbour lists: the first open end of the
    list is the cheapest (the lists hold the cheapest ends in order), else
    every end is priced; the same order as the dense table gives."""
    m = len(cell)
    n = m // 2
    done = np.zeros(n, dtype=np.bool_)
    seq = np.empty(n, dtype=np.int64)
    seq[0] = 2 * first
    done[first] = True
    for t in range(1, n):
        x = seq[t - 1] ^ 1
        be = -1
        for q in range(nb.shape[1]):
            e = nb[x, q]
            if e >= 0 and not done[e // 2]:
                be = e
                break
        if be < 0:
            best = np.inf
            for e in range(m):
                if not done[e // 2]:
                    c = link_cost(dist, cell, ur, uc, w, x, e, lam)
                    if c < best:
                        best, be = c, e
        seq[t] = be
        done[be // 2] = True
    return seq


@njit(cache=True)
def _reverse(seq, pos, lo, hi):
    """seq[lo..hi] reversed, each lane flipped; ``pos`` (lane → position) kept."""
    while lo < hi:
        t = seq[lo]
        seq[lo] = seq[hi] ^ 1
        seq[hi] = t ^ 1
        pos[seq[lo] // 2] = lo
        pos[seq[hi] // 2] = hi
        lo += 1
        hi -= 1
    if lo == hi:
        seq[lo] ^= 1


@njit(cache=True)
def improve_s(seq, offs, near, kth, dist, cell, ur, uc, w, lam, passes, first=1, last=-1):
    """:func:`improve_t` on neighbour lists (:func:`symmetric_lists`: ``near``
    [offs[x]:offs[x + 1]] are end x's; ``kth[x]``: the cost of the last of
    x's own cheapest ends, :func:`neighbour_lists`). A 2-opt reversal gains
    only when one of its new links is cheaper than the link it replaces at
    that end; that end's list holds every such link while the old link costs
    at most kth, so only the list is tried then, every position otherwise (a
    long link: a full scan, as in improve_t). A lane is moved next to the
    ends in its own ends' lists, or, when both its links are longer than
    kth at its ends (a lane stranded between two long links), to the best
    place anywhere. Costs priced as needed
    (:func:`link_cost`); a pass ∝ n · k + n per long link. Returns the
    moves taken."""
    n = len(seq)
    top = n if last < 0 else min(last, n)
    bottom = max(first, 1)
    pos = np.empty(n, dtype=np.int64)
    for t in range(n):
        pos[seq[t] // 2] = t
    moves = 0
    for _ in range(passes):
        gained = False
        for i in range(bottom, top):  # 2-opt: new link seq[i-1] → seq[j] ^ 1
            a = seq[i - 1] ^ 1
            old = link_cost(dist, cell, ur, uc, w, a, seq[i], lam)
            full = old > kth[a]
            q, stop = (offs[a], offs[a + 1]) if not full else (i, n)
            while q < stop:
                if full:
                    j = q
                    e = seq[j] ^ 1
                else:
                    e = near[q]
                    j = pos[e // 2]
                q += 1
                c1 = link_cost(dist, cell, ur, uc, w, a, e, lam)
                if c1 >= old - 1e-9:
                    if full:
                        continue
                    break
                if j < i or seq[j] != e ^ 1:
                    continue
                delta = c1 - old
                if j + 1 < n:
                    delta += link_cost(dist, cell, ur, uc, w, seq[i], seq[j + 1], lam)
                    delta -= link_cost(dist, cell, ur, uc, w, seq[j] ^ 1, seq[j + 1], lam)
                if delta < -1e-9:
                    _reverse(seq, pos, i, j)
                    gained = True
                    moves += 1
                    break
        for j1 in range(bottom + 1, n):  # 2-opt: new link seq[i] → seq[j1], seq[i..j1-1] reversed
            b = seq[j1]
            old = link_cost(dist, cell, ur, uc, w, seq[j1 - 1] ^ 1, b, lam)
            full = old > kth[b]
            q, stop = (offs[b], offs[b + 1]) if not full else (bottom, min(top, j1))
            while q < stop:
                if full:
                    i = q
                    x = seq[i]
                else:
                    x = near[q]
                    i = pos[x // 2]
                q += 1
                c2 = link_cost(dist, cell, ur, uc, w, x, b, lam)
                if c2 >= old - 1e-9:
                    if full:
                        continue
                    break
                if i < bottom or i >= top or i >= j1 or seq[i] != x:
                    continue
                delta = c2 - old
                delta += link_cost(dist, cell, ur, uc, w, seq[i - 1] ^ 1, seq[j1 - 1] ^ 1, lam)
                delta -= link_cost(dist, cell, ur, uc, w, seq[i - 1] ^ 1, seq[i], lam)
                if delta < -1e-9:
                    _reverse(seq, pos, i, j1 - 1)
                    gained = True
                    moves += 1
                    break
        for i in range(bottom, top):  # or-opt: lane i moved after lane kk, either way round
            e0 = seq[i]
            prv = seq[i - 1] ^ 1
            c_in = link_cost(dist, cell, ur, uc, w, prv, e0, lam)
            cut = c_in
            full = c_in > kth[e0]
            if i + 1 < n:
                c_out = link_cost(dist, cell, ur, uc, w, e0 ^ 1, seq[i + 1], lam)
                cut += c_out - link_cost(dist, cell, ur, uc, w, prv, seq[i + 1], lam)
                full = full and c_out > kth[e0 ^ 1]
            best, bk, bo = 1e-9, -1, 0
            for o in range(2):
                e = e0 ^ o
                for side in range(2):  # an end x → e (x = seq[kk] ^ 1), or e ^ 1 → y = seq[kk + 1]
                    f = e if side == 0 else e ^ 1
                    q, stop = (offs[f], offs[f + 1]) if not full else (0, n if side == 0 else 0)
                    while q < stop:
                        if full:
                            kk = q
                        else:
                            z = near[q]
                            p = pos[z // 2]
                            if side == 0:
                                kk = p if seq[p] == z ^ 1 else -1
                            else:
                                kk = p - 1 if seq[p] == z else -1
                        q += 1
                        if kk < 0 or kk == i or kk == i - 1:
                            continue
                        x = seq[kk] ^ 1
                        y = seq[kk + 1] if kk + 1 < n else -1
                        add = link_cost(dist, cell, ur, uc, w, x, e, lam)
                        if y >= 0:
                            add += link_cost(dist, cell, ur, uc, w, e ^ 1, y, lam)
                            add -= link_cost(dist, cell, ur, uc, w, x, y, lam)
                        if cut - add > best:
                            best, bk, bo = cut - add, kk, o
            if bk >= 0:
                e = e0 ^ bo
                if bk > i:
                    for t in range(i, bk):
                        seq[t] = seq[t + 1]
                        pos[seq[t] // 2] = t
                    seq[bk] = e
                    pos[e // 2] = bk
                else:
                    for t in range(i, bk + 1, -1):
                        seq[t] = seq[t - 1]
                        pos[seq[t] // 2] = t
                    seq[bk + 1] = e
                    pos[e // 2] = bk + 1
                gained = True
                moves += 1
        if not gained:
            break
    return moves


@njit(cache=True)
def tour_cost_s(seq, dist, cell, ur, uc, w, lam):
    total = 0.0
    for t in range(1, len(seq)):
        total += link_cost(dist, cell, ur, uc, w, seq[t - 1] ^ 1, seq[t], lam)
    return total


@njit(cache=True)
def kicked_s(seq, offs, near, kth, dist, cell, ur, uc, w, lam, passes, kicks, seed):
    """:func:`kicked_t` (double bridges anywhere) with :func:`improve_s`
    as its local search."""
    np.random.seed(seed)
    n = len(seq)
    best = seq.copy()
    best_cost = tour_cost_s(best, dist, cell, ur, uc, w, lam)
    if n < 5:
        return best
    for _ in range(kicks):
        a, b, c = np.sort(np.random.choice(np.arange(1, n), 3, replace=False))
        trial = np.concatenate((best[:a], best[b:c], best[a:b], best[c:]))
        improve_s(trial, offs, near, kth, dist, cell, ur, uc, w, lam, passes)
        c_trial = tour_cost_s(trial, dist, cell, ur, uc, w, lam)
        if c_trial < best_cost - 1e-9:
            best, best_cost = trial, c_trial
    return best
