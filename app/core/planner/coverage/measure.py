"""A coverage plan's figures (seed 001, Definition 7) and the checks of a plan's inputs.

Coverage J_c = covered / reachable; repetition J_o = (visits − distinct) /
reachable; turns = changes of heading (a U-turn two, a diagonal jog two); length in
cells (a diagonal step √2). ``wrap``: the wall's left and right edges are neighbours
(the seam).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _kernels as K


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
