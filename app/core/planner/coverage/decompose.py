"""Rectangle decomposition of the wall grid (seed 001 §3.2, Figs. 6–8).

Coordinates as in the paper: x is the column, y the row (row 0 at the bottom
of the wall). For each obstacle:

1. M(x1, y1): its cell of least x, the least y among ties;
2. N(x2, y2): its cell of greatest x, the greatest y among ties;
3. the obstacle is replaced by a virtual rectangle — here its bounding box,
   whose lower-left corner is M's column and upper-right N's column;
4. a vertical cut from M along the rectangle's left edge, both ways, until
   the map edge, an obstacle or another cut;
5. a horizontal cut from N along the rectangle's top edge, both ways, until
   the map edge, an obstacle or another cut.

The cuts split the free cells into sub-regions, each monotone along both
axes, so one boustrophedon sweep covers it (§3.4).

Two departures, both so that every free cell is still covered:

- an obstacle that fills less than half of its bounding box (a diagonal
  stair band, an L-shaped group) is split into smaller boxes, halving the
  longer side until each piece fills at least half of its box; one box round
  a stair climbing the whole wall would otherwise swallow the wall;
- free cells inside a virtual rectangle, which the paper gives up (part of
  its 1.75 % missed area, Table 2), become small sub-regions of their own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._kernels import label_regions

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class Box:
    """A virtual rectangular obstacle: rows y0..y1, columns x0..x1 inclusive.
    M = (x0, y_M) and N = (x1, y_N) are the paper's points (x, y)."""

    y0: int
    y1: int
    x0: int
    x1: int
    m: tuple[int, int]
    n: tuple[int, int]


@dataclass(frozen=True)
class Decomposition:
    """labels: region id per cell, −1 on obstacles; boxes: virtual obstacles;
    vcut[r, c]: a cut between (r, c−1) and (r, c); hcut[r, c]: a cut between
    (r, c) and (r+1, c); inside[k]: region k lies inside a virtual box."""

    labels: np.ndarray
    boxes: list[Box]
    vcut: np.ndarray
    hcut: np.ndarray
    inside: np.ndarray

    @property
    def count(self) -> int:
        return len(self.inside)


def m_n_points(cells: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]]:
    """M and N of one obstacle given its (row, col) cells (§3.2 steps 1–2),
    as (x, y) = (col, row)."""
    rows, cols = cells[:, 0], cells[:, 1]
    xmin, xmax = cols.min(), cols.max()
    m = (int(xmin), int(rows[cols == xmin].min()))
    n = (int(xmax), int(rows[cols == xmax].max()))
    return m, n


def _boxes_of(cells: np.ndarray, min_fill: float) -> list[Box]:
    """Virtual rectangles of one obstacle (§3.2 step 3), split while the
    obstacle fills less than ``min_fill`` of the box."""
    y0, x0 = cells.min(axis=0)
    y1, x1 = cells.max(axis=0)
    area = (y1 - y0 + 1) * (x1 - x0 + 1)
    if len(cells) >= min_fill * area or area <= 4:
        m, n = m_n_points(cells)
        return [Box(int(y0), int(y1), int(x0), int(x1), m, n)]
    if y1 - y0 >= x1 - x0:
        cut = (y0 + y1) // 2
        lo, hi = cells[cells[:, 0] <= cut], cells[cells[:, 0] > cut]
    else:
        cut = (x0 + x1) // 2
        lo, hi = cells[cells[:, 1] <= cut], cells[cells[:, 1] > cut]
    return _boxes_of(lo, min_fill) + _boxes_of(hi, min_fill)


def obstacle_boxes(blocked: np.ndarray, min_fill: float = 0.5) -> list[Box]:
    """Every obstacle (8-connected group of blocked cells) as virtual boxes,
    in order of their M point (least x, then least y)."""
    # imported here: scipy.ndimage alone costs ≈ 0.6 s at start
    from scipy import ndimage

    lab, n = ndimage.label(blocked, structure=_EIGHT)
    if n == 0:
        return []
    rr, cc = np.nonzero(lab)
    ids = lab[rr, cc]
    order = np.argsort(ids, kind="stable")
    rr, cc, ids = rr[order], cc[order], ids[order]
    bounds = np.searchsorted(ids, np.arange(1, n + 2))
    boxes: list[Box] = []
    for k in range(n):
        cells = np.stack([rr[bounds[k] : bounds[k + 1]], cc[bounds[k] : bounds[k + 1]]], axis=1)
        boxes.extend(_boxes_of(cells, min_fill))
    boxes.sort(key=lambda b: (b.m[0], b.m[1]))
    return boxes


