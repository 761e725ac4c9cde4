"""The anchors the coverage planner is compared with, on the same maps.

They live in bench/, not in app/core: the robot never runs them, they exist
only to put the planner's figures beside known methods, and keeping them
here keeps the planner package to what the climber uses. Each returns a list
of (row, col) from the start, valid under the same rules as coverage_path
(8-adjacent steps, no corner cutting); gaps between the cells a method wants
to visit are joined by the fewest-step path (travel over covered cells counts
as repetition).

- paper_method: seed 001 as described — virtual rectangles (their free
  cells given up, as the paper does), cuts, the DFS order of eq. 5, a
  boustrophedon per region from the associated cell nearest the last exit
  (eq. 11), and moves between lanes/regions by the path selection function
  f_i (eqs. 6–9), falling back to the shortest path when f_i stalls.
- bcd: boustrophedon cellular decomposition (Choset 2000) on the grid:
  column runs joined into cells at connectivity changes (critical points),
  cells ordered depth-first over their adjacency graph, each swept column by
  column.
- stc: spanning-tree coverage (Gabriely & Rimon 2001): a spanning tree
  (depth-first) over the 2×2 blocks that are wholly free, circumnavigated;
  the cells STC cannot reach (in partly blocked blocks) are then visited by
  nearest-first tours so that coverage is complete; ``stc_raw_coverage``
  says how much plain STC covered.
"""

from __future__ import annotations

import numpy as np

from app.core.planner.coverage import _kernels as K
from app.core.planner.coverage.decompose import decompose
from app.core.planner.coverage.escape import escape
from app.core.planner.coverage.order import adjacency_matrix, dfs_order
from app.core.planner.coverage.sweep import sweep_axes


