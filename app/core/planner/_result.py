"""The result type shared by the grid planners, and input checks."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from ._astar_kernel import astar_kernel
from ._grid_search import trace_cells
from ._jps_kernel import jps_kernel
from ._jps_table_kernel import jps_table_kernel
from .grid import GridMap


@dataclass(frozen=True)
class PlanResult:
    """cells: [(row, col), ...] from start to goal (empty when no path);
    length: path cost in cells (None when no path); expanded: nodes expanded
    (for JPS, jump points); time_ms: wall time of the search kernel."""

    cells: list[tuple[int, int]]
    length: float | None
    expanded: int
    time_ms: float = 0.0

    @property
    def found(self) -> bool:
        return self.length is not None


def as_grid_array(blocked: np.ndarray | GridMap) -> np.ndarray:
    """C-contiguous uint8 array (1 = blocked) for the kernels."""
    if isinstance(blocked, GridMap):
        blocked = blocked.blocked
    a = np.asarray(blocked)
    if a.ndim != 2:
        raise ValueError(f"blocked must be a 2-D array, got shape {a.shape}")
    if a.dtype == np.uint8 and a.flags.c_contiguous and a.max(initial=0) <= 1:
        return a
    return np.ascontiguousarray(a != 0, dtype=np.uint8)


def check_endpoint(grid: np.ndarray, cell: tuple[int, int], name: str) -> tuple[int, int]:
    try:
        r, c = int(cell[0]), int(cell[1])
    except (TypeError, ValueError, IndexError) as exc:
        raise ValueError(f"{name} must be (row, col), got {cell!r}") from exc
    h, w = grid.shape
    if not (0 <= r < h and 0 <= c < w):
        raise ValueError(f"{name} {(r, c)} lies outside the {h}×{w} map")
    if grid[r, c]:
        raise ValueError(f"{name} {(r, c)} is on a blocked cell")
    return r, c


def path_length(cells: np.ndarray) -> float:
    """Octile length of a cell path whose steps are straight or diagonal."""
    if len(cells) < 2:
        return 0.0
    d = np.abs(np.diff(np.asarray(cells, dtype=np.int64), axis=0))
    diag = np.minimum(d[:, 0], d[:, 1])
    straight = np.maximum(d[:, 0], d[:, 1]) - diag
    return float(np.sum(straight) + np.sqrt(2.0) * np.sum(diag))


class _Workspace(threading.local):
    """Per-thread search arrays reused between queries (see _grid_search)."""

    def __init__(self) -> None:
        self.n = 0
        self.gen = 0

    def get(self, n: int):
        if n > self.n:
            self.n = n
            self.stamp = np.zeros(n, dtype=np.int32)
            self.g = np.empty(n, dtype=np.float64)
            self.parent = np.empty(n, dtype=np.int32)
            self.pos = np.empty(n, dtype=np.int32)
            self.hn = np.empty(n, dtype=np.int32)
            self.hf = np.empty(n, dtype=np.float64)
            self.hg = np.empty(n, dtype=np.float64)
            self.inc = np.empty(n, dtype=np.int8)
            self.gen = 0
        self.gen += 1
        if self.gen >= 2**31 - 1:
            self.stamp[:] = 0
            self.gen = 1
        return (self.gen, self.stamp, self.g, self.parent, self.pos, self.hn, self.hf, self.hg)


_WS = _Workspace()


def padded_flat(grid: np.ndarray) -> np.ndarray:
    """The map with a one-cell blocked border, flattened (kernel layout)."""
    h, w = grid.shape
    gp = np.ones((h + 2, w + 2), dtype=np.uint8)
    gp[1:-1, 1:-1] = grid
    return gp.ravel()


def run_search(
    kind: str, grid: np.ndarray, start, goal, hmode: int = 0, hscale: float = 1.0, prep=None
):
    """Run the A* or JPS kernel; returns (cells array or None, expanded).
    prep: (padded flat grid, jump table) of a JumpTable for kind "jps"."""
    h, w = grid.shape
    wp = w + 2
    gp = padded_flat(grid) if prep is None else prep[0]
    s = (start[0] + 1) * wp + start[1] + 1
    t = (goal[0] + 1) * wp + goal[1] + 1
    st = _WS.get(gp.size)
    if kind == "astar":
        found, expanded = astar_kernel(gp, wp, s, t, hmode, hscale, *st)
    elif prep is not None:
        found, expanded = jps_table_kernel(gp, prep[1], wp, s, t, *st, _WS.inc)
    else:
        found, expanded = jps_kernel(gp, wp, s, t, *st)
    if not found:
        return None, int(expanded)
    cells = trace_cells(st[3], t, wp) - 1
    return cells, int(expanded)
