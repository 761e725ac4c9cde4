"""spend (coverage/spend.py): the repeats a plan's cap leaves unused bought
back as fewer turns by bridged 2-opt reversals, and best_plan using them."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage.plan import MAX_REPETITION, best_plan, plan_coverage
from app.core.planner.coverage.relocate import _index
from app.core.planner.coverage.spend import best_move, spend
from bench.coverage_maps import paper_like, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


# An open 4 × 3 wall covered without a repeat, with a zigzag at the top:
# no reversal of a stretch whose ends join in one step turns less.
OPEN = np.zeros((4, 3), dtype=bool)
ZIGZAG = [
    (0, 0), (1, 0), (2, 0), (3, 0), (3, 1), (3, 2), (2, 2), (2, 1), (1, 2),
    (0, 1), (0, 2), (1, 1),
]  # fmt: skip


def test_one_repeat_buys_two_turns_on_a_zigzag():
    free = np.ascontiguousarray(~OPEN, dtype=np.uint8)
    before = figures(OPEN, (0, 0), ZIGZAG)
    assert before.visits == before.covered == 12
    # no repeat allowed: nothing to buy (and no plain reversal helps)
    assert spend(free, _flat(ZIGZAG, 3), 0).tolist() == _flat(ZIGZAG, 3).tolist()
    out = _cells(spend(free, _flat(ZIGZAG, 3), 1), 3)
    assert check(OPEN, (0, 0), out) == reachable(OPEN, (0, 0))
    after = figures(OPEN, (0, 0), out)
    assert after.visits - after.covered == 1  # the bridge: one repeat
    assert after.turns == before.turns - 2


def test_min_gain_refuses_a_repeat_that_saves_too_little():
    free = np.ascontiguousarray(~OPEN, dtype=np.uint8)
    arr = _flat(ZIGZAG, 3)
    assert spend(free, arr, 1, 3.0).tolist() == arr.tolist()  # 2 turns < 3 per repeat


def test_spend_on_random_walks_valid_complete_within_target_fewer_turns(rng):
    for density in (0.0, 0.15, 0.3):
        for _ in range(10):
            h, w = int(rng.integers(2, 20)), int(rng.integers(2, 20))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="tight").cells
            before = figures(blocked, start, cells)
            target = before.visits - before.covered + int(rng.integers(0, 4))
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            out = _cells(spend(free, _flat(cells, w), target), w)
            assert check(blocked, start, out) == reachable(blocked, start)
            after = figures(blocked, start, out)
            assert after.visits - after.covered <= target
            assert after.turns <= before.turns


def test_best_plan_leaves_no_repeat_under_its_cap_that_would_save_a_turn():
    # paper-like tuning map 0: the plan with the fewest turns within the cap
    # used to leave four repeats of it unused
    blocked = paper_like(0)
    start = start_cell(blocked)
    cells = best_plan(blocked, start).cells
    f = figures(blocked, start, cells)
    assert f.coverage == 1.0
    budget = int(MAX_REPETITION * f.reachable) - (f.visits - f.covered)
    assert budget >= 0
    w = blocked.shape[1]
    arr = _flat(cells, w)
    first, nxt = np.full(blocked.size, -1, dtype=np.int64), np.empty(len(arr), dtype=np.int64)
    _index(arr, len(arr), first, nxt)
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    gain, added = best_move(free, arr, len(arr), w, first, nxt, budget)[:2]
    assert added < 0 or gain < added, f"a move saving {gain} turns for {added} repeats is left"