class _Joiner:
    """Appends cells to a path, joining non-adjacent ones by a BFS path."""

    def __init__(self, blocked: np.ndarray, start: tuple[int, int]):
        self.free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        self.w = blocked.shape[1]
        n = blocked.size
        self.parent = np.empty(n, dtype=np.int64)
        self.stamp = np.zeros(n, dtype=np.int64)
        self.queue = np.empty(n, dtype=np.int64)
        self.gen = 0
        self.visits = np.zeros(blocked.shape, dtype=np.int32)
        self.region = np.zeros(blocked.shape, dtype=np.int32)
        self.path = [start]
        self.visits[start] += 1

    def adjacent(self, a, b) -> bool:
        dr, dc = b[0] - a[0], b[1] - a[1]
        if max(abs(dr), abs(dc)) != 1:
            return False
        return not (
            dr and dc and (not self.free[a[0] + dr, a[1]] or not self.free[a[0], a[1] + dc])
        )

    def step(self, b) -> None:
        self.path.append(b)
        self.visits[b] += 1

    def go(self, b) -> None:
        a = self.path[-1]
        if a == b:
            return
        if self.adjacent(a, b):
            self.step(b)
            return
        self.gen += 1
        w = self.w
        trip = K.bfs_path(
            self.free,
            self.visits,
            self.region,
            a[0] * w + a[1],
            b[0] * w + b[1],
            -1,
            False,
            self.parent,
            self.stamp,
            self.gen,
            self.queue,
        )
        for v in trip.tolist():
            self.step((v // w, v % w))

    def nearest_open(self, mask: np.ndarray) -> tuple[int, int] | None:
        """BFS to the nearest cell of ``mask`` not visited yet."""
        a = self.path[-1]
        w = self.w
        region = np.where(mask, 0, 1).astype(np.int32)
        self.gen += 1
        trip = K.bfs_path(
            self.free,
            self.visits,
            region,
            a[0] * w + a[1],
            -1,
            0,
            False,
            self.parent,
            self.stamp,
            self.gen,
            self.queue,
        )
        if len(trip) == 0:
            return None
        for v in trip.tolist():
            self.step((v // w, v % w))
        return self.path[-1]


def _reach(blocked, start) -> np.ndarray:
    w = blocked.shape[1]
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    return K.flood(free, start[0] * w + start[1], False).astype(bool)


def _finish(j: _Joiner, reach: np.ndarray) -> None:
    """Visit whatever the method left, nearest first."""
    while True:
        left = reach & (j.visits == 0)
        if not left.any():
            return
        if j.nearest_open(left) is None:
            return


# ---- boustrophedon cellular decomposition ------------------------------------------


def _runs(col: np.ndarray) -> list[tuple[int, int]]:
    d = np.diff(np.concatenate([[0], col.astype(np.int8), [0]]))
    return list(
        zip(np.nonzero(d == 1)[0].tolist(), (np.nonzero(d == -1)[0] - 1).tolist(), strict=True)
    )


def bcd_cells(reach: np.ndarray) -> tuple[list[list[tuple[int, int, int]]], set[tuple[int, int]]]:
    """Cells as lists of (col, lo, hi) runs, and the adjacency of cells."""
    cells: list[list[tuple[int, int, int]]] = []
    edges: set[tuple[int, int]] = set()
    prev: list[tuple[int, int, int]] = []  # (lo, hi, cell id) in the previous column
    for c in range(reach.shape[1]):
        cur = []
        runs = _runs(reach[:, c])
        for lo, hi in runs:
            over = [p for p in prev if p[0] <= hi and lo <= p[1]]
            if len(over) == 1:
                plo, phi, pid = over[0]
                back = [q for q in runs if q[0] <= phi and plo <= q[1]]
                if len(back) == 1:
                    cells[pid].append((c, lo, hi))
                    cur.append((lo, hi, pid))
                    continue
            cells.append([(c, lo, hi)])
            cid = len(cells) - 1
            cur.append((lo, hi, cid))
            for p in over:
                edges.add((min(p[2], cid), max(p[2], cid)))
        prev = cur
    return cells, edges


def bcd(blocked: np.ndarray, start: tuple[int, int]) -> list[tuple[int, int]]:
    blocked = np.asarray(blocked, dtype=bool)
    reach = _reach(blocked, start)
    cells, edges = bcd_cells(reach)
    n = len(cells)
    cen = np.array(
        [
            [np.mean([(lo + hi) / 2 for _, lo, hi in cl]), np.mean([c for c, _, _ in cl])]
            for cl in cells
        ]
    )
    a = np.full((n, n), np.inf)
    np.fill_diagonal(a, 0.0)
    for i, k in edges:
        a[i, k] = a[k, i] = float(np.hypot(*(cen[i] - cen[k])))
    first = next(
        i
        for i, cl in enumerate(cells)
        for c, lo, hi in cl
        if c == start[1] and lo <= start[0] <= hi
    )
    j = _Joiner(blocked, start)
    for cid in dfs_order(a, first):
        cl = cells[cid]
        here = j.path[-1]
        if abs(cl[-1][0] - here[1]) < abs(cl[0][0] - here[1]):
            cl = cl[::-1]
        c0, lo0, hi0 = cl[0]
        up = abs(here[0] - lo0) <= abs(here[0] - hi0)
        for c, lo, hi in cl:
            rows = range(lo, hi + 1) if up else range(hi, lo - 1, -1)
            for r in rows:
                if j.visits[r, c] == 0:
                    j.go((r, c))
            up = not up
    _finish(j, reach)
    return j.path


# ---- spanning-tree coverage --------------------------------------------------------


def stc(blocked: np.ndarray, start: tuple[int, int]) -> tuple[list[tuple[int, int]], float]:
    """(path, raw coverage of the plain STC part)."""
    blocked = np.asarray(blocked, dtype=bool)
    reach = _reach(blocked, start)
    h, w = blocked.shape
    H, W = h // 2, w // 2
    mega = reach[: 2 * H, : 2 * W].reshape(H, 2, W, 2).all(axis=(1, 3))
    j = _Joiner(blocked, start)
    if mega.any():
        ms = np.argwhere(mega)
        root = tuple(
            ms[np.argmin(np.abs(ms[:, 0] - start[0] // 2) + np.abs(ms[:, 1] - start[1] // 2))]
        )
        adj: dict[tuple[int, int], set] = {}

        def link(p, q):
            adj.setdefault(p, set()).add(q)
            adj.setdefault(q, set()).add(p)

        def unlink(p, q):
            adj[p].discard(q)
            adj[q].discard(p)

        seen = {root}
        stack = [root]
        tree = []
        while stack:  # depth-first spanning tree
            i, k = stack[-1]
            for di, dk in ((0, 1), (1, 0), (0, -1), (-1, 0)):
                q = (i + di, k + dk)
                if 0 <= q[0] < H and 0 <= q[1] < W and mega[q] and q not in seen:
                    seen.add(q)
                    tree.append(((i, k), q))
                    stack.append(q)
                    break
            else:
                stack.pop()
        for i, k in seen:
            tl, tr, br, bl = (
                (2 * i, 2 * k),
                (2 * i, 2 * k + 1),
                (2 * i + 1, 2 * k + 1),
                (2 * i + 1, 2 * k),
            )
            link(tl, tr), link(tr, br), link(br, bl), link(bl, tl)
        for (i, k), (i2, k2) in tree:
            if i2 < i or k2 < k:
                i, k, i2, k2 = i2, k2, i, k
            if i2 == i:  # side by side: join across the shared vertical side
                unlink((2 * i, 2 * k + 1), (2 * i + 1, 2 * k + 1))
                unlink((2 * i, 2 * k2), (2 * i + 1, 2 * k2))
                link((2 * i, 2 * k + 1), (2 * i, 2 * k2))
                link((2 * i + 1, 2 * k + 1), (2 * i + 1, 2 * k2))
            else:
                unlink((2 * i + 1, 2 * k), (2 * i + 1, 2 * k + 1))
                unlink((2 * i2, 2 * k), (2 * i2, 2 * k + 1))
                link((2 * i + 1, 2 * k), (2 * i2, 2 * k))
                link((2 * i + 1, 2 * k + 1), (2 * i2, 2 * k + 1))
        first = (2 * root[0], 2 * root[1])
        j.go(first)
        prev, cur = None, first
        for _ in range(len(adj) - 1):
            nxt = next(q for q in adj[cur] if q != prev)
            j.go(nxt)
            prev, cur = cur, nxt
    raw = float((j.visits > 0)[reach].mean()) if reach.any() else 1.0
    _finish(j, reach)
    return j.path, raw


# ---- seed 001 as described -------------------------------------------------------


def paper_method(
    blocked: np.ndarray, start: tuple[int, int], t: float = 0.5
) -> tuple[list[tuple[int, int]], int]:
    """(path, number of times f_i stalled and the shortest path was used)."""
    blocked = np.asarray(blocked, dtype=bool)
    reach = _reach(blocked, start)
    dec = decompose(~reach)
    labels = np.where(
        dec.inside[dec.labels] & (dec.labels >= 0), -1, dec.labels
    )  # box interiors given up
    count = dec.count
    axes = sweep_axes(labels, count)
    j = _Joiner(blocked, start)
    stalls = 0
    here_reg = int(dec.labels[start])
    a = adjacency_matrix(labels, count)
    order = dfs_order(a, here_reg if here_reg >= 0 and not dec.inside[here_reg] else 0)

    def travel(target):
        nonlocal stalls
        here = j.path[-1]
        if here == target or j.adjacent(here, target):
            j.go(target)
            return
        trial = j.visits.copy()
        steps = escape(
            blocked,
            trial,
            here,
            t=t,
            target=target,
            max_steps=4 * (abs(here[0] - target[0]) + abs(here[1] - target[1])) + 8,
        )
        if steps is None:
            stalls += 1
            j.go(target)
            return
        for p in steps:
            j.step(p)

    for reg in order:
        if dec.inside[reg]:
            continue
        rr, cc = np.nonzero(labels == reg)
        if len(rr) == 0:
            continue
        axis = axes[reg]
        here = j.path[-1]
        corners = [
            (rr.min(), cc.min()),
            (rr.min(), cc.max()),
            (rr.max(), cc.max()),
            (rr.max(), cc.min()),
        ]
        er, ec = min(corners, key=lambda p: (p[0] - here[0]) ** 2 + (p[1] - here[1]) ** 2)  # eq. 11
        lanes = sorted(
            set((cc if axis == 1 else rr).tolist()),
            reverse=bool((ec if axis == 1 else er) != (cc.min() if axis == 1 else rr.min())),
        )
        fwd = (er == rr.min()) if axis == 1 else (ec == cc.min())
        for lane in lanes:
            sel = (cc == lane) if axis == 1 else (rr == lane)
            along = np.sort((rr if axis == 1 else cc)[sel])
            if not fwd:
                along = along[::-1]
            for x in along.tolist():
                cell = (x, lane) if axis == 1 else (lane, x)
                if j.visits[cell] == 0:
                    travel(cell)
            fwd = not fwd
    return j.path, stalls
