"""coverage_path and plan_coverage on random walls: complete, valid, no
corner cutting (property-style over many seeds)."""

import numpy as np
import pytest

from app.core.planner import coverage_path
from app.core.planner.coverage import figures, plan_coverage, rasterise
from app.core.planner.coverage.wall import Band, Disc, WallSpec

from .conftest import free_cell, random_grid

pytestmark = pytest.mark.slow(65)


def reachable(blocked, start):
    """Flood fill written apart from the planner: 8 moves, no corner cutting."""
    h, w = blocked.shape
    seen = {start}
    stack = [start]
    while stack:
        r, c = stack.pop()
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, c + dc
                if (dr or dc) and 0 <= nr < h and 0 <= nc < w and not blocked[nr, nc]:
                    if dr and dc and (blocked[r + dr, c] or blocked[r, c + dc]):
                        continue
                    if (nr, nc) not in seen:
                        seen.add((nr, nc))
                        stack.append((nr, nc))
    return seen


def check(blocked, start, cells, wrap=False):
    assert cells[0] == start
    w = blocked.shape[1]
    for (r0, c0), (r1, c1) in zip(cells, cells[1:], strict=False):
        dr, dc = r1 - r0, c1 - c0
        if wrap and abs(dc) == w - 1:
            dc = -int(np.sign(dc))
        assert max(abs(dr), abs(dc)) == 1, f"step {(r0, c0)} -> {(r1, c1)}"
        assert not blocked[r1, c1]
        if dr and dc:
            assert not blocked[r0 + dr, c0] and not blocked[r0, (c0 + dc) % w], "corner cut"
    return set(cells)


@pytest.mark.parametrize("density", [0.0, 0.1, 0.25, 0.4])
def test_coverage_path_random_grids(rng, density):
    for _ in range(8):
        h, w = int(rng.integers(1, 30)), int(rng.integers(1, 30))
        blocked = random_grid(rng, h, w, density)
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        cells = coverage_path(blocked, start)
        assert check(blocked, start, cells) == reachable(blocked, start)


def _random_wall(rng):
    width, height = float(rng.uniform(3, 8)), float(rng.uniform(2, 5))

    def disc(lo, hi):
        return Disc(
            float(rng.uniform(0, width)), float(rng.uniform(0, height)), float(rng.uniform(lo, hi))
        )

    x0 = float(rng.uniform(0, width))
    return WallSpec(
        width / np.pi,
        height,
        0.1,
        manholes=(disc(0.4, 0.7),),
        nozzles=tuple(disc(0.1, 0.3) for _ in range(int(rng.integers(3, 10)))),
        stairs=(
            Band(x0, 0.0, x0 + float(rng.uniform(1, 4)), height, float(rng.uniform(0.3, 0.8))),
        ),
        seams=(
            Band(
                float(rng.uniform(0, width)), 0.5, float(rng.uniform(0, width)), height - 0.5, 0.02
            ),
        ),
    )


def test_coverage_path_random_walls(rng):
    for _ in range(6):
        blocked = rasterise(_random_wall(rng))
        start = free_cell(rng, blocked)
        cells = coverage_path(blocked, start)
        assert check(blocked, start, cells) == reachable(blocked, start)


@pytest.mark.parametrize("regions", [True, False])
@pytest.mark.parametrize("family", ["lanes", "hug", "tight"])
@pytest.mark.parametrize("order", ["dfs", "nearest"])
def test_every_variant_is_complete(rng, regions, family, order):
    for seed in range(6):
        blocked = random_grid(rng, 25, 35, 0.2)
        blocked[3:9, 5:20] = True
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        plan = plan_coverage(blocked, start, regions=regions, family=family, seed=seed, order=order)
        assert check(blocked, start, plan.cells) == reachable(blocked, start)


def test_wrapped_plan_crosses_the_seam_and_covers_both_sides():
    # a wall cut by a seam not to cross: only the wrap joins its two sides
    spec = WallSpec(4.0 / np.pi, 1.0, 0.1, seams=(Band(2.0, 0.0, 2.0, 1.0, 0.01),))
    blocked = rasterise(spec)
    plan = plan_coverage(blocked, (5, 1), wrap=True)
    seen = check(blocked, (5, 1), plan.cells, wrap=True)
    assert seen == {tuple(p) for p in np.argwhere(~blocked).tolist()}
    assert len(reachable(blocked, (5, 1))) < len(seen)  # without the wrap: one side only


def test_empty_rectangle_is_swept_without_repeats_and_two_turns_per_lane():
    blocked = np.zeros((6, 20), dtype=bool)
    cells = coverage_path(blocked, (0, 0))
    f = figures(blocked, (0, 0), cells)
    assert f.coverage == 1.0 and f.repetition == 0.0
    assert f.turns == 2 * (6 - 1)  # six lanes along the longer side


def test_bad_input_is_refused_clearly():
    blocked = np.zeros((4, 4), dtype=bool)
    blocked[1, 1] = True
    with pytest.raises(ValueError, match="blocked"):
        coverage_path(blocked, (1, 1))
    with pytest.raises(ValueError, match="outside"):
        coverage_path(blocked, (4, 0))
    with pytest.raises(ValueError, match="2-D"):
        coverage_path(np.zeros(5, dtype=bool), (0, 0))
    with pytest.raises(ValueError, match="order"):
        plan_coverage(blocked, (0, 0), order="bfs")


@pytest.mark.parametrize("axis, lanes", [(0, 6), (1, 20)])
def test_forced_sweep_axis_sets_the_lanes(axis, lanes):
    blocked = np.zeros((6, 20), dtype=bool)
    plan = plan_coverage(blocked, (0, 0), regions=False, axis=axis)
    f = figures(blocked, (0, 0), plan.cells)
    assert f.repetition == 0.0 and f.turns == 2 * (lanes - 1)


