"""Jump point search: seed 004 §2's "node screening" (节点筛选) of A*.

Instead of pushing every neighbour, a search direction is followed until a
jump point: the goal, or a cell with a forced neighbour, i.e. a side cell
that is free while the cell behind it is blocked (the no-corner-cutting form
of Harabor & Grastien's rules). Diagonal runs stop where a straight run
from them would find a jump point. Only jump points enter the open list, so
the path length equals A*'s (octile heuristic, same cost model) with far
fewer expansions. Seed 004 gives the rules as figures (Fig. 7); its
formulas were lost in the text copy.

JPS+ (Rabin's precomputed jump distances): :class:`JumpTable` stores, per
free cell and move, the distance to the next jump point (or the free run to
the wall). It depends on the map only, so it is built once per map; a query
on it reads each jump in O(1) instead of scanning — the same jump points,
expansions and paths as the scanning search. Pass it in place of the map.
"""

from __future__ import annotations

import time

import numpy as np

from . import _kernels as K
from ._result import (
    PlanResult,
    as_grid_array,
    check_endpoint,
    padded_flat,
    path_length,
    run_search,
)
from .grid import GridMap


class JumpTable:
    """A map prepared for JPS+: the padded grid and the jump distance table
    (8 int32 per cell, so 32 bytes per cell). ``build_ms`` is the one-off
    precompute time. The map is copied: later edits to the caller's array do
    not reach the table (build a new one)."""

    def __init__(self, blocked: np.ndarray | GridMap):
        t0 = time.perf_counter()
        self.grid = as_grid_array(blocked).copy()
        h, w = self.grid.shape
        self.gp = padded_flat(self.grid)
        self.table = K.build_jump_table(self.gp, w + 2)
        self.build_ms = (time.perf_counter() - t0) * 1e3

    @property
    def shape(self) -> tuple[int, int]:
        return self.grid.shape  # type: ignore[return-value]


def jps(
    blocked: np.ndarray | GridMap | JumpTable, start: tuple[int, int], goal: tuple[int, int]
) -> PlanResult:
    """Same contract as :func:`astar`; ``expanded`` counts jump points. With a
    :class:`JumpTable` the jumps are read from the table (JPS+)."""
    prep = None
    if isinstance(blocked, JumpTable):
        grid = blocked.grid
        prep = (blocked.gp, blocked.table)
    else:
        grid = as_grid_array(blocked)
    sr, sc = check_endpoint(grid, start, "start")
    gr, gc = check_endpoint(grid, goal, "goal")
    t0 = time.perf_counter()
    cells, expanded = run_search("jps", grid, (sr, sc), (gr, gc), prep=prep)
    if cells is None:
        return PlanResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
    ms = (time.perf_counter() - t0) * 1e3
    return PlanResult(list(map(tuple, cells.tolist())), path_length(cells), expanded, ms)
