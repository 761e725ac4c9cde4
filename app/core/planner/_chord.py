"""The chord corridor of the optimised A* (optimised_astar.py, stage 1): jump
point search between pins on the straight line from start to goal.

JPS's octile metric cannot tell a straight route from a staircase "elbow" of
the same octile length, and its canonical order takes the elbow; on a field
of small obstacles the taut path of that corridor can be 1–2 % longer than
the shortest. So JPS runs between pins — the free cell nearest the straight
line every ``step`` cells — and the pieces are joined; as soon as a piece has
to go round something (octile length over ``detour`` × its ends' octile
distance: a wall, a room, a tank) the corridor is dropped (None) and the
caller runs JPS from start to goal. The pins and the octile lengths are numba
kernels: a query places about ten pins and measures as many pieces.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .jps import _bits_search

SQRT2 = math.sqrt(2.0)


@njit(cache=True)
def pins(grid, sr, sc, tr, tc, k, radius):
    """The pins (m × 2) of the chord from (sr, sc) to (tr, tc) cut into k
    pieces: for each inner chord point (r, c), the free cell whose centre
    offset (row − r, col − c) is least within ``radius`` cells (Chebyshev);
    points with no free cell there get no pin."""
    h, w = grid.shape
    out = np.empty((max(k - 1, 0), 2), dtype=np.int64)
    m = 0
    for i in range(1, k):
        r = sr + (tr - sr) * i / k
        c = sc + (tc - sc) * i / k
        ir = int(r)
        ic = int(c)
        best = np.inf
        br = -1
        bc = -1
        for rr in range(max(0, ir - radius), min(h, ir + radius + 1)):
            for cc in range(max(0, ic - radius), min(w, ic + radius + 1)):
                if grid[rr, cc] != 0:
                    continue
                d = math.hypot(rr - r, cc - c)
                if d < best:
                    best = d
                    br = rr
                    bc = cc
        if br >= 0:
            out[m, 0] = br
            out[m, 1] = bc
            m += 1
    return out[:m]


@njit(cache=True)
def octile_length(cells):
    """Octile length of a cell path: straight steps 1, diagonal steps √2."""
    straight = 0
    diag = 0
    for i in range(cells.shape[0] - 1):
        dr = abs(cells[i + 1, 0] - cells[i, 0])
        dc = abs(cells[i + 1, 1] - cells[i, 1])
        lo = min(dr, dc)
        straight += max(dr, dc) - lo
        diag += lo
    return float(straight) + SQRT2 * float(diag)


def octile_between(a, b) -> float:
    dr, dc = abs(a[0] - b[0]), abs(a[1] - b[1])
    return max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)


def chord_corridor(grid: np.ndarray, s, t, m, step: float, detour: float, radius: int):
    """(cells, expanded): the JPS corridor (on the prepared map ``m``) pinned to
    the straight line from s to t every ``step`` cells, or (None, expanded)
    when a piece must go round something or the chord is under two steps."""
    k = int(math.hypot(t[0] - s[0], t[1] - s[1]) // step)
    if k < 2:
        return None, 0
    way = [s] + [(int(r), int(c)) for r, c in pins(grid, s[0], s[1], t[0], t[1], k, radius)]
    way.append(t)
    pieces, expanded = [], 0
    for a, b in zip(way[:-1], way[1:], strict=True):
        cells, e = _bits_search(m, a, b)
        expanded += e
        if cells is None or octile_length(cells) > detour * octile_between(a, b) + 2.0:
            return None, expanded
        pieces.append(cells if not pieces else cells[1:])
    return np.concatenate(pieces), expanded
