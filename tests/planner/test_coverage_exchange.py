"""exchange (coverage/exchange.py): two neighbouring stretches of a coverage
path swapped (and turned round) when the joins are moves and turns fall;
checked against a brute force written apart from the kernel."""

import numpy as np

from app.core.planner.coverage import figures
from app.core.planner.coverage.exchange import MOVES_AT_MOST, _best_at, exchange
from app.core.planner.coverage.plan import plan_coverage
from app.core.planner.coverage.relocate import _index

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def _turns(cells):
    steps = [(b[0] - a[0], b[1] - a[1]) for a, b in zip(cells, cells[1:], strict=False)]
    return sum(s != t for s, t in zip(steps, steps[1:], strict=False))


def _valid(blocked, cells):
    for (r0, c0), (r1, c1) in zip(cells, cells[1:], strict=False):
        dr, dc = r1 - r0, c1 - c0
        if max(abs(dr), abs(dc)) != 1 or blocked[r1, c1]:
            return False
        if dr and dc and (blocked[r0 + dr, c0] or blocked[r0, c0 + dc]):
            return False
    return True


def _brute_best(blocked, cells, i):
    """The most turns any of the four exchanges with B starting at p_i removes
    (B, C of at least two cells each), by building every new path."""
    n, old, best = len(cells), _turns(cells), 0
    for j in range(i + 1, n):
        for k in range(j + 2, n):
            a, b, c, d = cells[:i], cells[i : j + 1], cells[j + 1 : k + 1], cells[k + 1 :]
            for new in (a + c + b + d, a + c + b[::-1] + d, a + c[::-1] + b + d,
                        a + b[::-1] + c[::-1] + d):  # fmt: skip
                if _valid(blocked, new):
                    best = max(best, old - _turns(new))
    return best


# An open 4 × 4 wall: the second row left half-swept, cut diagonally to the
# lower rows, and finished last (8 turns); the boustrophedon turns 6 times.
OPEN = np.zeros((4, 4), dtype=bool)
OUT_OF_ORDER = [
    (0, 0), (0, 1), (0, 2), (0, 3), (1, 3), (1, 2), (2, 1), (2, 2), (2, 3),
    (3, 3), (3, 2), (3, 1), (3, 0), (2, 0), (1, 0), (1, 1),
]  # fmt: skip


def test_two_stretches_swapped_into_a_boustrophedon():
    free = np.ascontiguousarray(~OPEN, dtype=np.uint8)
    arr = _flat(OUT_OF_ORDER, 4)
    gained = exchange(free, arr, 5)
    out = _cells(arr, 4)
    assert check(OPEN, (0, 0), out) == reachable(OPEN, (0, 0))
    assert sorted(out) == sorted(OUT_OF_ORDER)  # same visits
    assert _turns(out) == _turns(OUT_OF_ORDER) - gained
    assert _turns(OUT_OF_ORDER) == 8 and _turns(out) == 6


def test_best_exchange_at_each_cut_matches_brute_force(rng):
    for density in (0.0, 0.2):
        for _ in range(8):
            h, w = int(rng.integers(3, 7)), int(rng.integers(3, 7))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="tight").cells
            if len(cells) < 5:
                continue
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            arr = _flat(cells, w)
            first = np.full(blocked.size, -1, dtype=np.int64)
            nxt = np.empty(len(arr), dtype=np.int64)
            _index(arr, len(arr), first, nxt)
            buf = np.empty((MOVES_AT_MOST, 4), dtype=np.int64)
            for i in range(1, len(cells) - 3):
                gain = _best_at(free, arr, len(arr), w, i, first, nxt, buf)[0]
                assert gain == _brute_best(blocked, cells, i), (cells, i)


def test_exchange_on_random_walks_keeps_visits_valid_and_counts_its_gain(rng):
    for density in (0.0, 0.15, 0.3):
        for _ in range(10):
            h, w = int(rng.integers(2, 20)), int(rng.integers(2, 20))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            cells = plan_coverage(blocked, start, regions=False, family="tight").cells
            before = figures(blocked, start, cells)
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            arr = _flat(cells, w)
            gained = exchange(free, arr, 10)
            out = _cells(arr, w)
            assert check(blocked, start, out) == reachable(blocked, start)
            assert sorted(out) == sorted(cells)
            assert figures(blocked, start, out).turns == before.turns - gained
