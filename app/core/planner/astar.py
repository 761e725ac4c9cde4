"""A* on the 8-connected grid (seed 000 §4.2.1–4.2.2, eqs. 24–27).

f(n) = g(n) + h(n)                     (eq. 24)
h = |x_n − x_g| + |y_n − y_g|           Manhattan (eq. 25)
h = √((x_n − x_g)² + (y_n − y_g)²)       Euclidean (eq. 26)
h = max + (√2 − 1)·min                   octile: exact on an obstacle-free
                                         8-connected grid; the default
f(n) = g(n) + (e^h − 1)·h               the paper's improved heuristic (eq. 27)

Eq. 27 as written overflows a double once h > 709 cells and, long before that,
the weight e^h swamps g entirely (for h ≳ 37 cells g is below the last bit of
f), so the search becomes greedy best-first. We evaluate it as
(expm1(min(h/s, 600)))·h: s = 1 (default) is the paper's formula in cells, and
a larger s stretches the distance over which it still behaves like A*.
It is inadmissible: paths may be longer than optimal. The bench reports
time, length and expansions against the octile and Euclidean ones.
"""

from __future__ import annotations

import time

import numpy as np

from ._grid_search import H_EUCLIDEAN, H_IMPROVED, H_MANHATTAN, H_OCTILE
from ._result import PlanResult, as_grid_array, check_endpoint, path_length, run_search
from .grid import GridMap

HEURISTICS = {
    "octile": H_OCTILE,
    "euclidean": H_EUCLIDEAN,
    "manhattan": H_MANHATTAN,
    "improved": H_IMPROVED,
}


def astar(
    blocked: np.ndarray | GridMap,
    start: tuple[int, int],
    goal: tuple[int, int],
    heuristic: str = "octile",
    improved_scale: float = 1.0,
) -> PlanResult:
    """Shortest 8-connected path without corner cutting, in cells.

    Raises ValueError when start or goal is outside the map or blocked, or the
    heuristic is unknown. No path: ``length is None`` and ``cells == []``.
    """
    grid = as_grid_array(blocked)
    if heuristic not in HEURISTICS:
        raise ValueError(f"unknown heuristic {heuristic!r}; choose from {sorted(HEURISTICS)}")
    if not improved_scale > 0:
        raise ValueError("improved_scale must be positive")
    sr, sc = check_endpoint(grid, start, "start")
    gr, gc = check_endpoint(grid, goal, "goal")
    t0 = time.perf_counter()
    cells, expanded = run_search(
        "astar", grid, (sr, sc), (gr, gc), HEURISTICS[heuristic], float(improved_scale)
    )
    if cells is None:
        return PlanResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
    ms = (time.perf_counter() - t0) * 1e3
    return PlanResult(list(map(tuple, cells.tolist())), path_length(cells), expanded, ms)