def _vertical_cut(box_mask, vcut, hcut, b: Box) -> None:
    """Step 4: the cut on the column edge left of the box, both ways."""
    rows = box_mask.shape[0]
    c = b.x0
    if c == 0:
        return
    vcut[b.y0 : b.y1 + 1, c] = True
    r = b.y0 - 1
    while (
        r >= 0 and not (hcut[r, c - 1] or hcut[r, c]) and not (box_mask[r, c - 1] or box_mask[r, c])
    ):
        vcut[r, c] = True
        r -= 1
    r = b.y1 + 1
    while (
        r < rows
        and not (hcut[r - 1, c - 1] or hcut[r - 1, c])
        and not (box_mask[r, c - 1] or box_mask[r, c])
    ):
        vcut[r, c] = True
        r += 1


def _horizontal_cut(box_mask, vcut, hcut, b: Box) -> None:
    """Step 5: the cut on the row edge above the box, both ways."""
    rows, cols = box_mask.shape
    r = b.y1
    if r + 1 >= rows:
        return
    hcut[r, b.x0 : b.x1 + 1] = True
    c = b.x1 + 1
    while (
        c < cols
        and not (vcut[r, c] or vcut[r + 1, c])
        and not (box_mask[r, c] or box_mask[r + 1, c])
    ):
        hcut[r, c] = True
        c += 1
    c = b.x0 - 1
    while (
        c >= 0
        and not (vcut[r, c + 1] or vcut[r + 1, c + 1])
        and not (box_mask[r, c] or box_mask[r + 1, c])
    ):
        hcut[r, c] = True
        c -= 1


def decompose(blocked: np.ndarray, min_fill: float = 0.5) -> Decomposition:
    """Sub-regions of the free cells (§3.2): virtual rectangles, then all the
    vertical cuts from M points, then all the horizontal cuts from N points."""
    blocked = np.asarray(blocked, dtype=bool)
    rows, cols = blocked.shape
    boxes = obstacle_boxes(blocked, min_fill)
    box_mask = np.zeros_like(blocked)
    for b in boxes:
        box_mask[b.y0 : b.y1 + 1, b.x0 : b.x1 + 1] = True
    vcut = np.zeros((rows, cols + 1), dtype=np.bool_)
    hcut = np.zeros((rows, cols), dtype=np.bool_)
    for b in boxes:
        _vertical_cut(box_mask, vcut, hcut, b)
    for b in boxes:
        _horizontal_cut(box_mask, vcut, hcut, b)
    outside = np.ascontiguousarray(~box_mask, dtype=np.uint8)
    labels = label_regions(outside, vcut, hcut)
    n_out = int(labels.max()) + 1
    # Free cells inside virtual boxes: their own regions, no cuts inside.
    hollow = np.ascontiguousarray(box_mask & ~blocked, dtype=np.uint8)
    if hollow.any():
        inner = label_regions(hollow, np.zeros_like(vcut), np.zeros_like(hcut))
        labels = np.where(inner >= 0, inner + n_out, labels).astype(np.int32)
    n_all = int(labels.max()) + 1
    inside = np.zeros(n_all, dtype=bool)
    inside[n_out:] = True
    return Decomposition(labels, boxes, vcut, hcut, inside)


# ---- per-region geometry ------------------------------------------------------


def region_boxes(labels: np.ndarray, count: int) -> np.ndarray:
    """(count, 4) int64: row min, row max, col min, col max of each region."""
    rr, cc = np.nonzero(labels >= 0)
    ids = labels[rr, cc]
    out = np.empty((count, 4), dtype=np.int64)
    out[:, 0] = np.iinfo(np.int64).max
    out[:, 2] = np.iinfo(np.int64).max
    out[:, 1] = -1
    out[:, 3] = -1
    np.minimum.at(out[:, 0], ids, rr)
    np.maximum.at(out[:, 1], ids, rr)
    np.minimum.at(out[:, 2], ids, cc)
    np.maximum.at(out[:, 3], ids, cc)
    return out


def centroids(labels: np.ndarray, count: int) -> np.ndarray:
    """(count, 2) float: mean (row, col) of each region's cells (the vertices
    of Fig. 9)."""
    rr, cc = np.nonzero(labels >= 0)
    ids = labels[rr, cc]
    n = np.bincount(ids, minlength=count).astype(float)
    n[n == 0] = 1.0
    return np.stack([np.bincount(ids, rr, count) / n, np.bincount(ids, cc, count) / n], axis=1)


def adjacent_pairs(labels: np.ndarray) -> set[tuple[int, int]]:
    """Region pairs that share an edge or a point (Definition 2)."""
    pairs: set[tuple[int, int]] = set()
    views = (
        (labels[:, :-1], labels[:, 1:]),
        (labels[:-1, :], labels[1:, :]),
        (labels[:-1, :-1], labels[1:, 1:]),
        (labels[:-1, 1:], labels[1:, :-1]),
    )
    for a, b in views:
        sel = (a >= 0) & (b >= 0) & (a != b)
        if sel.any():
            lo = np.minimum(a[sel], b[sel])
            hi = np.maximum(a[sel], b[sel])
            for i, j in set(zip(lo.tolist(), hi.tolist(), strict=True)):
                pairs.add((i, j))
    return pairs
