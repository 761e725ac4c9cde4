"""Maps cut by scattered obstacles into many short lanes (docs/coverage.md,
"What is weaker"): the lane orders on neighbour lists (coverage/sparse.py) and
the kick budget scaled by the lanes (coverage/plan.py), and the plan of such
a map complete and valid."""

import numpy as np

from app.core.planner.coverage import _kernels as K
from app.core.planner.coverage import lanes as L
from app.core.planner.coverage import plan as P
from app.core.planner.coverage import sparse as S

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _split_set(seed, size):
    """The split lanes along rows of a random grid a fifth blocked, their
    ends, distances and dense link costs (λ = 1.5)."""
    rng = np.random.default_rng(seed)
    blocked = random_grid(rng, size, size, 0.2)
    start = free_cell(rng, blocked)
    w = size
    s0 = start[0] * w + start[1]
    reach = K.flood(np.ascontiguousarray(~blocked, dtype=np.uint8), s0, False)
    free = np.ascontiguousarray(reach > 0, dtype=np.uint8)
    whole = np.where(reach > 0, 0, -1).astype(np.int32)
    lanes, first = L.lane_set(whole, np.array([0]), s0, False, True)
    cell, ur, uc = L._ends(lanes, w)
    dist = L.end_distances(free, cell, 48)
    cost = L.link_table(dist, cell, ur, uc, w, 1.5)
    return lanes, first, (dist, cell, ur, uc, w, 1.5), cost


def test_kick_budget_keeps_small_lane_counts_and_bounds_kicks_times_lanes():
    assert P.kick_budget(600, 73) == 600  # the most lanes of a paper-like wall
    assert P.kick_budget(600, P.KICK_FULL_LANES) == 600
    assert P.kick_budget(600, 2 * P.KICK_FULL_LANES) == 300
    assert P.kick_budget(600, 6 * P.KICK_FULL_LANES) == 100
    assert P.kick_budget(600, 10**7) == 1  # never none
    for lanes in range(P.KICK_FULL_LANES, 5000, 37):
        assert P.kick_budget(600, lanes) * lanes <= 600 * P.KICK_FULL_LANES


def test_lane_count_takes_the_axis_with_fewer_runs():
    reach = np.ones((4, 6), dtype=np.uint8)
    reach[:, 2] = 0  # every row cut in two: 8 row runs; 5 columns of one run
    assert P.lane_count(reach) == 5
    reach[1, :] = 0  # and the columns too: rows 6 runs, columns 10
    assert P.lane_count(reach) == 6


def test_neighbour_lists_hold_each_ends_cheapest_links_and_give_the_dense_nearest_tour():
    lanes, first, args, cost = _split_set(3, 30)
    k = 10
    nb = S.neighbour_lists(*args, k)
    m = len(lanes) * 2
    for x in range(0, m, 7):
        others = [y for y in range(m) if y // 2 != x // 2]
        want = sorted(others, key=lambda y: (cost[x, y], y))[:k]
        assert nb[x].tolist() == want
    assert S.nearest_tour_s(nb, *args, first).tolist() == L.nearest_tour_t(cost, first).tolist()


def test_order_search_on_lists_leaves_no_gaining_reversal():
    lanes, first, args, cost = _split_set(4, 30)
    nb = S.neighbour_lists(*args, L.NEIGHBOURS)
    offs, near = S.symmetric_lists(nb, *args)
    kth = S.kth_costs(nb, *args)
    seq = S.nearest_tour_s(nb, *args, first)
    before = L.tour_cost_t(seq, cost)
    S.improve_s(seq, offs, near, kth, *args, 30)
    n = len(seq)
    assert seq[0] == 2 * first and sorted((seq // 2).tolist()) == list(range(n))
    assert L.tour_cost_t(seq, cost) < before
    # no 2-opt reversal seq[i..j] lowers the cost (the dense search's move)
    for i in range(1, n):
        a = seq[i - 1] ^ 1
        j = np.arange(i, n)
        nxt = seq[np.minimum(j + 1, n - 1)]
        old = cost[a, seq[i]] + np.where(j + 1 < n, cost[seq[j] ^ 1, nxt], 0)
        new = cost[a, seq[j] ^ 1] + np.where(j + 1 < n, cost[seq[i], nxt], 0)
        assert (new >= old - 1e-9).all(), i


def test_a_scattered_grid_is_planned_on_the_sparse_tours_complete_and_valid(monkeypatch):
    rng = np.random.default_rng(7)
    blocked = random_grid(rng, 34, 34, 0.2)
    start = free_cell(rng, blocked)
    sparse, budgets = [], []
    real_improve, real_searched = L.improve_s, P.searched

    def improve_s(seq, *a, **kw):
        sparse.append(len(seq))
        return real_improve(seq, *a, **kw)

    def searched(free, starts, budget, *a, **kw):
        budgets.append(budget)
        return real_searched(free, starts, budget, *a, **kw)

    monkeypatch.setattr(L, "improve_s", improve_s)
    monkeypatch.setattr(P, "searched", searched)
    cells = P.coverage_path(blocked, start)
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert sparse and min(sparse) > L.SPARSE_LANES  # the split lanes went on lists
    reach = K.flood(np.ascontiguousarray(~blocked, dtype=np.uint8), start[0] * 34 + start[1], False)
    lanes = P.lane_count(reach)
    assert lanes > P.KICK_FULL_LANES
    assert budgets == [P.kick_budget(P.KICKS, lanes)] and budgets[0] < P.KICKS
