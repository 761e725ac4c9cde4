"""Line of sight between cell centres and post-smoothing by it, compiled
(anyangle.py's ``shorten`` and ``line_of_sight``). Conventions as in
:mod:`._grid_search`, on the unpadded grid.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._grid_search import _sgn


@njit(cache=True)
def _free(grid, r, c):
    h, w = grid.shape
    return 0 <= r < h and 0 <= c < w and grid[r, c] == 0


@njit(cache=True)
def line_of_sight(grid, r0, c0, r1, c1):
    """True when the segment between the two cell centres crosses only free
    cells; passing exactly through a cell corner needs both side cells free
    (the same no-squeezing rule as the diagonal step). Exact integer walk."""
    if not _free(grid, r0, c0) or not _free(grid, r1, c1):
        return False
    dr = r1 - r0
    dc = c1 - c0
    sr = _sgn(dr)
    sc = _sgn(dc)
    adr = abs(dr)
    adc = abs(dc)
    r = r0
    c = c0
    i = 0
    j = 0
    while i < adc or j < adr:
        lhs = (2 * i + 1) * adr
        rhs = (2 * j + 1) * adc
        if i < adc and (j >= adr or lhs < rhs):
            c += sc
            i += 1
        elif j < adr and (i >= adc or lhs > rhs):
            r += sr
            j += 1
        else:
            if not _free(grid, r, c + sc) or not _free(grid, r + sr, c):
                return False
            r += sr
            c += sc
            i += 1
            j += 1
        if not _free(grid, r, c):
            return False
    return True


@njit(cache=True)
def shortcut_path(grid, cells):
    """Post-smoothing: from each kept vertex jump to the farthest later cell of
    the path still in line of sight. Returns the kept rows of ``cells``."""
    n = cells.shape[0]
    keep = np.empty(n, dtype=np.int64)
    if n == 0:
        return keep[:0]
    m = 0
    keep[m] = 0
    m += 1
    a = 0
    while a < n - 1:
        b = a + 1
        best = b
        # Scan forward; allow a few failures so a visible cell past a short
        # occluded stretch is still found.
        misses = 0
        while b < n:
            if line_of_sight(grid, cells[a, 0], cells[a, 1], cells[b, 0], cells[b, 1]):
                best = b
                misses = 0
            else:
                misses += 1
                if misses > 8:
                    break
            b += 1
        keep[m] = best
        m += 1
        a = best
    return keep[:m]
