"""Whether a lane's end was surely probed, as the estimate and its own
covariance put it, and the shell's edge sought when it was not.

A vertical lane crosses each of its inner cells from one side to the other, so
a height error of less than a cell still leaves the true probe in the cell's
column: only the lane's ends (and the cells the route runs sideways through:
the lane changes, the runs along an edge row, the detours) depend on the
belief's height. There the believed probe point stops within ``reach`` of the
cell's centre, and the true one lies ``e`` lower or higher; it is in the cell
only while |dy + e| < D/2. So a run's end is surely probed when the believed
point came within D/2 − k·σ_y of the centre's height, σ_y the estimate's
standard deviation of the probe point's height (seed 003's EKF covariance,
carried to the probe L/2 ahead of the axle).

On the 24 m tank every cell the detours' defaults missed (seeds 1 and 2; and
the 8 m wall's, seeds 0-2; docs/climber.md, "Sure lane ends") was such an end
near the top edge, reached with the belief 4-11 cm too high: lanes too short
to cross a girth seam (between the stair band and the top edge, or above the
last girth seam) have no height landmark but the edge, which the camera sees
within 8 cm, so a belief that far off never sees it. The filter knew: σ_y was
5 cm to 2.4 m there, where it is 1-2 cm on lanes that cross the seams. When an
end is not sure and the shell's edge lies within ``near_m``, the crawler seeks
the edge (the guarded move of :mod:`.edge_seek`) and comes back to the cell on
the corrected belief. An unsure end far from the edge (beside a manhole, a
nozzle, the stair band; about a hundred on the tank, one of them missed on seed
0) drives to the nearest height landmark instead: the fewest straight steps over
free cells to a row just across a girth seam (the camera fixes the belief's
height on crossing it) or to the top or bottom row (where the edge is sought as
above), and back to the cell on the corrected belief (:meth:`SureEnds.fix_route`,
at most ``max_steps`` cells each way; an end with no landmark that near is only
recorded, :attr:`SureEnds.unsure`).
Only the y axis is judged: the filter's x deviation (4-7 cm between
the detours to a vertical seam) is ten times its true x error on the tank (the
probe's x error's 99th percentile 0.3 σ_x), so an x test would flag half the
wall; the lanes' x is held by those detours (:mod:`.seam_detour`).

Only the estimate, its covariance and the wall's map are read; the
simulator's truth never is.
"""

from __future__ import annotations

import math

import numpy as np

from .edge_seek import BOTTOM, TOP
from .seam_detour import grid_path

__all__ = ["FIX_STEPS", "K_SIGMA", "NEAR_EDGE_M", "SureEnds", "girth_goals", "probe_sigma_y",
           "run_end", "run_ends"]

K_SIGMA = 1.0  # an end is sure when the believed point lies within D/2 − K_SIGMA·σ_y
NEAR_EDGE_M = 0.3  # an unsure end's cell centre this near the shell's edge seeks it
FIX_STEPS = 30  # the longest way (cells, one way) to a girth seam driven for an unsure end

Cell = tuple[int, int]


def run_end(cells: list[Cell], i: int) -> bool:
    """Whether the route does not cross its cell ``i`` straight up or down: the
    previous and the next cell are not the cells below and above it (in either
    order). The route's first and last cells are ends."""
    r, c = cells[i]
    prev = cells[i - 1] if i else None
    nxt = cells[i + 1] if i + 1 < len(cells) else None
    through = (prev is not None and nxt is not None and prev[1] == c == nxt[1]
               and {prev[0] - r, nxt[0] - r} == {-1, 1})
    return not through


def run_ends(cells: list[Cell]) -> set[int]:
    """The indices of the route's ends (:func:`run_end`)."""
    return {i for i in range(len(cells)) if run_end(cells, i)}


def girth_goals(seams, row: int, cell_m: float, blocked: np.ndarray) -> set[Cell]:
    """The free cells of the rows just across each crossable girth seam of the map
    from ``row`` (the row below a seam when ``row`` is above it, else the row above),
    where the seam runs: driving into one from ``row``'s side, the camera crosses
    the seam."""
    rows, cols = blocked.shape
    out: set[Cell] = set()
    for b in seams:
        if b.y0_m != b.y1_m or not getattr(b, "crossable", True):
            continue  # vertical seams; a band the crawler may not cross
        k = round(b.y0_m / cell_m)  # the first row above the seam
        goal = k - 1 if row >= k else k
        if not 0 <= goal < rows:
            continue
        lo, hi = sorted((b.x0_m, b.x1_m))
        for c in range(cols):
            if lo <= (c + 0.5) * cell_m <= hi and not blocked[goal, c]:
                out.add((goal, c))
    return out


