"""Boustrophedon sweeps and why turns cost (seed 001 §2, §3.4).

§2 models the crawler (Fig. 2): body length made of the inner distance S
between the front and rear wheels, two wheels of diameter d, the overhang m
beyond each wheel, and the probe (width D) n ahead of the front face. A
straight pass misses nothing; a U-turn about the probe's half width (Fig. 4)
starts when the probe's far edge is I from the boundary (eq. 2),

    I = √(D² + (S/2 + d + m + n)²) − (S/2 + d + m + n),

and leaves unprobed (eq. 3)

    S_UR = (S + 2I + 2n + 2m + 2d)·D − (πI/2)·(S + I + 2n + 2m + 2d).

So the sweep of each sub-region runs along the direction with fewer turns
(§3.4): lanes along the longer side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CrawlerDims:
    """The climber of seed 003 Table 1 (288 mm long, 260 mm wide) split as in
    seed 001 Fig. 2. Table 1 gives only the body; the split S + 2d + 2m =
    288 mm (wheel diameter 60 mm, 14 mm overhang) and the probe at the front
    face (n = 0) are this project's choices. D = 0.1 m, the cell size."""

    length_m: float = 0.288
    width_m: float = 0.260
    wheel_d_m: float = 0.060
    overhang_m: float = 0.014
    probe_ahead_m: float = 0.0
    probe_width_m: float = 0.100

    @property
    def inner_s_m(self) -> float:
        """S: inner distance between front and rear wheels."""
        return self.length_m - 2.0 * self.wheel_d_m - 2.0 * self.overhang_m


def turn_gap_m(dims: CrawlerDims) -> float:
    """I of eq. 2: how far from the boundary the U-turn begins."""
    a = dims.inner_s_m / 2.0 + dims.wheel_d_m + dims.overhang_m + dims.probe_ahead_m
    return math.hypot(dims.probe_width_m, a) - a


def turn_missed_area_m2(dims: CrawlerDims) -> float:
    """S_UR of eq. 3: wall left unprobed by one U-turn."""
    s, d, m, n, pd = (
        dims.inner_s_m,
        dims.wheel_d_m,
        dims.overhang_m,
        dims.probe_ahead_m,
        dims.probe_width_m,
    )
    i = turn_gap_m(dims)
    return (s + 2 * i + 2 * n + 2 * m + 2 * d) * pd - (math.pi * i / 2.0) * (
        s + i + 2 * n + 2 * m + 2 * d
    )


# ---- lanes and turns ------------------------------------------------------------


def lane_counts(labels: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Lanes per region when sweeping along rows and along columns: the number
    of maximal runs of the region's cells in each row (resp. column)."""
    pad_r = np.full((labels.shape[0], 1), -1, dtype=labels.dtype)
    left = np.hstack([pad_r, labels[:, :-1]])
    row_starts = labels[(labels >= 0) & (labels != left)]
    pad_c = np.full((1, labels.shape[1]), -1, dtype=labels.dtype)
    below = np.vstack([pad_c, labels[:-1, :]])
    col_starts = labels[(labels >= 0) & (labels != below)]
    return np.bincount(row_starts, minlength=count), np.bincount(col_starts, minlength=count)


def sweep_axes(labels: np.ndarray, count: int) -> np.ndarray:
    """Per region: 0 = lanes along rows, 1 = lanes along columns, whichever
    needs fewer U-turns (lanes − 1); rows on a tie."""
    rows, cols = lane_counts(labels, count)
    return (cols < rows).astype(np.int64)


def boustrophedon(
    y0: int, y1: int, x0: int, x1: int, entry: tuple[int, int], axis: int
) -> list[tuple[int, int]]:
    """The sweep of a free rectangle rows y0..y1 × cols x0..x1 from the corner
    ``entry`` (row, col): lanes along rows (axis 0) or columns (axis 1)."""
    er, ec = entry
    if er not in (y0, y1) or ec not in (x0, x1):
        raise ValueError(f"entry {entry} is not a corner of rows {y0}..{y1}, cols {x0}..{x1}")
    rows = list(range(y0, y1 + 1)) if er == y0 else list(range(y1, y0 - 1, -1))
    cols = list(range(x0, x1 + 1)) if ec == x0 else list(range(x1, x0 - 1, -1))
    out = []
    if axis == 0:
        for i, r in enumerate(rows):
            out.extend((r, c) for c in (cols if i % 2 == 0 else cols[::-1]))
    else:
        for i, c in enumerate(cols):
            out.extend((r, c) for r in (rows if i % 2 == 0 else rows[::-1]))
    return out


def count_turns(cells: list[tuple[int, int]]) -> int:
    """Changes of heading along a path of cells (a U-turn counts two)."""
    turns = 0
    prev = None
    for (r0, c0), (r1, c1) in zip(cells, cells[1:], strict=False):
        step = (r1 - r0, c1 - c0)
        if prev is not None and step != prev:
            turns += 1
        prev = step
    return turns
