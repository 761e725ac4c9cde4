"""best_plan's extra lane tours (coverage/extra.py): judged on the final
plan, kept only when better, so they never make a plan worse."""

import numpy as np
import pytest

from app.core.planner.coverage import figures
from app.core.planner.coverage.extra import EXTRA_SEEDS, extra_tours
from app.core.planner.coverage.plan import MAX_REPETITION, best_plan
from bench.coverage_maps import crowded, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable

pytestmark = pytest.mark.slow(34)


def _rank(blocked, start, cells):
    """best_plan's order, written apart: within the cap fewest turns, then
    fewest repeats; over it, repeats + 0.02 per turn."""
    f = figures(blocked, start, cells)
    repeats = f.visits - f.covered
    if repeats <= MAX_REPETITION * f.reachable:
        return (0, f.turns, repeats)
    return (1, repeats + 0.02 * f.turns, 0)


def test_extra_tours_are_valid_and_complete(rng):
    blocked = random_grid(rng, 24, 30, 0.15)
    start = free_cell(rng, blocked)
    reach = reachable(blocked, start)
    mask = np.zeros(blocked.shape, dtype=np.uint8)
    for r, c in reach:
        mask[r, c] = 1
    w = blocked.shape[1]
    tours = extra_tours(mask, start[0] * w + start[1], (1.5,), 48, split=True, kicks=20)
    # rows and columns × each seed, the sub-regions; each also split
    assert len(tours) == 2 * (2 * len(EXTRA_SEEDS) + 1)
    for arr in tours:
        cells = list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))
        assert check(blocked, start, cells) == reach


@pytest.mark.parametrize("density", [0.05, 0.15, 0.3])
def test_extra_candidates_never_make_a_plan_worse(rng, density):
    for _ in range(3):
        h, w = int(rng.integers(12, 36)), int(rng.integers(12, 36))
        blocked = random_grid(rng, h, w, density)
        blocked[:2, :2] = False
        start = (0, 0)
        # small maps are kicked instead of given extra tours (.kick): off here
        base = best_plan(blocked, start, extra=False, kicks=0).cells
        got = best_plan(blocked, start, kicks=0).cells
        assert check(blocked, start, got) == reachable(blocked, start)
        assert _rank(blocked, start, got) <= _rank(blocked, start, base)


def test_a_longer_searched_repaired_lane_tour_wins_on_a_crowded_wall():
    # crowded tuning wall 4: without the extra tours every candidate within
    # the cap is a walker's plan (516 turns); a lane tour searched longer
    # and repaired within the cap turns far less
    blocked = crowded(4)
    start = start_cell(blocked)
    cap = MAX_REPETITION * len(reachable(blocked, start))
    base = figures(blocked, start, best_plan(blocked, start, extra=False).cells)
    cells = best_plan(blocked, start).cells
    got = figures(blocked, start, cells)
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert got.visits - got.covered <= cap and base.visits - base.covered <= cap
    assert got.turns < 0.8 * base.turns
