"""kick (coverage/kick.py): iterated local search on the final plan, kicked
by random stretch exchanges; same visits, never more turns."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage.kick import kicked
from app.core.planner.coverage.plan import MAX_REPETITION, best_plan, plan_coverage
from bench.coverage_maps import paper_like, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def test_kicked_walks_keep_visits_valid_and_turn_no_more(rng):
    for density in (0.0, 0.15, 0.3):
        for _ in range(6):
            h, w = int(rng.integers(2, 16)), int(rng.integers(2, 16))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="tight").cells
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            out = _cells(kicked(free, _flat(cells, w), 10, None, 10), w)
            assert check(blocked, start, out) == reachable(blocked, start)
            assert sorted(out) == sorted(cells)  # every visit kept: same repetition
            assert figures(blocked, start, out).turns <= figures(blocked, start, cells).turns


def test_kicked_is_reproducible():
    blocked = paper_like(3)
    start = start_cell(blocked)
    w = blocked.shape[1]
    cells = plan_coverage(blocked, start, regions=False, family="lanes").cells
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    one = kicked(free, _flat(cells, w), 20, None, 10)
    two = kicked(free, _flat(cells, w), 20, None, 10)
    assert one.tolist() == two.tolist()


def test_kicks_cut_the_turns_of_a_paper_like_plan_at_the_same_repetition():
    # paper-like tuning map 4: the plan without kicks turns 206 times,
    # much of it staircase walks beside discs and the diagonal bar
    blocked = paper_like(4)
    start = start_cell(blocked)
    base = figures(blocked, start, best_plan(blocked, start, kicks=0).cells)
    cells = best_plan(blocked, start).cells
    got = figures(blocked, start, cells)
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert got.visits - got.covered <= MAX_REPETITION * got.reachable
    assert got.turns <= base.turns - 10
