"""Optimised A* of seed 004 §2.2: any-direction search on cell-edge nodes,
jump-point screening, and non-uniform cubic spline smoothing.

``any_angle(blocked, start, goal)`` returns a path whose vertices are cell
corners (plus the start and goal centres), each segment valid by the rule of
:mod:`._edge_kernels` (along a free boundary is fine; through a blocked
interior or a diagonal pinch is not).

Nodes on cell edges (Figs. 5–6). The seed moves the search nodes from the
cell centres to the cells' edge lines, so a path may leave a node in any
direction, and interpolates the heuristic linearly along an edge,
h(n) = (1 − b)·h(N1) + b·h(N2) for the point n at distance b from end node N1,
taking the edge point of least f as the next node (Fig. 6). With straight-line
costs the least-f point on an edge seen from a node lies at an end point or on
the straight line from the node's predecessor; so here the nodes are the edge
end points (cell corners) and a node may link straight back to its
predecessor's parent when that segment is valid — the parent rule of Theta*
(Nash et al. 2007): ``search="edges"``. It expands about as many nodes as A*
and tests a segment per expansion, 10–100 ms on the 512 × 512 maps, so the
default reaches the same edge-node path another way:

1. Jump-point screening (Fig. 7), ``search="jps"``: the octile-shortest cell
   corridor by jump point search (:func:`jps`, issue 4), which puts only jump
   points on the open list (``search="astar"``: the same search unscreened).
2. Onto the edge nodes, any direction: string pulling, then every vertex v
   between a and b is replaced by the convex chain over the blocked-cell
   corners inside triangle (a, v, b) — the shortest path homotopic to a→v→b —
   until a pass changes nothing. The candidate corners are screened like jump
   points: only convex corners (one blocked cell of four, a "forced
   neighbour") can be turning points of a shortest path, so the others are
   pruned (``screen=False`` keeps them; the path is the same — see
   tests/planner/test_any_angle.py — from fewer candidates).
3. Homotopy repair: the octile corridor may pass an obstacle on the side that
   is shorter on the grid but longer in the plane. Over windows of ~48 cells
   of path, A* on the visibility graph of the convex corners within ``band``
   cells (taut edges only, ellipse-pruned) replaces the piece when shorter.
   Routes that part for longer than a window or wider than the band are not
   compared: that is the remaining way to miss the shortest path.

Smoothing (end of §2.2, Fig. 9(c)) is a separate step the robot applies:
:func:`smooth_path` fits a chord-length (non-uniform) cubic spline through the
vertices and pins it back towards the polyline where it would come closer
than the safety distance to a blocked cell.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from . import _edge_kernels as E
from ._result import _WS, as_grid_array, check_endpoint
from .astar import astar
from .grid import GridMap
from .jps import _CACHE as _JPS_CACHE
from .jps import _bits_search

log = logging.getLogger(__name__)
PASSES = 20
BAND = 8
WINDOW = 48.0
SKIP_GAP = 0.003
OVERLAP = 0.5

__all__ = ["AnyAngleResult", "any_angle", "clearance", "segment_valid", "smooth_path"]


@dataclass(frozen=True)
class AnyAngleResult:
    """points: [(row, col)] vertices from the start centre to the goal centre
    (empty when unreachable); length: Euclidean length in cells or None;
    expanded: nodes taken from the open list; time_ms: wall time of the query;
    search_length: the length before the taut refinement."""

    points: list[tuple[float, float]]
    length: float | None
    expanded: int = 0
    time_ms: float = 0.0
    search_length: float | None = None

    @property
    def found(self) -> bool:
        return self.length is not None


class _Coords(threading.local):
    def __init__(self) -> None:
        self.n = 0

    def get(self, n: int):
        if n > self.n:
            self.n = n
            self.cr = np.zeros(n, dtype=np.int64)
            self.cc = np.zeros(n, dtype=np.int64)
        return self.cr, self.cc


_XY = _Coords()


def any_angle(
    blocked: np.ndarray | GridMap, start, goal, *, screen: bool = True, refine: bool = True,
    lazy: bool = True, search: str = "jps", band: int = BAND,
) -> AnyAngleResult:
    """Any-angle shortest path between the centres of cells ``start`` and
    ``goal`` (each (row, col)) on a bool grid (True = blocked). ``search``:
    "jps" (default), "astar" or "edges" (see the module docstring); ``lazy``:
    the Lazy Theta* variant of "edges"; ``refine``: stages 2–3; ``band``:
    the repair's band in cells (0: no repair).

    Raises ValueError for a grid that is not 2-D or an end cell that is outside
    the map or blocked."""
    t0 = time.perf_counter()
    grid = as_grid_array(blocked)
    s = check_endpoint(grid, start, "start")
    t = check_endpoint(grid, goal, "goal")
    h, w = grid.shape
    n = (h + 1) * (w + 1) + 2
    if search not in ("jps", "astar", "edges"):
        raise ValueError(f"search must be 'jps', 'astar' or 'edges', got {search!r}")
    if search != "edges":
        if search == "jps":  # the cell array straight from the kernel, no tuple list
            cells, expanded = _bits_search(_JPS_CACHE.get(grid, grid), s, t)
        else:
            res = astar(grid, s, t)
            cells = np.asarray(res.cells, dtype=np.int64) if res.found else None
            expanded = res.expanded
        if cells is None:
            return AnyAngleResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
        pts = 2 * np.asarray(cells, dtype=np.int64).reshape(-1, 2) + 1
    else:
        st = _WS.get(n)
        cr, cc = _XY.get(n)
        found, expanded = E.theta_kernel(grid, s[0], s[1], t[0], t[1], *st, cr, cc, lazy)
        if not found:
            return AnyAngleResult([], None, int(expanded), (time.perf_counter() - t0) * 1e3)
        pts = E.trace(st[3], cr, cc, n - 2, n - 1)
    search_len = E.path_len(pts) / 2.0
    if refine and len(pts) > 2:
        pts = E.drop_vertices(grid, pts)
        pts = E.tauten(grid, pts, screen, PASSES)
        pts = E.drop_vertices(grid, pts)
        if band > 0 and len(pts) > 2:
            pts = _band_repair(grid, pts, band)
    if len(pts) > 1:
        pts = pts[np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]]
    length = E.path_len(pts) / 2.0
    return AnyAngleResult(
        [(float(r) / 2.0, float(c) / 2.0) for r, c in pts],
        float(length),
        int(expanded),
        (time.perf_counter() - t0) * 1e3,
        float(search_len),
    )


class _Stamp(threading.local):
    def __init__(self) -> None:
        self.a = np.zeros(0, dtype=np.int32)

    def get(self, n: int) -> np.ndarray:
        if self.a.size < n:
            self.a = np.zeros(n, dtype=np.int32)
        return self.a


_STAMP = _Stamp()


def _band_repair(grid: np.ndarray, pts: np.ndarray, band: int) -> np.ndarray:
    """Homotopy repair: over windows of about ``window`` cells of path (each
    overlapping the last by half), the shortest path through the visibility
    graph of the convex corners within ``band`` cells replaces the window's
    piece when it is shorter. Linear in the path length; cannot switch
    between routes that part for longer than a window or wider than the band."""
    h, w = grid.shape
    stamp = _STAMP.get((h + 1) * (w + 1))
    i = 0
    while i < len(pts) - 1:
        seg = np.linalg.norm(np.diff(pts[i:].astype(np.float64), axis=0), axis=1) / 2.0
        j = i + 1 + int(np.searchsorted(np.cumsum(seg), WINDOW))
        j = min(j, len(pts) - 1)
        sub = pts[i:j + 1]
        straight = float(np.hypot(*(sub[-1] - sub[0]).astype(np.float64)))
        if len(sub) > 2 and E.path_len(sub) - straight > SKIP_GAP * straight:
            # (a piece within SKIP_GAP of its chord cannot gain more than that)
            bound2 = E.path_len(sub) + 1e-6
            nodes = E.band_nodes(grid, sub, band, bound2, stamp)
            better = E.vg_search(grid, nodes, bound2)
            if len(better) and E.path_len(better) < bound2 - 1e-6 - 1e-9:
                pts = np.vstack([pts[:i], better, pts[j + 1:]])
                j = i + len(better) - 1
        if j >= len(pts) - 1:
            break
        i = max(i + 1, j - int(OVERLAP * (j - i)))
    return pts


def segment_valid(blocked: np.ndarray | GridMap, p, q) -> bool:
    """The validity rule for a segment between two points (row, col) that are
    cell corners (integers) or cell centres (x.5)."""
    grid = as_grid_array(blocked)
    a = [int(round(2 * float(v))) for v in p]
    b = [int(round(2 * float(v))) for v in q]
    for v, orig in zip(a + b, list(p) + list(q), strict=True):
        if abs(v - 2 * float(orig)) > 1e-9:
            raise ValueError(f"segment end {orig} is not a corner or a centre")
    return bool(E.seg_free(grid, a[0], a[1], b[0], b[1]))


# ---- smoothing (§2.2, Fig. 9(c)) ----------------------------------------------------------


def clearance(blocked: np.ndarray | GridMap, points, max_cells: float = 8.0) -> np.ndarray:
    """Distance (cells) from each point (row, col) to the nearest blocked cell
    square or the map edge, capped at ``max_cells``."""
    grid = as_grid_array(blocked)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return _clearance(grid, p, float(max_cells))


def _clearance(grid: np.ndarray, p: np.ndarray, cap: float) -> np.ndarray:
    h, w = grid.shape
    out = np.full(len(p), cap)
    k = int(np.ceil(cap)) + 1
    for i, (r, c) in enumerate(p):
        best = min(cap, r, c, h - r, w - c)
        r0, r1 = max(0, int(r) - k), min(h, int(r) + k + 1)
        c0, c1 = max(0, int(c) - k), min(w, int(c) + k + 1)
        win = grid[r0:r1, c0:c1]
        rr, cc = np.nonzero(win)
        if len(rr):
            rr = rr + r0
            cc = cc + c0
            dr = np.maximum(0.0, np.maximum(rr - r, r - (rr + 1)))
            dc = np.maximum(0.0, np.maximum(cc - c, c - (cc + 1)))
            best = min(best, float(np.min(np.hypot(dr, dc))))
        out[i] = best
    return out


def _spline(pts: np.ndarray, step: float) -> np.ndarray:
    """Chord-length (non-uniform) natural cubic spline through pts, sampled
    about every ``step`` cells."""
    u = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    cs = CubicSpline(u, pts, bc_type="natural")
    n = max(2, int(np.ceil(u[-1] / step)) + 1)
    return cs(np.linspace(0.0, u[-1], n))


def smooth_path(
    blocked: np.ndarray | GridMap, points, safety_cells: float = 1.0, step: float = 0.25,
    max_rounds: int = 10,
) -> np.ndarray:
    """A smooth curve (N × 2, (row, col)) through the path's vertices that
    keeps at least ``safety_cells`` from every blocked cell (or, when the
    polyline itself comes closer, as much as the polyline keeps).

    Plan on a map inflated by the safety distance so the polyline keeps it;
    where a spline sample comes closer, knots are added a quarter of the way
    along the two segments around the nearest vertex (pinning the spline to
    the polyline there) and the spline is refitted. After ``max_rounds`` the
    densified polyline is returned."""
    grid = as_grid_array(blocked)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    keep = np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]
    pts = pts[keep]
    poly = _densify(pts, step)
    if len(pts) < 3:
        return poly
    need = min(safety_cells, float(np.min(_clearance(grid, poly, safety_cells + 1.0))))
    if need < safety_cells - 1e-6:
        log.debug("smooth_path: the polyline keeps only %.2f cells; holding the spline to that",
                  need)
    knots = pts
    for _ in range(max_rounds):
        curve = _spline(knots, step)
        cl = _clearance(grid, curve, safety_cells + 1.0)
        bad = np.nonzero(cl < need - 1e-6)[0]
        if len(bad) == 0:
            return curve
        d = np.linalg.norm(curve[bad][:, None, :] - knots[None, :, :], axis=2)
        corners = set(int(i) for i in np.argmin(d, axis=1))
        new = [knots[0]]
        for i in range(1, len(knots)):
            a, b = knots[i - 1], knots[i]
            if (i - 1) in corners:
                new.append(a + 0.25 * (b - a))
            if i in corners:
                new.append(a + 0.75 * (b - a))
            new.append(b)
        knots = np.asarray(new)
    log.debug("smooth_path: the spline kept cutting the safety distance; using the polyline")
    return poly


def _densify(pts: np.ndarray, step: float) -> np.ndarray:
    if len(pts) < 2:
        return pts.copy()
    out = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out.append(a + np.linspace(0, 1, n + 1)[1:, None] * (b - a))
    return np.vstack(out)
