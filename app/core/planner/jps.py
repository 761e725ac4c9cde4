"""Jump point search: seed 004 §2's "node screening" (节点筛选) of A*.

Instead of pushing every neighbour, a search direction is followed until a
jump point: the goal, or a cell with a forced neighbour, i.e. a side cell
that is free while the cell behind it is blocked (the no-corner-cutting form
of Harabor & Grastien's rules). Diagonal runs stop where a straight run
from them would find a jump point. Only jump points enter the open list, so
the path length equals A*'s (octile heuristic, same cost model) with far
fewer expansions. Seed 004 gives the rules as figures (Fig. 7); its
formulas were lost in the text copy.
"""

from __future__ import annotations

import time

import numpy as np

from ._result import PlanResult, as_grid_array, check_endpoint, path_length, run_search
from .grid import GridMap


def jps(blocked: np.ndarray | GridMap, start: tuple[int, int], goal: tuple[int, int]) -> PlanResult:
    """Same contract as :func:`astar`; ``expanded`` counts jump points."""
    grid = as_grid_array(blocked)
    sr, sc = check_endpoint(grid, start, "start")
    gr, gc = check_endpoint(grid, goal, "goal")
    t0 = time.perf_counter()
    cells, expanded = run_search("jps", grid, (sr, sc), (gr, gc))
    if cells is None:
        return PlanResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
    ms = (time.perf_counter() - t0) * 1e3
    return PlanResult(list(map(tuple, cells.tolist())), path_length(cells), expanded, ms)
