"""prune (coverage/prune.py): drops visits a path does not need, never adds
a turn, keeps the path valid and complete."""

import numpy as np

from app.core.planner.coverage import figures, plan_coverage
from app.core.planner.coverage.prune import prune

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def test_a_needless_return_is_dropped():
    # two lanes, then back along the first lane's end: the return is repetition
    blocked = np.zeros((2, 4), dtype=bool)
    cells = [(0, 0), (0, 1), (0, 2), (0, 3), (1, 3), (1, 2), (1, 1), (1, 0), (0, 0)]
    out = _cells(prune(np.ones((2, 4), dtype=np.uint8), _flat(cells, 4), 5), 4)
    assert out == cells[:-1]
    assert figures(blocked, (0, 0), out).repetition == 0.0


def test_a_repeat_whose_drop_would_add_turns_stays():
    # (0, 2) is visited twice; dropping its first visit would replace the
    # corner at (0, 2) by a diagonal jog with two turns, so only the second,
    # the path's last cell, goes
    free = np.ones((3, 3), dtype=np.uint8)
    cells = [(0, 0), (0, 1), (0, 2), (1, 2), (2, 2), (2, 1), (2, 0), (1, 0), (1, 1), (0, 2)]
    assert _cells(prune(free, _flat(cells, 3), 5), 3) == cells[:-1]


def test_a_path_without_repeats_is_unchanged():
    free = np.ones((3, 3), dtype=np.uint8)
    arr = _flat([(1, 0), (1, 1), (1, 2), (0, 2), (0, 1), (0, 0)], 3)
    assert prune(free, arr, 5).tolist() == arr.tolist()


def test_prune_on_walker_paths_valid_complete_no_more_turns(rng):
    for density in (0.1, 0.25, 0.4):
        for _ in range(8):
            h, w = int(rng.integers(2, 25)), int(rng.integers(2, 25))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="lanes").cells
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            out = _cells(prune(free, _flat(cells, w), 10), w)
            assert check(blocked, start, out) == reachable(blocked, start)
            before, after = figures(blocked, start, cells), figures(blocked, start, out)
            assert after.turns <= before.turns
            assert after.visits <= before.visits
