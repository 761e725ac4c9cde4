"""The coverage planner's faster kernels against plain definitions.

Each speed-up of best_plan's pipeline claims to compute exactly what the
plain version did (so the plans do not change): the neighbour table, the
walker's running open-neighbour counts and its escape search, the 2-opt on
move masks, the lane-order search on a cost table, the lane ends' distances
searched once for several tours, and the axis-free walks reused. Each is
checked here against a plain (uncompiled or recounting) definition on
random maps.
"""

from __future__ import annotations

import numpy as np
import pytest

from app.core.planner.coverage import _kernels as K
from app.core.planner.coverage import _walker as W
from app.core.planner.coverage import plan as P
from app.core.planner.coverage.lanes import (
    _ends,
    end_distances,
    improve_t,
    lane_set,
    link_cost,
    link_table,
    nearest_tour_t,
    shared_distances,
)
from app.core.planner.coverage.prune import prune
from app.core.planner.coverage.untwist import two_opt


def _random_map(rng, h=18, w=22, p=0.18):
    blocked = rng.random((h, w)) < p
    blocked[0, 0] = False
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    reach = K.flood(free, 0, False)
    return blocked, reach


def _move_ok(free, a, b, w):
    ar, ac, br, bc = a // w, a % w, b // w, b % w
    dr, dc = br - ar, bc - ac
    if max(abs(dr), abs(dc)) != 1:
        return False
    if not free[br, bc]:
        return False
    return not (dr and dc and (not free[br, ac] or not free[ar, bc]))


