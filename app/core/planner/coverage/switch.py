"""Switching between sub-regions through their associated cells (seed 001 §4).

Each sub-region has four associated cells, its corners, counter-clockwise
(Fig. 15): c1 lower-left, c2 lower-right, c3 upper-right, c4 upper-left
(row 0 at the bottom). The sweep enters at one (c_in) and leaves at another
(c_out, Definition 5); the next region is entered at its associated cell
nearest to the current exit (Definition 6, eq. 11):

    d_ij_min = min d(c_i_out, c_j_in).

Eq. 10 pairs entry and exit by the parity of the number of turns
(c1⇔c2, c3⇔c4 when odd; c1⇔c4, c2⇔c3 when even). A boustrophedon that
makes an odd number of U-turns ends on the entry's side (an adjacent
corner); one that makes an even number ends at the diagonally opposite
corner, which eq. 10 as printed never pairs. So :func:`exit_cell` follows
the sweep itself: for an odd number it agrees with eq. 10's first line when
the lanes run across the c1–c2 edge.

When nothing lies between exit and entry the robot goes straight (Fig. 16);
otherwise it steers by the path selection function with the entry cell in
place of U (Fig. 17, :func:`escape.escape` with ``target``).
"""

from __future__ import annotations

import math

import numpy as np

from .decompose import region_boxes
from .escape import escape


def associated_cells(labels: np.ndarray, region: int) -> list[tuple[int, int]]:
    """c1..c4 of a region: for each corner of its bounding box, the region's
    cell nearest to it (the corner itself for a rectangle)."""
    rr, cc = np.nonzero(labels == region)
    if len(rr) == 0:
        raise ValueError(f"region {region} has no cells")
    y0, y1, x0, x1 = rr.min(), rr.max(), cc.min(), cc.max()
    out = []
    for ry, cx in ((y0, x0), (y0, x1), (y1, x1), (y1, x0)):
        i = int(np.argmin(np.abs(rr - ry) + np.abs(cc - cx)))
        out.append((int(rr[i]), int(cc[i])))
    return out


def corner_table(labels: np.ndarray, count: int) -> np.ndarray:
    """(count, 4) flat indices of c1..c4 for every region at once."""
    w = labels.shape[1]
    rr, cc = np.nonzero(labels >= 0)
    ids = labels[rr, cc]
    box = region_boxes(labels, count)
    out = np.zeros((count, 4), dtype=np.int64)
    corners = ((0, 2), (0, 3), (1, 3), (1, 2))
    for j, (bi, bj) in enumerate(corners):
        key = np.abs(rr - box[ids, bi]) + np.abs(cc - box[ids, bj])
        order = np.lexsort((key, ids))
        first = np.ones(len(order), dtype=bool)
        first[1:] = ids[order][1:] != ids[order][:-1]
        sel = order[first]
        out[ids[sel], j] = rr[sel] * w + cc[sel]
    return out


def exit_cell(
    entry: tuple[int, int], rect: tuple[int, int, int, int], axis: int
) -> tuple[int, int]:
    """c_out of a rectangle rows y0..y1 × cols x0..x1 swept from corner
    ``entry`` with lanes along rows (axis 0) or columns (axis 1)."""
    y0, y1, x0, x1 = rect
    er, ec = entry
    lanes = (y1 - y0 + 1) if axis == 0 else (x1 - x0 + 1)
    turns = lanes - 1
    far_r = y1 if er == y0 else y0
    far_c = x1 if ec == x0 else x0
    if axis == 0:  # rows: the last lane is the far row; odd turns end back at entry's column
        return (far_r, ec if turns % 2 else far_c)
    return (er if turns % 2 else far_r, far_c)


def nearest_entry(exit_rc: tuple[int, int], candidates: list[tuple[int, int]]) -> tuple[int, int]:
    """Eq. 11: the candidate associated cell nearest to the exit."""
    return min(candidates, key=lambda p: math.hypot(p[0] - exit_rc[0], p[1] - exit_rc[1]))


def straight_cells(a: tuple[int, int], b: tuple[int, int]) -> list[tuple[int, int]]:
    """The 8-connected cells of the straight run from a to b (without a)."""
    (r0, c0), (r1, c1) = a, b
    n = max(abs(r1 - r0), abs(c1 - c0))
    return [(round(r0 + (r1 - r0) * k / n), round(c0 + (c1 - c0) * k / n)) for k in range(1, n + 1)]


def switch_path(
    blocked: np.ndarray,
    visits: np.ndarray,
    exit_rc: tuple[int, int],
    entry: tuple[int, int],
    t: float = 0.5,
) -> list[tuple[int, int]] | None:
    """Cells from the exit to the next entry: straight when free (Fig. 16),
    else by f_i towards the entry (Fig. 17). None if the greedy rule stalls."""
    line = straight_cells(exit_rc, entry)
    ok = all(not blocked[r, c] for r, c in line)
    prev = exit_rc
    for r, c in line:
        dr, dc = r - prev[0], c - prev[1]
        if dr and dc and (blocked[prev[0] + dr, prev[1]] or blocked[prev[0], prev[1] + dc]):
            ok = False
        prev = (r, c)
    if ok:
        for r, c in line:
            visits[r, c] += 1
        return line
    return escape(blocked, visits, exit_rc, t=t, target=entry)
