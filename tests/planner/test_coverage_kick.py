"""kick (coverage/kick.py): iterated local search on the final plan, kicked
by random stretch exchanges; same visits, never more turns; with a cap, the
repeats moved too (a repeat dropped, the cap's room spent again)."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage import plan as plan_module
from app.core.planner.coverage.exchange import exchange
from app.core.planner.coverage.kick import droppable, kicked
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


def test_droppable_visits_are_repeats_whose_neighbours_join():
    # 2 × 2 open: cell 1 visited twice; both its visits may go (0 → 3 is a
    # legal diagonal, 3 → 2 a step); cell 3's one visit may not
    free = np.ones((2, 2), dtype=np.uint8)
    path = np.array([0, 1, 3, 1, 2], dtype=np.int64)
    assert droppable(free, path).tolist() == [1, 3]
    # with cell 2 blocked, 0 → 3 would cut its corner
    free[1, 0] = 0
    assert droppable(free, np.array([0, 1, 3, 1], dtype=np.int64)).tolist() == []
    # 2 × 3 open: cell 1's first visit sits between 0 and 2 (two apart), its
    # second between 4 and 3 (a step): only the second may go
    free = np.ones((2, 3), dtype=np.uint8)
    path = np.array([0, 1, 2, 5, 4, 1, 3], dtype=np.int64)
    assert droppable(free, path).tolist() == [5]


def test_kicks_that_move_repeats_stay_complete_valid_and_within_the_cap(rng):
    for density in (0.0, 0.15, 0.3):
        for _ in range(6):
            h, w = int(rng.integers(3, 16)), int(rng.integers(3, 16))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="tight").cells
            base = figures(blocked, start, cells)
            cap = base.visits - base.covered + 2  # room for two more repeats
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            out = _cells(kicked(free, _flat(cells, w), 10, None, 10, cap=cap), w)
            got = figures(blocked, start, out)
            assert check(blocked, start, out) == reachable(blocked, start)
            assert got.visits - got.covered <= cap
            assert got.turns <= base.turns


def test_kicks_over_the_cap_never_repeat_more_than_their_input():
    blocked = paper_like(2)
    start = start_cell(blocked)
    w = blocked.shape[1]
    cells = plan_coverage(blocked, start, regions=False, family="tight").cells
    base = figures(blocked, start, cells)
    assert base.visits - base.covered > 3  # the walk is over the cap below
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    one = kicked(free, _flat(cells, w), 8, None, 10, cap=3)
    two = kicked(free, _flat(cells, w), 8, None, 10, cap=3)
    assert one.tolist() == two.tolist()  # seeded: reproducible
    got = figures(blocked, start, _cells(one, w))
    assert got.visits - got.covered <= base.visits - base.covered
    assert got.turns <= base.turns
    assert got.covered == base.reachable


def test_moving_repeats_cuts_the_turns_of_a_paper_like_plan(monkeypatch):
    # paper-like tuning map 1: with the visits fixed the kicks leave 159
    # turns; moving the repeats too (same number of kicks, same cap) 143
    blocked = paper_like(1)
    start = start_cell(blocked)
    monkeypatch.setattr(plan_module, "KICK_DROPS", 0)
    fixed = figures(blocked, start, best_plan(blocked, start).cells)
    monkeypatch.undo()
    cells = best_plan(blocked, start).cells
    got = figures(blocked, start, cells)
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert got.visits - got.covered <= MAX_REPETITION * got.reachable
    assert got.turns <= fixed.turns - 10


def test_kicks_without_exchanges_end_exchanged():
    # the local search after each kick leaves stretch exchanges out; the
    # plan it returns has had them once at the end, so none is left to gain
    blocked = paper_like(3)
    start = start_cell(blocked)
    w = blocked.shape[1]
    cells = plan_coverage(blocked, start, regions=False, family="lanes").cells
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    out = kicked(free, _flat(cells, w), 10, None, 10, exchanges=0, final_exchanges=50)
    assert check(blocked, start, _cells(out, w)) == reachable(blocked, start)
    assert sorted(_cells(out, w)) == sorted(cells)
    assert exchange(free, out.copy(), 50) == 0
    bare = kicked(free, _flat(cells, w), 10, None, 10, exchanges=0)
    assert exchange(free, bare.copy(), 50) > 0  # without the last pass some were left
