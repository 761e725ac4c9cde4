import math

import numpy as np
import pytest

from app.core.planner import JpsMap, JumpTable, astar, jps
from app.core.planner._result import as_grid_array, path_length, run_search

from .conftest import dijkstra_length, free_cell, random_grid


def _check_path(blocked, res, start, goal):
    cells = res.cells
    assert cells[0] == start and cells[-1] == goal
    total = 0.0
    for (r0, c0), (r1, c1) in zip(cells, cells[1:], strict=False):
        dr, dc = r1 - r0, c1 - c0
        assert max(abs(dr), abs(dc)) == 1, "steps are to a neighbour"
        assert not blocked[r1, c1]
        if dr and dc:
            assert not blocked[r0 + dr, c0] and not blocked[r0, c0 + dc], "no corner cutting"
            total += math.sqrt(2)
        else:
            total += 1
    assert total == pytest.approx(res.length, rel=1e-9)


@pytest.mark.parametrize("planner", ["astar", "astar-euclid", "jps", "jps-map", "jps+"])
def test_optimal_against_dijkstra_on_random_grids(rng, planner):
    solved = 0
    for trial in range(150):
        h, w = int(rng.integers(2, 24)), int(rng.integers(2, 24))
        blocked = random_grid(rng, h, w, [0.1, 0.25, 0.35, 0.45][trial % 4])
        if blocked.all() or (~blocked).sum() < 2:
            continue
        s, g = free_cell(rng, blocked), free_cell(rng, blocked)
        want = dijkstra_length(blocked, s, g)
        if planner == "jps":
            res = jps(blocked, s, g)
        elif planner == "jps-map":
            res = jps(JpsMap(blocked), s, g)
        elif planner == "jps+":
            res = jps(JumpTable(blocked), s, g)
        else:
            res = astar(blocked, s, g, "euclidean" if planner.endswith("euclid") else "octile")
        if want is None:
            assert res.length is None and res.cells == []
            continue
        solved += 1
        assert res.length == pytest.approx(want, rel=1e-9), (trial, s, g)
        _check_path(blocked, res, s, g)
    assert solved > 60


def test_no_corner_cutting_through_diagonal_gap():
    # Two blocks touching at a corner: the diagonal squeeze is forbidden.
    blocked = np.zeros((4, 4), bool)
    blocked[0:2, 2] = True
    blocked[2, 0:2] = True
    blocked[0, 0:2] = False
    # (1,1) → (2,2) would pass between (1,2) and (2,1), both blocked.
    res = astar(blocked, (1, 1), (2, 2))
    assert res.length is None
    assert jps(blocked, (1, 1), (2, 2)).length is None


def test_single_blocked_corner_forbids_diagonal():
    blocked = np.zeros((2, 2), bool)
    blocked[0, 1] = True
    for plan in (astar, jps):
        res = plan(blocked, (0, 0), (1, 1))
        assert res.cells == [(0, 0), (1, 0), (1, 1)]
        assert res.length == 2.0


def test_unreachable_goal():
    blocked = np.zeros((20, 20), bool)
    blocked[:, 10] = True
    for plan in (astar, jps):
        res = plan(blocked, (0, 0), (19, 19))
        assert res.length is None and res.cells == [] and not res.found
        assert res.expanded == 200 if plan is astar else res.expanded > 0


@pytest.mark.parametrize("plan", [astar, jps])
def test_blocked_or_outside_endpoints_raise(plan):
    blocked = np.zeros((5, 5), bool)
    blocked[2, 2] = True
    with pytest.raises(ValueError, match="start .* blocked"):
        plan(blocked, (2, 2), (0, 0))
    with pytest.raises(ValueError, match="goal .* blocked"):
        plan(blocked, (0, 0), (2, 2))
    with pytest.raises(ValueError, match="outside"):
        plan(blocked, (0, 0), (5, 0))
    with pytest.raises(ValueError, match="outside"):
        plan(blocked, (-1, 0), (1, 1))


def test_start_equals_goal():
    blocked = np.zeros((3, 3), bool)
    for plan in (astar, jps):
        res = plan(blocked, (1, 1), (1, 1))
        assert res.cells == [(1, 1)] and res.length == 0.0


def test_jps_equals_astar_and_expands_fewer(rng):
    blocked = random_grid(rng, 120, 120, 0.15)
    fewer = 0
    for _ in range(20):
        s, g = free_cell(rng, blocked), free_cell(rng, blocked)
        a, j = astar(blocked, s, g), jps(blocked, s, g)
        assert (a.length is None) == (j.length is None)
        if a.length is not None:
            assert j.length == pytest.approx(a.length, rel=1e-9)
            fewer += j.expanded < a.expanded
    assert fewer >= 15


def test_heuristics_manhattan_and_improved_find_valid_paths(rng):
    blocked = random_grid(rng, 40, 40, 0.2)
    blocked[0, 0] = blocked[39, 39] = False
    opt = astar(blocked, (0, 0), (39, 39))
    assert opt.found
    for h in ("manhattan", "improved", "euclidean"):
        res = astar(blocked, (0, 0), (39, 39), heuristic=h)
        _check_path(blocked, res, (0, 0), (39, 39))
        assert res.length >= opt.length - 1e-9
    with pytest.raises(ValueError, match="heuristic"):
        astar(blocked, (0, 0), (1, 1), heuristic="chebyshev")


def test_improved_heuristic_does_not_overflow_on_long_distances():
    blocked = np.zeros((5, 3000), bool)
    res = astar(blocked, (0, 0), (4, 2999), heuristic="improved")
    assert res.found and math.isfinite(res.length)
    assert res.length >= astar(blocked, (0, 0), (4, 2999)).length - 1e-9


def _plain_jps(blocked, s, g):
    """The byte-by-byte scanning search (_jps_kernel.jps_kernel)."""
    cells, expanded = run_search("jps", as_grid_array(blocked), s, g)
    if cells is None:
        return [], None, expanded
    return list(map(tuple, cells.tolist())), path_length(cells), expanded


def test_jump_table_gives_the_scanning_search_exactly(rng):
    """JPS+ reads the same jump points from its table: same path, length and
    expansions as the plain scanning JPS, on small and larger random grids."""
    for trial in range(300):
        n = int(rng.integers(2, 40)) if trial < 250 else 150
        blocked = random_grid(rng, n, int(rng.integers(2, 40)), [0.05, 0.2, 0.35][trial % 3])
        if (~blocked).sum() < 2:
            continue
        table = JumpTable(blocked)
        for _ in range(3):
            s, g = free_cell(rng, blocked), free_cell(rng, blocked)
            b = jps(table, s, g)
            assert _plain_jps(blocked, s, g) == (b.cells, b.length, b.expanded)
    edited = np.zeros((5, 5), bool)
    table = JumpTable(edited)
    edited[:, 2] = True  # the table keeps its own copy of the map
    assert jps(table, (0, 0), (0, 4)).length == 4.0