def test_given_labels_are_swept_region_by_region():
    blocked = np.zeros((8, 12), dtype=bool)
    labels = np.zeros((8, 12), dtype=np.int32)
    labels[:, 6:] = 1
    plan = plan_coverage(blocked, (0, 0), labels=labels, axis=1)
    regs = [labels[p] for p in plan.cells]
    first_right = regs.index(1)
    assert all(r == 0 for r in regs[:first_right]) and all(r == 1 for r in regs[first_right:])
    assert check(blocked, (0, 0), plan.cells) == reachable(blocked, (0, 0))


def test_straightening_keeps_the_visits_and_never_turns_more(rng):
    from collections import Counter

    from app.core.planner.coverage.plan import straightened

    for seed in range(20):
        blocked = random_grid(rng, 20, 26, 0.15)
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        plan = plan_coverage(blocked, start, regions=False, family="hug", seed=seed)
        better = straightened(blocked, plan, window=5)
        assert better.cells[0] == plan.cells[0]  # the tail may be reversed (2-opt)
        assert Counter(better.cells) == Counter(plan.cells)
        check(blocked, start, better.cells)
        assert (
            figures(blocked, start, better.cells).turns <= figures(blocked, start, plan.cells).turns
        )


def test_two_opt_reverses_a_stretch_into_lanes():
    """2 × 4 free grid: a path that crosses back and forth (6 turns) becomes
    two lanes (2 turns) by reversing stretches whose ends still join."""
    from app.core.planner.coverage.sweep import count_turns
    from app.core.planner.coverage.untwist import two_opt

    free = np.ones((2, 4), dtype=np.uint8)
    cells = [(0, 0), (0, 1), (1, 0), (1, 1), (0, 2), (0, 3), (1, 3), (1, 2)]
    assert count_turns(cells) == 6
    arr = np.array([r * 4 + c for r, c in cells], dtype=np.int64)
    assert two_opt(free, arr, 10) == 4
    out = [(int(a // 4), int(a % 4)) for a in arr]
    assert out == [(0, 0), (0, 1), (0, 2), (0, 3), (1, 3), (1, 2), (1, 1), (1, 0)]
    assert count_turns(out) == 2


def test_two_opt_never_cuts_a_corner(rng):
    """Random walls: every reversal keeps steps 8-adjacent, free and without
    corner cutting, the same visits, and turns never grow."""
    from collections import Counter

    from app.core.planner.coverage.untwist import two_opt

    for seed in range(20):
        blocked = random_grid(rng, 18, 22, 0.25)
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        plan = plan_coverage(blocked, start, regions=False, family="tight", seed=seed)
        w = blocked.shape[1]
        arr = np.array([r * w + c for r, c in plan.cells], dtype=np.int64)
        before = figures(blocked, start, plan.cells).turns
        gained = two_opt(np.ascontiguousarray(~blocked, dtype=np.uint8), arr, 20)
        out = [(int(a // w), int(a % w)) for a in arr]
        assert Counter(out) == Counter(plan.cells)
        check(blocked, start, out)
        assert figures(blocked, start, out).turns == before - gained


def test_relocate_moves_stretches_keeping_visits_and_counts_its_gain(rng):
    """Random walls: moving stretches keeps every step 8-adjacent, free and
    without corner cutting, the start and the visits; the turns fall by
    exactly the gain it reports, and it finds gains on walker paths."""
    from collections import Counter

    from app.core.planner.coverage.relocate import relocate

    total = 0
    for seed in range(20):
        blocked = random_grid(rng, 18, 22, 0.2)
        if blocked.all():
            continue
        start = free_cell(rng, blocked)
        plan = plan_coverage(blocked, start, regions=False, family="tight", seed=seed)
        w = blocked.shape[1]
        arr = np.array([r * w + c for r, c in plan.cells], dtype=np.int64)
        before = figures(blocked, start, plan.cells).turns
        gained = relocate(np.ascontiguousarray(~blocked, dtype=np.uint8), arr, 12, 20)
        out = [(int(a // w), int(a % w)) for a in arr]
        assert Counter(out) == Counter(plan.cells)
        check(blocked, start, out)
        assert figures(blocked, start, out).turns == before - gained
        total += gained
    assert total > 0


def test_relocate_leaves_a_boustrophedon_alone():
    """Three lanes of a 3 × 6 block (4 turns, the fewest): nothing to move."""
    from app.core.planner.coverage.relocate import relocate

    free = np.ones((3, 6), dtype=np.uint8)
    cells = [(0, c) for c in range(6)] + [(1, c) for c in range(5, -1, -1)]
    cells += [(2, c) for c in range(6)]
    arr = np.array([r * 6 + c for r, c in cells], dtype=np.int64)
    assert relocate(free, arr, 6, 5) == 0
    assert [(int(a // 6), int(a % 6)) for a in arr] == cells


def test_a_map_of_more_lanes_than_the_tours_take_is_planned_without_them(rng, monkeypatch):
    """Past MAX_TOUR_LANES lanes (scattered obstacles cut a map into lanes of a cell or two;
    the tours' tables grow as the square of their number) no lane tour is made, and the
    walkers' plan is complete, valid and without corner cuts."""
    from app.core.planner.coverage import lanes, plan

    monkeypatch.setattr(lanes, "MAX_TOUR_LANES", 20)
    blocked = random_grid(rng, 25, 25, 0.2)
    blocked[0, 0] = False
    start = (0, 0)
    assert plan.lane_plans(blocked, start, False) == []
    cells = coverage_path(blocked, start)
    assert check(blocked, start, cells) == reachable(blocked, start)
