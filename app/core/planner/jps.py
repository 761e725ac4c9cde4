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
expansions and paths as the plain scanning search. Pass it in place of the map.

The scanning search itself runs on :class:`JpsMap`: the padded map plus its
rows and columns packed into 64-bit words, so a straight jump tests 64 cells
per word (JPS-B, Harabor & Grastien 2014; see ``_jps_bits``). Building one
takes well under a millisecond on 512 × 512; :func:`jps` keeps the last few it
built for plain arrays (keyed by the array object, checked against a copy of
its content, so an edited map is prepared afresh), and a planner that owns its
map passes a ``JpsMap`` and does no per-query work proportional to the map.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from . import _jps_bits as B
from ._jps_table_kernel import build_jump_table
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
        self.table = build_jump_table(self.gp, w + 2)
        self.build_ms = (time.perf_counter() - t0) * 1e3

    @property
    def shape(self) -> tuple[int, int]:
        return self.grid.shape  # type: ignore[return-value]


class JpsMap:
    """A map prepared for the bit-parallel scanning search: the padded grid
    and its rows and columns as 64-bit words (JPS-B). ``build_ms`` is the
    one-off preparation time. The map is copied: later edits to the caller's
    array do not reach it (build a new one)."""

    def __init__(self, blocked: np.ndarray | GridMap):
        t0 = time.perf_counter()
        self.grid = as_grid_array(blocked).copy()
        self.grid.flags.writeable = False
        h, w = self.grid.shape
        self.gp = padded_flat(self.grid)
        g2 = self.gp.reshape(h + 2, w + 2)
        self.rows = B.pack_lines(g2)
        self.cols = B.pack_lines(np.ascontiguousarray(g2.T))
        self.build_ms = (time.perf_counter() - t0) * 1e3

    @property
    def shape(self) -> tuple[int, int]:
        return self.grid.shape  # type: ignore[return-value]


class _Cache:
    """The last few JpsMaps built for plain arrays, keyed by the array
    object's identity and checked against the copy they hold (a byte
    comparison, much cheaper than packing), so an edited or replaced array
    gets a fresh one."""

    def __init__(self, size: int = 4) -> None:
        self.size = size
        self.lock = threading.Lock()
        self.entries: list[tuple[int, JpsMap]] = []

    def get(self, source, grid: np.ndarray) -> JpsMap:
        key = id(source)
        with self.lock:
            for i, (k, m) in enumerate(self.entries):
                if k == key and m.grid.shape == grid.shape and np.array_equal(m.grid, grid):
                    if i:
                        self.entries.insert(0, self.entries.pop(i))
                    return m
        m = JpsMap(grid)
        with self.lock:
            self.entries = [(key, m)] + [e for e in self.entries if e[0] != key][: self.size - 1]
        return m


_CACHE = _Cache()


class _Workspace(threading.local):
    """Per-thread node records and heap for the bit-parallel search, reused
    between queries: a generation stamp in each record marks what the
    current query wrote, so nothing is cleared per query."""

    def __init__(self) -> None:
        self.rec = np.zeros((0, 2), dtype=np.int64)
        self.gen = 0
        self.heap_n = 0
        self._heap(1024)
        self.moves = np.empty((8, 2), dtype=np.int64)

    def _heap(self, n: int) -> None:
        self.heap_n = n
        self.hn = np.empty(n, dtype=np.int32)
        self.hf = np.empty(n, dtype=np.float64)
        self.hg = np.empty(n, dtype=np.float64)

    def next(self, n: int):
        if len(self.rec) < n:
            self.rec = np.zeros((n, 2), dtype=np.int64)
            self.recf = self.rec.view(np.float64)
            self.gen = 0
        self.gen += 1
        if self.gen >= 2**B.GEN_BITS:
            self.rec[:] = 0
            self.gen = 1
        return self.gen

    def arrays(self):
        return self.rec, self.recf, self.hn, self.hf, self.hg, self.moves

    def grow_heap(self) -> None:
        self._heap(2 * self.heap_n)


_WS = _Workspace()


def _bits_search(m: JpsMap, start, goal):
    """(cells array in map coordinates or None, expanded)."""
    h, w = m.grid.shape
    wp = w + 2
    s = (start[0] + 1) * wp + start[1] + 1
    t = (goal[0] + 1) * wp + goal[1] + 1
    while True:
        gen = _WS.next(m.gp.size)
        status, expanded = B.jps_bits_kernel(
            m.gp, m.rows, m.cols, wp, s, t, gen, *_WS.arrays()
        )
        if status >= 0:
            break
        _WS.grow_heap()
    if status == 0:
        return None, int(expanded)
    return B.trace_rec(_WS.rec, t, wp) - 1, int(expanded)


def jps(
    blocked: np.ndarray | GridMap | JpsMap | JumpTable,
    start: tuple[int, int],
    goal: tuple[int, int],
) -> PlanResult:
    """Same contract as :func:`astar`; ``expanded`` counts jump points. With a
    :class:`JumpTable` the jumps are read from the table (JPS+); otherwise the
    bit-parallel scanning search runs on a :class:`JpsMap` (the one passed,
    or one kept for this array)."""
    if isinstance(blocked, JumpTable):
        grid = blocked.grid
        search = lambda s, g: run_search("jps", grid, s, g, prep=(blocked.gp, blocked.table))  # noqa: E731
    else:
        if isinstance(blocked, JpsMap):
            m = blocked
        else:
            m = _CACHE.get(blocked, as_grid_array(blocked))
        grid = m.grid
        search = lambda s, g: _bits_search(m, s, g)  # noqa: E731
    sr, sc = check_endpoint(grid, start, "start")
    gr, gc = check_endpoint(grid, goal, "goal")
    t0 = time.perf_counter()
    cells, expanded = search((sr, sc), (gr, gc))
    if cells is None:
        return PlanResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
    ms = (time.perf_counter() - t0) * 1e3
    return PlanResult(list(map(tuple, cells.tolist())), path_length(cells), expanded, ms)