def probe_sigma_y(cov: np.ndarray, theta: float, lead_m: float) -> float:
    """The standard deviation of the probe point's height, y + lead·sin θ, from
    the covariance of the pose (x, y, θ first)."""
    j = np.array([0.0, 1.0, lead_m * math.cos(theta)])
    return math.sqrt(max(float(j @ cov[:3, :3] @ j), 0.0))


class SureEnds:
    """The judgement of the runs' ends and the record of those not surely probed.

    ``rows``, ``cell_m``: the wall's grid; ``k``: the standard deviations the
    believed point must lie inside the cell's half-width; ``near_m``: how near the
    shell's edge an unsure end seeks it; ``blocked``, ``seams``: the wall's map, for
    the routes to a girth seam from an unsure end far from the edge (none without
    them); ``max_steps``: the longest such route worth driving (cells, one way);
    ``step_ok(a, b)``, if given, must allow each step of such a route, both ways (the
    relay's executor: the body fits along it, :mod:`.link_ends`)."""

    def __init__(self, rows: int, cell_m: float, k: float = K_SIGMA,
                 near_m: float = NEAR_EDGE_M, blocked: np.ndarray | None = None,
                 seams=(), max_steps: int = FIX_STEPS, step_ok=None) -> None:
        self.rows, self.cell_m, self.k, self.near_m = rows, cell_m, k, near_m
        self.blocked, self.seams, self.max_steps = blocked, tuple(seams), max_steps
        self.step_ok = step_ok
        self.unsure: set[Cell] = set()  # ends reached, never surely
        self.sure_cells: set[Cell] = set()
        self.seeks = 0  # edge seeks started because an end was not sure
        self.fixes = self.fix_cells = 0  # routes to a girth seam driven, cells on them

    def fix_route(self, cell: Cell) -> tuple[list[Cell], list[Cell]]:
        """The cells to drive from the unsure end ``cell`` to the nearest height
        landmark (a row just across a girth seam, or the top or bottom row, where the
        shell's edge is sought) and those back to ``cell``: fewest straight steps over
        free cells, at most ``max_steps`` each way; empty when none is that near or
        no map was given."""
        if self.blocked is None:
            return [], []
        goals = girth_goals(self.seams, cell[0], self.cell_m, self.blocked)
        cols = self.blocked.shape[1]
        goals |= {(r, c) for r in (0, self.rows - 1) for c in range(cols)
                  if not self.blocked[r, c]}
        there = grid_path(self.blocked, cell, goals, self.max_steps, self.step_ok)
        if not there:
            return [], []
        back = [*there[-2::-1], cell]
        self.fixes += 1
        self.fix_cells += len(there) + len(back)
        return there, back

    def check(self, cell: Cell, py: float,
              sigma_y: float) -> tuple[bool, int, list[Cell], list[Cell]]:
        """The first judgement of the end ``cell``, reached with the believed probe
        height ``py`` and deviation ``sigma_y``: ``(sure, side, there, back)``. When
        not sure, ``side`` is the shell's edge to seek (TOP or BOTTOM, when within
        ``near_m``; counted in :attr:`seeks`), else ``there`` and ``back`` the route
        to the nearest height landmark and back (:meth:`fix_route`; empty when none
        is near). The caller drives the remedy, judges the end again on the
        corrected belief, and records the outcome (:meth:`judged`)."""
        if self.sure(cell[0], py, sigma_y):
            return True, 0, [], []
        side = self.edge_side(cell[0])
        if side:
            self.seeks += 1
            return False, side, [], []
        there, back = self.fix_route(cell)
        return False, 0, there, back

    def sure(self, row: int, py: float, sigma_y: float) -> bool:
        """Whether the believed probe height ``py`` with deviation ``sigma_y`` is
        surely inside ``row``."""
        dy = abs(py - (row + 0.5) * self.cell_m)
        return dy + self.k * sigma_y <= self.cell_m / 2

    def edge_side(self, row: int) -> int:
        """TOP or BOTTOM when that edge of the shell lies within ``near_m`` of the
        row's centre, else 0."""
        if (self.rows - row - 0.5) * self.cell_m <= self.near_m:
            return TOP
        if (row + 0.5) * self.cell_m <= self.near_m:
            return BOTTOM
        return 0

    def judged(self, cell: Cell, sure: bool) -> None:
        """Record an end's judgement: once sure, a cell stays so."""
        if sure:
            self.sure_cells.add(cell)
            self.unsure.discard(cell)
        elif cell not in self.sure_cells:
            self.unsure.add(cell)
