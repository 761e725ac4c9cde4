"""The result type shared by the grid planners, and input checks."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

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
    extra: dict = field(default_factory=dict, compare=False)

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
