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

1. Jump-point screening (Fig. 7), ``search="jps"``: an octile cell corridor
   by jump point search (:func:`jps`, issue 4), which puts only jump points
   on the open list (``search="astar"``: plain A*'s corridor). The octile
   metric cannot tell a straight route from a staircase "elbow" of the same
   octile length, and JPS's canonical order takes the elbow — on a field of
   small obstacles the taut path of that corridor can be 1–2 % longer than
   the shortest. So JPS first runs between pins: free cells on the straight
   line from start to goal every ``CHORD_STEP`` cells (the "chord
   corridor"); as soon as a piece has to go round something (octile length
   over ``CHORD_DETOUR`` × its ends' octile distance: a wall, a room, a
   tank) the corridor is dropped and JPS runs from start to goal
   (``chord=False``: always). The pins and octile lengths are numba
   kernels (:mod:`._chord`).
2. Onto the edge nodes, any direction: string pulling, then every vertex v
   between a and b is replaced by the convex chain over the blocked-cell
   corners inside triangle (a, v, b) — the shortest path homotopic to a→v→b —
   until a pass changes nothing. The candidate corners are screened like jump
   points: only convex corners (one blocked cell of four, a "forced
   neighbour") can be turning points of a shortest path, so the others are
   pruned (``screen=False`` keeps them; the path is the same — see
   tests/planner/test_any_angle.py — from fewer candidates).
3. Homotopy repair (:mod:`._vg_repair`): the corridor may pass an obstacle on
   the side that is shorter on the grid but longer in the plane. Passes of
   windows of ``WINDOWS`` cells of path (48, 192, the whole path) replace a
   window's piece by the shortest path between its ends over the visibility
   graph of the convex corners inside the ellipse that any shorter path must
   stay in — exact for the window. The cost is quadratic in those corners,
   so a window with more than ``NODES_MAX`` of them is left: on open maps
   (the station, rooms) the long windows run and fix the side taken round a
   tank or a large wall; on a field of small obstacles only the short ones
   do, and the chord corridor has to be right at longer range. That is where
   the path can still be more than 1 % long: the taut path from the corridor
   and the 48-cell windows settle in a "lane" between small obstacles that
   is locally shortest while the shortest path runs one lane over for 90–150
   cells, whose ellipse holds 500–1100 corners (bench/fws_misses.py prints
   this per miss).
4. Second opinion: a chord-corridor path longer than ``ALT_TRIGGER`` × the
   straight line (on random512, the third of the queries where such lanes
   matter) and not proved shortest by the repair is compared with the path
   from another corridor, refined the same way, and the shorter is kept. The
   two corridors fail on different queries (fresh random512 draws, seeds
   11–20: 4 and 10 of 179 over 1.01×, none when both are tried). The other
   corridor is JPS's own, or on queries over two ``ALT_STEP`` long JPS
   between pins that far apart (JPS unpinned from start to goal costs 3–10 ms
   there; the coarse pins leave it the freedom to take another lane over 128
   cells at a fraction of that).
5. Certificate (:func:`._vg_repair.certify`), on the same paths: every path
   shorter than |path| / ``CERT_RATIO`` lies in the ellipse of that length
   round the ends, so A* over the convex corners in it either finds the
   shortest path (shorter than that; it replaces ours) or proves ours within
   ``CERT_RATIO`` of the shortest. Exact, whatever lane the corridors took:
   the fix for the misses where both corridors settle in the same wrong lane.
   Its cost is quadratic in the corners, 1–15 ms CPU with up to
   ``CERT_NODES`` (random512 queries up to ≈ 200 cells); with more it is not
   run. JPS's corridor (taken where walls and rooms make the chord detour)
   is left to the repair's long windows.

Smoothing (end of §2.2, Fig. 9(c)) is a separate step the robot applies:
:func:`smooth_path` fits a chord-length (non-uniform) cubic spline through the
vertices and pins it back towards the polyline where it would come closer
than the safety distance to a blocked cell.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass

import numpy as np

from . import _chord as C
from . import _edge_kernels as E
from . import _vg_repair as V
from ._result import _WS, as_grid_array, check_endpoint
from .astar import astar
from .grid import GridMap
from .jps import _CACHE as _JPS_CACHE
from .jps import _bits_search

log = logging.getLogger(__name__)
PASSES = 20
WINDOWS = (48.0, 192.0, math.inf)  # repair passes: window lengths in cells of path
# and the most convex corners a window's ellipse may hold (the search is quadratic in
# them); the whole path's window gets more: it alone sees a path that passes a large
# obstacle on the other side (den520d: 519 corners, 12 ms CPU, 1.0108 → 1.0)
NODES_MAX = (1500, 400, 1000)
SKIP_GAP = 0.003  # windows within 0.3 % of their chord are left
PIN_RADIUS = 2  # a pin: the free cell nearest the chord point within this many cells
CHORD_STEP = 32.0  # cells between the chord corridor's pins
CHORD_DETOUR = 1.5  # a piece longer than this × its ends' octile distance: no chord corridor
OVERLAP = 0.5
ALT_TRIGGER = 1.02  # a chord-corridor path longer than this × the straight line: JPS's too
BUCKET_MIN = 64  # a repair window with more corners is searched with them in buckets
BUCKET_THIN = 1.05  # when its piece is under this × its chord (in rooms the scan is faster)
CERT_RATIO = 1.01  # stage 5 proves the path within this of the shortest, or finds the shortest
CERT_NODES = 2000  # the most convex corners its ellipse may hold (else it is not run)
ALT_STEP = 4 * CHORD_STEP  # the second opinion's pins (JPS's own corridor under 2 steps)
ALT_SLACK = 0.01  # JPS's taut path is repaired when within this of the chord path's length

__all__ = ["AnyAngleResult", "any_angle", "clearance", "segment_valid", "smooth_path"]


@dataclass(frozen=True)
class AnyAngleResult:
    """points: [(row, col)] vertices from the start centre to the goal centre
    (empty when unreachable); length: Euclidean length in cells or None;
    expanded: nodes taken from the open list; time_ms: wall time of the query;
    search_length: the length before the taut refinement; corridor: the
    search that gave it ("chord", "jps", "astar" or "edges"; "visibility" when
    the certificate stage found a shorter path)."""

    points: list[tuple[float, float]]
    length: float | None
    expanded: int = 0
    time_ms: float = 0.0
    search_length: float | None = None
    corridor: str = ""

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
    lazy: bool = True, search: str = "jps", repair: bool = True,
    chord: bool = True,
) -> AnyAngleResult:
    """Any-angle shortest path between the centres of cells ``start`` and
    ``goal`` (each (row, col)) on a bool grid (True = blocked). ``search``:
    "jps" (default), "astar" or "edges" (see the module docstring); ``lazy``:
    the Lazy Theta* variant of "edges"; ``refine``: stages 2–3; ``repair``:
    stage 3; ``chord``: try the chord corridor before JPS's own.

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
    jm = None
    if search != "edges":
        if search == "jps":  # the cell array straight from the kernel, no tuple list
            jm = _JPS_CACHE.get(grid, grid)  # checks the array against its copy: once
            cells, expanded = None, 0
            if chord:
                cells, expanded = C.chord_corridor(grid, s, t, jm, CHORD_STEP, CHORD_DETOUR,
                                                   PIN_RADIUS)
            corridor = "chord"
            if cells is None:
                cells, more = _bits_search(jm, s, t)
                expanded += more
                corridor = "jps"
        else:
            res = astar(grid, s, t)
            cells = np.asarray(res.cells, dtype=np.int64) if res.found else None
            expanded = res.expanded
            corridor = "astar"
        if cells is None:
            return AnyAngleResult([], None, expanded, (time.perf_counter() - t0) * 1e3)
        pts = 2 * np.asarray(cells, dtype=np.int64).reshape(-1, 2) + 1
    else:
        st = _WS.get(n)
        cr, cc = _XY.get(n)
        found, expanded = E.theta_kernel(grid, s[0], s[1], t[0], t[1], *st, cr, cc, lazy)
        corridor = "edges"
        if not found:
            return AnyAngleResult([], None, int(expanded), (time.perf_counter() - t0) * 1e3)
        pts = E.trace(st[3], cr, cc, n - 2, n - 1)
    search_len = E.path_len(pts) / 2.0
    if refine:
        cum = _ROWS.get(grid, jm) if repair else None
        pts, exact = _refine(grid, pts, screen, cum)
        if corridor == "chord" and repair and not exact and _long_way(pts, s, t):
            pts, more, won = _second_opinion(grid, s, t, pts, screen, jm, cum)
            expanded += more
            corridor = "jps" if won else corridor
            pts, status = V.certify(grid, cum, pts, CERT_RATIO, CERT_NODES)
            corridor = "visibility" if status == 2 else corridor
    if len(pts) > 1:
        pts = pts[np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]]
    length = E.path_len(pts) / 2.0
    return AnyAngleResult(
        [(float(r) / 2.0, float(c) / 2.0) for r, c in pts],
        float(length),
        int(expanded),
        (time.perf_counter() - t0) * 1e3,
        float(search_len),
        corridor,
    )


def _refine(grid: np.ndarray, pts: np.ndarray, screen: bool, cum):
    """(points, exact): stages 2–3 on a corridor's vertices (half-cell units);
    no repair when ``cum`` (the map's convex-corner row counts) is None.
    exact: the path is provably the shortest (a straight segment, or the
    repair searched one window spanning it all)."""
    exact = False
    if len(pts) > 2:
        pts = E.drop_vertices(grid, pts)
        pts = E.tauten(grid, pts, screen, PASSES)
        pts = E.drop_vertices(grid, pts)
        if cum is not None and len(pts) > 2:
            pts, exact = _repair(grid, pts, cum)
    return pts, exact or len(pts) <= 2


def _long_way(pts: np.ndarray, s, t) -> bool:
    """A path longer than ``ALT_TRIGGER`` × the straight line: one that may
    have taken the wrong lane between small obstacles."""
    return E.path_len(pts) / 2.0 > ALT_TRIGGER * math.hypot(t[0] - s[0], t[1] - s[1])


def _second_opinion(grid: np.ndarray, s, t, pts: np.ndarray, screen: bool, jm, cum):
    """(points, expanded, won): a chord-corridor path more than ``ALT_TRIGGER``
    × the straight line is compared with the path from JPS's own corridor, or
    JPS's between pins every ``ALT_STEP`` cells on a query over two of them
    (taut, and repaired only when the taut path is within ``ALT_SLACK`` of
    ours); between each two vertices the paths share, the shorter stretch is
    kept (:func:`_crossover`), so the result is no longer than either. The
    pins hold the chord corridor in the "lane" between small obstacles
    nearest the straight line, while the shortest path may run a lane over
    for 90–150 cells, longer than the repair's short windows see; JPS's
    corridor is not pinned."""
    length = E.path_len(pts) / 2.0
    cells, expanded = C.chord_corridor(grid, s, t, jm, ALT_STEP, CHORD_DETOUR, PIN_RADIUS)
    if cells is None:
        cells, more = _bits_search(jm, s, t)
        expanded += more
    if cells is None:  # not reachable: cannot be, the chord corridor reached it
        return pts, expanded, False
    alt, _ = _refine(grid, 2 * np.asarray(cells, dtype=np.int64).reshape(-1, 2) + 1, screen, None)
    if E.path_len(alt) / 2.0 <= (1.0 + ALT_SLACK) * length and len(alt) > 2:
        alt, _ = _repair(grid, alt, cum)
    best = _crossover(pts, alt)
    if E.path_len(best) < 2.0 * length - 1e-9:
        return best, expanded, True
    return pts, expanded, False


def _crossover(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Two paths with the same ends (vertices k × 2): between each two
    successive vertices they share (in the order both visit them), the
    shorter of their two stretches (a's on a tie). Every stretch is one of a
    valid path between the same two points, so the result is valid, and no
    longer than a or b."""
    at = {(int(r), int(c)): j for j, (r, c) in enumerate(b.tolist())}
    ia, ib = [0], [0]
    for i, (r, c) in enumerate(a.tolist()[1:], start=1):
        j = at.get((r, c), -1)
        if j > ib[-1]:
            ia.append(i)
            ib.append(j)
    if ia[-1] != len(a) - 1 or ib[-1] != len(b) - 1:  # ends differ: not two paths of one query
        return a
    out = [a[:1]]
    for k in range(1, len(ia)):
        pa = a[ia[k - 1]:ia[k] + 1]
        pb = b[ib[k - 1]:ib[k] + 1]
        out.append((pb if E.path_len(pb) < E.path_len(pa) else pa)[1:])
    return np.concatenate(out)


class _CornerRows:
    """The convex-corner row counts (:func:`._vg_repair.corner_rows`) of the last
    few maps, keyed by the JPS cache's map object (which already checked the
    array against its copy)."""

    def __init__(self, size: int = 4) -> None:
        self.size = size
        self.lock = threading.Lock()
        self.entries: list[tuple[object, np.ndarray]] = []

    def get(self, grid: np.ndarray, key=None) -> np.ndarray:
        """``key``: the JPS cache's map of ``grid`` when the caller has it."""
        if key is None:
            key = _JPS_CACHE.get(grid, grid)
        with self.lock:
            for k, cum in self.entries:
                if k is key:
                    return cum
        cum = V.corner_rows(key.grid)
        with self.lock:
            self.entries = [(key, cum)] + [e for e in self.entries if e[0] is not key][
                : self.size - 1]
        return cum


_ROWS = _CornerRows()


def _repair(grid: np.ndarray, pts: np.ndarray, cum: np.ndarray):
    """Homotopy repair: passes of windows ``WINDOWS[k]`` cells of path long
    (each overlapping the last by half); in each, A* over the visibility graph
    of the convex corners inside the window's ellipse replaces the piece when
    it is shorter — the shortest path between the window's ends, exact for
    that window. A window whose ellipse holds more than ``NODES_MAX[k]``
    corners is left as it is (the cost is quadratic in them). Returns
    (points, exact): exact when a window spanned the whole path (the path
    is then the shortest there is)."""
    exact = False
    for win, nmax in zip(WINDOWS, NODES_MAX, strict=True):
        pts, whole = V.repair_pass(grid, cum, pts, win, nmax, SKIP_GAP, OVERLAP, BUCKET_MIN,
                                   BUCKET_THIN)
        exact = exact or whole
        if len(pts) <= 2:
            break
    return pts, exact


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
    # imported here: with scipy.optimize ≈ 0.3 s
    from scipy.interpolate import CubicSpline

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
