"""The complete-coverage plan: seed 001's steps joined (§3–4), and its figures.

1. Cells reachable from the start (the rest cannot be covered).
2. Sub-regions by the rectangle decomposition (§3.2).
3. Their order by the depth-first walk on eq. 5's matrix (§3.3), starting in
   the start's region.
4. Each region swept boustrophedon along the direction with fewer turns
   (§3.4, eqs. 2–3), by the compiled walker (:mod:`._kernels`).
5. A dead zone inside a region is left by the shortest way to the nearest
   uncovered cell of the region. This is where the f_i rule of eqs. 6–9
   steers; the rule itself is greedy and can stall in a pocket, so the plan
   takes the breadth-first shortest path (fewest cells, hence fewest
   repeats), and :func:`escape.escape` keeps the paper's rule for study.
6. A finished region hands over to the next through the nearest uncovered
   associated cell (§4, eq. 11); with ``order="nearest"`` the next region is
   the one whose associated cell is nearest, not the next in the DFS order.

Figures (Definition 7): coverage J_c = covered / reachable; repetition
J_o = (visits − distinct) / reachable; turns = changes of heading; length
in cells (a diagonal step √2).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from . import _kernels as K
from .decompose import decompose, region_boxes
from .order import adjacency_matrix, dfs_order
from .sweep import sweep_axes
from .switch import corner_table

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CoveragePlan:
    cells: list[tuple[int, int]]
    labels: np.ndarray
    order: list[int]
    axes: np.ndarray
    time_ms: float


@dataclass(frozen=True)
class CoverageFigures:
    reachable: int
    covered: int
    visits: int
    turns: int
    length: float

    @property
    def coverage(self) -> float:
        return self.covered / self.reachable if self.reachable else 1.0

    @property
    def repetition(self) -> float:
        return (self.visits - self.covered) / self.reachable if self.reachable else 0.0


def _check(blocked, start) -> tuple[np.ndarray, tuple[int, int]]:
    a = np.asarray(blocked)
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"blocked must be a non-empty 2-D array, got shape {a.shape}")
    a = a.astype(bool)
    try:
        r, c = (int(v) for v in start)
    except (TypeError, ValueError):
        raise ValueError(f"start must be (row, col), got {start!r}") from None
    if not (0 <= r < a.shape[0] and 0 <= c < a.shape[1]):
        raise ValueError(f"start {start} outside the {a.shape[0]}×{a.shape[1]} map")
    if a[r, c]:
        raise ValueError(f"start {start} is on a blocked cell")
    return a, (r, c)


WEIGHTS = np.array([0, 2, 3, 5, 6, -1, 1, 0, 0], dtype=np.int64)


def plan_coverage(blocked, start, order: str = "nearest", wrap: bool = False, weights=None, seed: int = 0) -> CoveragePlan:
    """Plan a path covering every free cell reachable from ``start``.

    order: "dfs" (§3.3's depth-first order) or "nearest" (eq. 11 over all
    unfinished regions). wrap: columns 0 and W−1 are neighbours (the seam)."""
    if order not in ("dfs", "nearest"):
        raise ValueError(f"order must be 'dfs' or 'nearest', got {order!r}")
    t0 = time.perf_counter()
    a, (r0, c0) = _check(blocked, start)
    w = a.shape[1]
    free = np.ascontiguousarray(~a, dtype=np.uint8)
    reach = K.flood(free, r0 * w + c0, wrap)
    dec = decompose(reach == 0)
    labels, count = dec.labels, dec.count
    axes = sweep_axes(labels, count)
    bbox = region_boxes(labels, count)
    corners = corner_table(labels, count)
    seq = dfs_order(adjacency_matrix(labels, count), int(labels[r0, c0])) if order == "dfs" else [int(labels[r0, c0])]
    path, _visits = K.walk(
        reach, labels, np.asarray(seq, dtype=np.int64), axes, bbox, corners, r0 * w + c0, wrap, order == "nearest",
        WEIGHTS if weights is None else np.asarray(weights, dtype=np.int64),
        seed,
    )
    cells = list(zip((path // w).tolist(), (path % w).tolist(), strict=True))
    ms = (time.perf_counter() - t0) * 1e3
    log.debug("coverage: %d cells, %d regions, %d steps, %.1f ms", int(reach.sum()), count, len(cells), ms)
    return CoveragePlan(cells, labels, seq, axes, ms)


def coverage_path(blocked, start) -> list[tuple[int, int]]:
    """The public face: a list of (row, col) from ``start``, consecutive cells
    8-adjacent, never blocked, no corner cutting, visiting every free cell
    reachable from ``start``. No wrap round the seam here. ValueError on a
    start outside the map or on a blocked cell."""
    return plan_coverage(blocked, start).cells


def figures(blocked, start, cells: list[tuple[int, int]], wrap: bool = False) -> CoverageFigures:
    """Coverage, repetition, turns and length of a path (Definition 7)."""
    a, (r0, c0) = _check(blocked, start)
    w = a.shape[1]
    reach = K.flood(np.ascontiguousarray(~a, dtype=np.uint8), r0 * w + c0, wrap)
    distinct = {p for p in cells if reach[p]}
    turns = 0
    length = 0.0
    prev = None
    for (ra, ca), (rb, cb) in zip(cells, cells[1:], strict=False):
        dr, dc = rb - ra, cb - ca
        if wrap and abs(dc) > 1:
            dc = -int(math.copysign(1, dc))
        length += math.sqrt(2.0) if dr and dc else 1.0
        if prev is not None and (dr, dc) != prev:
            turns += 1
        prev = (dr, dc)
    return CoverageFigures(int(reach.sum()), len(distinct), len(cells), turns, length)