def _turn(w, a, b, c):
    if a < 0 or c < 0:
        return 0
    return int((b // w - a // w, b % w - a % w) != (c // w - b // w, c % w - b % w))


def _two_opt_plain(free, path, passes):
    """The 2-opt sweep as first written: every position, every neighbour,
    every pass."""
    h, w = free.shape
    n = len(path)
    count = np.bincount(path, minlength=h * w)
    pos = np.full(h * w, -1)
    for k in range(n):
        if count[path[k]] == 1:
            pos[path[k]] = k
    gained = 0
    for _ in range(passes):
        changed = False
        for i in range(1, n - 1):
            a = path[i - 1]
            pa = path[i - 2] if i >= 2 else -1
            for dr, dc in zip(K.DR, K.DC, strict=True):
                qr, qc = a // w + dr, a % w + dc
                if not (0 <= qr < h and 0 <= qc < w) or not free[qr, qc]:
                    continue
                q = qr * w + qc
                j = pos[q]
                if j <= i or count[q] != 1 or not _move_ok(free, a, q, w):
                    continue
                after = path[j + 1] if j + 1 < n else -1
                if after >= 0 and not _move_ok(free, path[i], after, w):
                    continue
                after2 = path[j + 2] if j + 2 < n else -1
                tail = after >= 0
                old = (
                    _turn(w, pa, a, path[i])
                    + _turn(w, a, path[i], path[i + 1])
                    + _turn(w, path[j - 1], path[j], after)
                    + (_turn(w, path[j], after, after2) if tail else 0)
                )
                new = (
                    _turn(w, pa, a, q)
                    + _turn(w, a, path[j], path[j - 1])
                    + _turn(w, path[i + 1], path[i], after)
                    + (_turn(w, path[i], after, after2) if tail else 0)
                )
                if new < old:
                    path[i : j + 1] = path[i : j + 1][::-1].copy()
                    for k in range(i, j + 1):
                        if count[path[k]] == 1:
                            pos[path[k]] = k
                    gained += old - new
                    changed = True
                    break
        if not changed:
            break
    return gained


def _walk(blocked, reach, family, seed, axis):
    return P._walked(blocked, (0, 0), False, family, seed, "nearest", False, axis, None, reach)[0]


def test_neighbour_table_is_every_valid_move(rng):
    for wrap in (False, True):
        blocked, _ = _random_map(rng)
        free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        h, w = free.shape
        nbr = K.neighbour_table(free, wrap)
        for v in range(h * w):
            r, c = divmod(v, w)
            want = [K._step_ok(free, r, c, K.DR[k], K.DC[k], wrap) if free[r, c] else -1
                    for k in range(8)]  # fmt: skip
            assert nbr[v].tolist() == want


def test_walker_open_counts_stay_equal_to_a_recount(rng):
    blocked, reach = _random_map(rng)
    h, w = reach.shape
    region = np.where(reach > 0, (np.arange(h * w).reshape(h, w) % w) // 7, -1).astype(np.int32)
    nbr = K.neighbour_table(reach, False)
    vis = np.zeros(h * w, dtype=np.int32)
    reg = region.reshape(h * w)
    deg = W._degrees(nbr, vis, reg)
    cells = np.flatnonzero(reach.reshape(-1))
    for v in rng.choice(cells, size=3 * len(cells) // 2):
        W._visit(nbr, vis, reg, deg, v)
        mask = reg >= 0
        assert np.array_equal(deg[mask], W._degrees(nbr, vis, reg)[mask])


def test_walker_escape_is_the_plain_breadth_first_path(rng):
    blocked, reach = _random_map(rng)
    h, w = reach.shape
    nbr = K.neighbour_table(reach, False)
    region = np.where(reach > 0, 0, -1).astype(np.int32)
    visits = (rng.random((h, w)) < 0.8).astype(np.int32)
    cells = np.flatnonzero(reach.reshape(-1))
    n = h * w
    scratch = [np.empty(n, np.int64), np.zeros(n, np.int64), np.empty(n, np.int64)]
    other = [np.empty(n, np.int64), np.zeros(n, np.int64), np.empty(n, np.int64)]
    for g, s in enumerate(rng.choice(cells, size=30), start=1):
        goal = int(rng.choice(cells)) if g % 3 == 0 else -1
        want = K.bfs_path(reach, visits, region, int(s), goal, 0, False, other[0], other[1], g,
                          other[2])  # fmt: skip
        got = W._escape(nbr, visits.reshape(n), region.reshape(n), int(s), goal, 0,
                        scratch[0], scratch[1], g, scratch[2])  # fmt: skip
        assert got.tolist() == want.tolist()


def test_two_opt_makes_the_plain_sweeps_reversals(rng):
    checked = 0
    for _ in range(4):
        blocked, reach = _random_map(rng)
        free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        for family in ("lanes", "hug", "tight"):
            for seed in (0, 3):
                path = prune(free, _walk(blocked, reach, family, seed, 0), 10)
                fast, plain = path.copy(), path.copy()
                assert two_opt(free, fast, 20) == _two_opt_plain(free, plain, 20)
                assert fast.tolist() == plain.tolist()
                checked += int(not np.array_equal(fast, path))
    assert checked > 0  # some paths were changed, so reversals were compared


def _improve_plain(seq, dist, cell, ur, uc, w, lam, passes):
    """The lane-order 2-opt and or-opt computing each link's cost as it goes."""

    def lc(x, y):
        return link_cost(dist, cell, ur, uc, w, x, y, lam)

    n = len(seq)
    for _ in range(passes):
        gained = False
        for i in range(1, n):
            for j in range(i, n):
                a = seq[i - 1] ^ 1
                old, new = lc(a, seq[i]), lc(a, seq[j] ^ 1)
                if j + 1 < n:
                    old += lc(seq[j] ^ 1, seq[j + 1])
                    new += lc(seq[i], seq[j + 1])
                if new < old - 1e-9:
                    seq[i : j + 1] = seq[i : j + 1][::-1] ^ 1
                    gained = True
        for i in range(1, n):
            e0, prv = seq[i], seq[i - 1] ^ 1
            cut = lc(prv, e0)
            if i + 1 < n:
                cut += lc(e0 ^ 1, seq[i + 1]) - lc(prv, seq[i + 1])
            best, bk, bo = 1e-9, -1, 0
            for k in range(n):
                if k in (i, i - 1):
                    continue
                x = seq[k] ^ 1
                y = seq[k + 1] if k + 1 < n else -1
                if k + 1 == i:
                    y = seq[i + 1] if i + 1 < n else -1
                base = lc(x, y) if y >= 0 else 0.0
                for o in range(2):
                    e = e0 ^ o
                    add = lc(x, e) + (lc(e ^ 1, y) if y >= 0 else 0.0)
                    if cut - (add - base) > best:
                        best, bk, bo = cut - (add - base), k, o
            if bk >= 0:
                e = e0 ^ bo
                rest = np.delete(seq, i)
                at = bk if bk > i else bk + 1
                seq[:] = np.insert(rest, at, e)
                gained = True
        if not gained:
            break


def test_lane_order_search_on_the_cost_table_matches_the_plain_one(rng):
    for _ in range(3):
        blocked, reach = _random_map(rng, 14, 16)
        free = np.ascontiguousarray(reach, dtype=np.uint8)
        w = free.shape[1]
        labels = np.where(reach > 0, 0, -1).astype(np.int32)
        lanes, first = lane_set(labels, np.array([int(rng.integers(2))]), 0)
        cell, ur, uc = _ends(lanes, w)
        dist = end_distances(free, cell, 48)
        cost = link_table(dist, cell, ur, uc, w, 1.5)
        assert all(cost[x, y] == link_cost(dist, cell, ur, uc, w, x, y, 1.5)
                   for x in range(len(cell)) for y in range(len(cell)))  # fmt: skip
        seq = nearest_tour_t(cost, first)
        fast, plain = seq.copy(), seq.copy()
        improve_t(fast, cost, 30)
        _improve_plain(plain, dist, cell, ur, uc, w, 1.5, 30)
        assert fast.tolist() == plain.tolist()


def test_shared_distances_equal_each_sets_own(rng):
    blocked, reach = _random_map(rng, 20, 24)
    free = np.ascontiguousarray(reach, dtype=np.uint8)
    cells = np.flatnonzero(reach.reshape(-1))
    sets = [rng.choice(cells, size=k) for k in (5, 17, 30)]  # repeats within a set too
    for got, cs in zip(shared_distances(free, sets, 9), sets, strict=True):
        assert np.array_equal(got, end_distances(free, cs, 9))


@pytest.mark.parametrize("family", [f for f in P.FAMILIES if P._axis_free(f)])
def test_axis_free_families_walk_the_same_path_either_way(rng, family):
    # best_plan walks these once per seed and reuses the path for the other axis
    for _ in range(3):
        blocked, reach = _random_map(rng)
        for seed in (0, 2):
            rows = _walk(blocked, reach, family, seed, 0)
            cols = _walk(blocked, reach, family, seed, 1)
            assert rows.tolist() == cols.tolist()
