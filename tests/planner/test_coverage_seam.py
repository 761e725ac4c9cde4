"""Coverage round the tank's seam (coverage/seam.py, lanes.py with wrap): lanes
joined across the seam, lane tours that cross it, and wrap_plan complete and
valid on random ring walls."""

import numpy as np
import pytest

from app.core.planner.coverage import figures, plan_coverage, rasterise
from app.core.planner.coverage.lanes import lane_tour, lanes_of
from app.core.planner.coverage.seam import wrap_plan, wrap_turns
from app.core.planner.coverage.wall import Band, WallSpec

from .conftest import free_cell, random_grid
from .test_coverage_path import check


def ring_reachable(blocked, start):
    """Flood fill written apart from the planner, columns 0 and W−1 neighbours:
    8 moves, no corner cutting."""
    h, w = blocked.shape
    seen = {start}
    stack = [start]
    while stack:
        r, c = stack.pop()
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, (c + dc) % w
                if not (dr or dc) or not 0 <= nr < h or blocked[nr, nc]:
                    continue
                if dr and dc and (blocked[nr, c] or blocked[r, nc]):
                    continue
                if (nr, nc) not in seen:
                    seen.add((nr, nc))
                    stack.append((nr, nc))
    return seen


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def test_lanes_of_joins_a_row_across_the_seam():
    labels = np.zeros((2, 6), dtype=np.int32)
    labels[0, 2] = -1  # row 0: runs 0–1 and 3–5, which meet across the seam
    plain = sorted(tuple(ln.tolist()) for ln in lanes_of(labels, np.array([0])))
    assert plain == [(0, 1), (3, 4, 5), (6, 7, 8, 9, 10, 11)]
    ring = sorted(tuple(ln.tolist()) for ln in lanes_of(labels, np.array([0]), wrap=True))
    assert ring == [(3, 4, 5, 0, 1), (6, 7, 8, 9, 10, 11)]  # a full row stays one lane
    cols = lanes_of(labels, np.array([1]), wrap=True)  # columns never wrap
    assert len(cols) == 6


def test_lane_tour_sweeps_through_the_seam_without_repeats():
    # a full-height wall at column 3: without the seam every row is two lanes
    h, w = 3, 8
    blocked = np.zeros((h, w), dtype=bool)
    blocked[:, 3] = True
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    labels = np.where(blocked, -1, 0).astype(np.int32)
    arr = lane_tour(free, labels, np.array([0]), 4, wrap=True)
    cells = _cells(arr, w)
    assert check(blocked, (0, 4), cells, wrap=True) == ring_reachable(blocked, (0, 4))
    f = figures(blocked, (0, 4), cells, wrap=True)
    assert f.visits == f.reachable == h * (w - 1)  # no cell twice
    assert f.turns == wrap_turns(arr, w) == 2 * (h - 1)  # one U-turn between rows


@pytest.mark.parametrize("axis", [None, 0, 1])
@pytest.mark.parametrize("density", [0.1, 0.3])
def test_wrap_plan_random_rings_complete_and_valid(rng, axis, density):
    for _ in range(10):
        h, w = int(rng.integers(1, 22)), int(rng.integers(2, 30))
        blocked = random_grid(rng, h, w, density)
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        for regions in (False, True):
            plan = wrap_plan(blocked, start, regions=regions, axis=axis)
            assert check(blocked, start, plan.cells, wrap=True) == ring_reachable(blocked, start)


@pytest.mark.parametrize(
    "circ_m, stair, axis",
    [(10.0, (3.0, 0.0, 5.0, 3.0, 0.6), None), (6.0, (2.0, 0.0, 3.0, 3.0, 0.5), 1)],
)
def test_wrap_plan_on_a_stair_divided_wall_turns_less_than_the_walker(circ_m, stair, axis):
    # a diagonal stair from the bottom to the top: no column can be cut out of
    # the ring without losing cells, only the seam joins its two sides
    spec = WallSpec(circ_m / np.pi, 3.0, 0.1, stairs=(Band(*stair),))
    blocked = rasterise(spec)
    start = (1, 1)
    reach = ring_reachable(blocked, start)
    plan = wrap_plan(blocked, start, axis=axis)
    assert check(blocked, start, plan.cells, wrap=True) == reach
    mine = figures(blocked, start, plan.cells, wrap=True)
    walker = plan_coverage(blocked, start, wrap=True, regions=False, axis=axis)
    theirs = figures(blocked, start, walker.cells, wrap=True)
    assert mine.repetition <= 0.019 < theirs.repetition
    assert mine.turns < 0.6 * theirs.turns
    if axis is not None:
        assert plan.axes.tolist() == [axis]


def test_wrap_plan_refuses_bad_input():
    blocked = np.zeros((3, 3), dtype=bool)
    blocked[1, 1] = True
    with pytest.raises(ValueError, match="blocked"):
        wrap_plan(blocked, (1, 1))
    with pytest.raises(ValueError, match="outside"):
        wrap_plan(blocked, (5, 0))
