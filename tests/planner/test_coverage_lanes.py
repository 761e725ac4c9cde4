"""Lane tours (coverage/lanes.py): lanes of known shapes, complete and valid
paths on random walls, and the order search finding the plain boustrophedon."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage.lanes import (
    _ends,
    end_distances,
    improve,
    lane_tour,
    lanes_of,
    link_cost,
    tour_cost,
)

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def test_lanes_of_rows_split_by_an_obstacle_and_columns_by_region():
    labels = np.zeros((3, 5), dtype=np.int32)
    labels[1, 2] = -1  # a blocked cell splits the middle row
    labels[:, 4] = 1  # region 1: the last column, swept along columns
    lanes = lanes_of(labels, np.array([0, 1]))
    got = sorted(tuple(ln.tolist()) for ln in lanes)
    w = 5
    want = sorted(
        [
            (0, 1, 2, 3),
            (w, w + 1),
            (w + 3,),
            (2 * w, 2 * w + 1, 2 * w + 2, 2 * w + 3),
            (4, w + 4, 2 * w + 4),
        ]
    )
    assert got == want


def test_end_distances_no_corner_cutting_and_bounded():
    free = np.ones((3, 3), dtype=np.uint8)
    free[0, 1] = free[1, 0] = 0  # (0,0) is boxed in: its diagonal cuts a corner
    cells = np.array([0, 4, 8], dtype=np.int64)
    d = end_distances(free, cells, 10)
    assert d[0, 1] > 1 << 19  # unreachable
    assert d[1, 2] == 1 and d[2, 1] == 1
    d1 = end_distances(np.ones((1, 9), dtype=np.uint8), np.array([0, 8]), 3)
    assert d1[0, 1] > 1 << 19  # beyond the radius


def test_open_rectangle_is_swept_as_a_plain_boustrophedon():
    h, w = 8, 13
    free = np.ones((h, w), dtype=np.uint8)
    labels = np.zeros((h, w), dtype=np.int32)
    arr = lane_tour(free, labels, np.array([0]), 0)
    f = figures(np.zeros((h, w), dtype=bool), (0, 0), _cells(arr, w))
    assert f.coverage == 1.0 and f.visits == h * w  # no cell twice
    assert f.turns == 2 * (h - 1)  # one side-step U-turn between lanes


def test_improve_repairs_a_shuffled_order():
    h, w = 10, 6
    free = np.ones((h, w), dtype=np.uint8)
    lanes = lanes_of(np.zeros((h, w), dtype=np.int32), np.array([0]))
    cell, ur, uc = _ends(lanes, w)
    dist = end_distances(free, cell, 50)
    rng = np.random.default_rng(3)
    seq = np.concatenate([[0], 2 * rng.permutation(np.arange(1, h))]).astype(np.int64)
    before = tour_cost(seq, dist, cell, ur, uc, w, 2.0)
    improve(seq, dist, cell, ur, uc, w, 2.0, 30)
    after = tour_cost(seq, dist, cell, ur, uc, w, 2.0)
    assert after < before
    assert after == 2 * (h - 1)  # every link a side step: two turns, nothing crossed
    assert sorted(seq // 2) == list(range(h))
    assert link_cost(dist, cell, ur, uc, w, 1, 3, 2.0) == 2.0  # side step: a U-turn
    assert link_cost(dist, cell, ur, uc, w, 1, 2, 2.0) == 3.0 + 2.0 * 4  # across the row


def test_lane_tour_random_grids_complete_and_valid(rng):
    for density in (0.1, 0.25, 0.4):
        for _ in range(10):
            h, w = int(rng.integers(1, 25)), int(rng.integers(1, 25))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            reach = reachable(blocked, start)
            labels = np.full((h, w), -1, dtype=np.int32)
            for r, c in reach:
                labels[r, c] = 0
            free = np.ascontiguousarray(labels >= 0, dtype=np.uint8)
            for axis in (0, 1):
                arr = lane_tour(free, labels, np.array([axis]), start[0] * w + start[1])
                assert check(blocked, start, _cells(arr, w)) == reach


def test_the_order_search_on_hundreds_of_short_lanes_is_bounded(rng, monkeypatch):
    # scattered obstacles cut a wall into hundreds of one- and two-cell lanes;
    # each round of the whole-order search costs ∝ n², so its rounds shrink with
    # (KICK_LANES / n)²; a short order keeps every round asked for
    import app.core.planner.coverage.lanes as lanes_mod

    rounds = []
    real = lanes_mod.kicked_t

    def counted(seq, cost, passes, kicks, seed, span=0, local=False):
        rounds.append((len(seq), kicks))
        return real(seq, cost, passes, kicks, seed, span, local)

    monkeypatch.setattr(lanes_mod, "kicked_t", counted)
    w = 30
    for density, size in ((0.3, 30), (0.0, 12)):
        blocked = random_grid(rng, size, w, density)
        blocked[0, 0] = False
        reach = reachable(blocked, (0, 0))
        labels = np.full(blocked.shape, -1, dtype=np.int32)
        for r, c in reach:
            labels[r, c] = 0
        free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        rounds.clear()
        arr = lane_tour(free, labels, np.array([0]), 0, kicks=40, split=True)
        assert check(blocked, (0, 0), _cells(arr, w)) == reach
        [(n, kicks)] = rounds
        if density > 0:
            assert n > lanes_mod.KICK_LANES  # many short lanes
            assert 1 <= kicks <= 40 * (lanes_mod.KICK_LANES / n) ** 2 + 0.5
        else:
            assert n < lanes_mod.KICK_LANES and kicks == 40
