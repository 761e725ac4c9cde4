"""repair (coverage/repair.py) and split lanes (coverage/lanes.py): repeats
traded for turns, lanes cut beside their neighbours' ends, and best_plan
using both on a paper-like wall."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage.lanes import lane_tour, lanes_of, split_lanes
from app.core.planner.coverage.plan import MAX_REPETITION, best_plan
from app.core.planner.coverage.prune import prune
from app.core.planner.coverage.repair import repair
from app.core.planner.coverage.untwist import two_opt
from bench.coverage_maps import paper_like, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


# A staircase edge: row 0 has five free cells, row 1 four, row 2 three.
STAIR = np.array(
    [
        [0, 0, 0, 0, 0],
        [0, 0, 0, 0, 1],
        [0, 0, 0, 1, 1],
    ],
    dtype=bool,
)
# Lanes along rows from the bottom: the link from row 2's end to row 1's
# end (1, 3) cannot go diagonally (it would cut the blocked corner (2, 3)),
# so it steps over (1, 2), which row 1 then sweeps again: a spike at (1, 3).
STAIR_TOUR = [
    (2, 0), (2, 1), (2, 2), (1, 2), (1, 3), (1, 2), (1, 1), (1, 0),
    (0, 0), (0, 1), (0, 2), (0, 3), (0, 4),
]  # fmt: skip


def test_a_spike_at_a_staircase_becomes_a_dip_from_the_lane_beside_it():
    free = np.ascontiguousarray(~STAIR, dtype=np.uint8)
    before = figures(STAIR, (2, 0), STAIR_TOUR)
    assert (before.visits - before.covered, before.turns) == (1, 5)
    out = _cells(repair(free, _flat(STAIR_TOUR, 5), 0, 10), 5)
    # (1, 3) is visited from row 0 instead: (0, 2) → (1, 3) → (0, 3); the
    # only place where both neighbours on the path join it
    want = [
        (2, 0), (2, 1), (2, 2), (1, 2), (1, 1), (1, 0),
        (0, 0), (0, 1), (0, 2), (1, 3), (0, 3), (0, 4),
    ]  # fmt: skip
    assert out == want
    after = figures(STAIR, (2, 0), out)
    assert after.visits == after.covered == before.covered  # no repeat, all covered
    assert after.turns == 7  # the dip's three turns for the spike's one


def test_repair_stops_at_the_target():
    free = np.ascontiguousarray(~STAIR, dtype=np.uint8)
    arr = _flat(STAIR_TOUR, 5)
    assert repair(free, arr, 1, 10).tolist() == arr.tolist()  # one repeat allowed: kept


def test_repair_on_random_lane_tours_valid_complete_fewer_repeats(rng):
    for density in (0.1, 0.25, 0.4):
        for _ in range(8):
            h, w = int(rng.integers(2, 25)), int(rng.integers(2, 25))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            reach = reachable(blocked, start)
            free = np.zeros((h, w), dtype=np.uint8)
            for r, c in reach:
                free[r, c] = 1
            labels = np.where(free > 0, 0, -1).astype(np.int32)
            arr = lane_tour(free, labels, np.array([0]), start[0] * w + start[1], split=True)
            out = _cells(repair(free, arr, 0, 10 * len(arr)), w)
            assert out[0] == start
            assert check(blocked, start, out) == reach
            assert len(out) <= len(arr)


def test_split_lanes_cut_where_a_neighbour_begins_or_ends():
    labels = np.full((3, 8), -1, dtype=np.int32)
    labels[0, 0:8] = 0  # row 0: cols 0..7
    labels[1, 2:5] = 0  # row 1: cols 2..4
    labels[2, 0:8] = 0  # row 2: cols 0..7
    w = 8
    lanes = split_lanes(lanes_of(labels, np.array([0])), labels, np.array([0]))
    got = sorted(tuple((v // w, v % w) for v in ln.tolist()) for ln in lanes)
    want = sorted(
        [tuple((r, c) for c in cols) for r in (0, 2) for cols in ((0, 1), (2, 3, 4), (5, 6, 7))]
        + [tuple((1, c) for c in (2, 3, 4))]
    )
    assert got == want


def test_split_lane_tour_of_an_open_rectangle_is_still_a_boustrophedon():
    h, w = 6, 9
    free = np.ones((h, w), dtype=np.uint8)
    arr = lane_tour(free, np.zeros((h, w), dtype=np.int32), np.array([0]), 0, split=True)
    f = figures(np.zeros((h, w), dtype=bool), (0, 0), _cells(arr, w))
    assert f.visits == h * w and f.turns == 2 * (h - 1)


def test_best_plan_keeps_a_repaired_lane_tour_within_the_cap():
    # a paper-like wall where the lane tours repeat too much as they are;
    # repaired, a split one is within the cap and turns less than the walkers
    blocked = paper_like(2)
    start = start_cell(blocked)
    h, w = blocked.shape
    reach = reachable(blocked, start)
    free = np.zeros((h, w), dtype=np.uint8)
    for r, c in reach:
        free[r, c] = 1
    labels = np.where(free > 0, 0, -1).astype(np.int32)
    cap = int(MAX_REPETITION * len(reach))
    arr = lane_tour(free, labels, np.array([0]), start[0] * w + start[1], 1.5, split=True, kicks=10)
    raw = figures(blocked, start, _cells(arr, w))
    assert raw.visits - raw.covered > cap  # the tour alone is over the cap
    fixed = repair(free, prune(free, arr, 10), cap, len(arr))
    two_opt(free, fixed, 20)
    lane = figures(blocked, start, _cells(fixed, w))
    assert lane.visits - lane.covered <= cap
    got = figures(blocked, start, best_plan(blocked, start).cells)
    assert got.coverage == 1.0 and got.visits - got.covered <= cap
    assert got.turns <= lane.turns
