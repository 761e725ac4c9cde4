"""Detours to a vertical seam, so that the belief's x is fixed before it has
drifted half a cell.

On vertical lanes the camera sees a vertical seam only on the lanes that run
along one, and on the tank those are 47 lanes apart (8 plates a course, the
courses staggered by half a plate: every 4.71 m, alternately in the top and the
bottom course). Between two such lanes the believed x drifts a few millimetres
a lane, 5-8 cm in all, and once it passes half a cell (5 cm) a lane is driven
over its neighbour's column and a column goes unprobed, although the robot
believes it probed it (docs/climber.md: the tank's lost lanes).

A correction after the fact cannot tell which lane crossed: one fix gives the
drift at its own moment only, and the drift does not grow evenly over the lanes
(an estimate of the crossing lane from the share of the filter's variance
growth was measured 1-15 lanes off). So the drift is kept short instead: after
``max_lanes`` lane changes without an x fix (a vertical seam or a rim seen), at
the next lane's end the crawler drives along its row to the nearest vertical
seam that crosses that row, lets the camera see it, and drives back. The route
is a fewest-step path over free cells with straight moves only (4-adjacent,
round the wall's seam): with turns in place (:mod:`.turns`) it is driven as the
lanes are, facing along each leg, where gravity's along-track slip does not
act sideways.

With :attr:`SeamDetour.any_row` (off by default) the detour goes to the nearest
cell that any vertical seam crosses, on any row, by the way with the fewest steps
and of those the fewest turns (:func:`straight_path`), and back the same way:
where an obstacle cuts a course's seams off (the tank's wedge between the stair
band and the top edge) the nearest seam may be a few rows up or down but 60-80
cells along the lane end's row (docs/climber.md, "Detours to a seam's cell on any
row": measured, and not made the default).

How far the belief drifts a lane depends on the robot: through the link the
tank's lanes drifted 0.5 cm a lane, one way, every ten lanes (seed 0, 30x), so
the tenth lane ran 5 cm off and each detour's fix found the lanes since then not
surely in their columns (:mod:`.sure_lanes`): they were counted unprobed again
and queued to be driven again. Given the corrections the x fixes make
(:meth:`SeamDetour.fixed` with ``dx_m``), a detour is due sooner: after as many
lanes as keep the drift, at the rate those corrections show, within a quarter of
a cell (:data:`DRIFT_BUDGET`), and never later than ``max_lanes``.

Only the estimate and the wall's map (the seams the tank's drawing places) are
read; the simulator's truth never is.
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from collections.abc import Callable

import numpy as np

__all__ = ["DRIFT_BUDGET", "SeamDetour", "X_FIX_LANES", "grid_path", "seam_cells", "seam_goals",
           "straight_path"]

# lane changes without an x fix before a detour, by default (inspect_wall and the relay's
# executor): the tank's lanes drifted about 2.5 cm in 16 lanes, and 10 probed its seed 0 in full
X_FIX_LANES = 10
# given the drift's rate (the x fixes' corrections a lane), a detour is due before the
# drift reaches this share of a cell: a lane filed then stays sure in its column
# (sure_lanes: |offset + dx| + σ_x < D/2, with σ_x about D/10 after a seam's fix)
DRIFT_BUDGET = 0.25
MIN_DUE_LANES = 2  # however fast the drift, not a detour at every lane change
RATE_MEMORY = 0.5  # each new correction weighs as much as those before it together

_STRAIGHT = ((0, 1), (0, -1), (1, 0), (-1, 0))


def grid_path(blocked: np.ndarray, start: tuple[int, int], goals,
              max_steps: int | None = None,
              step_ok: Callable[[tuple[int, int], tuple[int, int]], bool] | None = None,
              ) -> list[tuple[int, int]]:
    """Fewest straight steps (4-adjacent, columns wrapping round) from ``start``
    to the nearest cell of ``goals`` over free cells, without ``start``; empty
    when ``start`` is a goal or no goal is within ``max_steps``. ``step_ok(a, b)``,
    when given, must allow each step from cell a to its neighbour b."""
    rows, cols = blocked.shape
    if start in goals:
        return []
    parent: dict[tuple[int, int], tuple[int, int] | None] = {start: None}
    todo = deque([(start, 0)])
    while todo:
        (r, c), n = todo.popleft()
        if max_steps is not None and n >= max_steps:
            continue
        for dr, dc in _STRAIGHT:
            nxt = (r + dr, (c + dc) % cols)
            if not 0 <= nxt[0] < rows or blocked[nxt] or nxt in parent:
                continue
            if step_ok is not None and not step_ok((r, c), nxt):
                continue
            parent[nxt] = (r, c)
            if nxt in goals:
                path = [nxt]
                while parent[path[-1]] != start:
                    path.append(parent[path[-1]])  # type: ignore[arg-type]
                return path[::-1]
            todo.append((nxt, n + 1))
    return []


def seam_cells(seams, row: int, cell_m: float, blocked: np.ndarray) -> set[tuple[int, int]]:
    """The free cells of ``row`` that a vertical seam of the map crosses: the
    camera over such a cell's centre sees the seam within half a cell."""
    y = (row + 0.5) * cell_m
    cols = blocked.shape[1]
    out = set()
    for b in seams:
        if b.x0_m != b.x1_m or not getattr(b, "crossable", True):
            continue  # girth seams; a seam the crawler may not cross
        lo, hi = sorted((b.y0_m, b.y1_m))
        if lo <= y <= hi:
            cell = (row, math.floor(b.x0_m / cell_m) % cols)
            if not blocked[cell]:
                out.add(cell)
    return out


def seam_goals(seams, cell_m: float, blocked: np.ndarray) -> frozenset[tuple[int, int]]:
    """The free cells of every row that a vertical seam of the map crosses
    (:func:`seam_cells` row by row)."""
    return frozenset(cell for row in range(blocked.shape[0])
                     for cell in seam_cells(seams, row, cell_m, blocked))


def straight_path(blocked: np.ndarray, start: tuple[int, int], goals,
                  max_steps: int | None = None,
                  step_ok: Callable[[tuple[int, int], tuple[int, int]], bool] | None = None,
                  ) -> list[tuple[int, int]]:
    """As :func:`grid_path` (fewest straight steps to the nearest goal, 4-adjacent,
    columns wrapping round, without ``start``), and of the ways that few steps long
    the one with the fewest changes of direction: each is a turn in place, and a
    way to another row otherwise may run as a staircase along an obstacle's edge.
    A search over (cell, direction of the step into it), its cost (steps, turns)."""
    rows, cols = blocked.shape
    if start in goals:
        return []
    best: dict[tuple[tuple[int, int], int], tuple[int, int]] = {}
    parent: dict[tuple[tuple[int, int], int], tuple[tuple[int, int], int] | None] = {}
    heap: list = [(0, 0, start, -1, None)]
    while heap:
        n, turns, cell, d, came = heapq.heappop(heap)
        key = (cell, d)
        if key in parent:
            continue
        parent[key] = came
        if cell in goals:
            path = []
            while parent[key] is not None:
                path.append(key[0])
                key = parent[key]  # type: ignore[assignment]
            return path[::-1]
        if max_steps is not None and n >= max_steps:
            continue
        r, c = cell
        for k, (dr, dc) in enumerate(_STRAIGHT):
            nxt = (r + dr, (c + dc) % cols)
            if not 0 <= nxt[0] < rows or blocked[nxt] or nxt == start:
                continue
            cost = (n + 1, turns + (d not in (-1, k)))
            if best.get((nxt, k), (math.inf, math.inf)) <= cost:
                continue
            if step_ok is not None and not step_ok(cell, nxt):
                continue
            best[(nxt, k)] = cost
            heapq.heappush(heap, (*cost, nxt, k, key))
    return []


class SeamDetour:
    """When a detour to a vertical seam is due, and its route.

    ``max_lanes``: lane changes allowed without an x fix; ``max_steps``: the
    longest way to a seam's cell worth driving (cells, one way)."""

    # to a seam's cell on any row, not only the lane end's own row (off by default: on the
    # tank it cost more than it gave headless, and through the link on the 6 m x 2.4 m
    # wall it left a lane end unsure; docs/climber.md, "Detours to a seam's cell on any
    # row"); the benches' --detour-any-row sets it
    any_row = False

    def __init__(self, blocked: np.ndarray, seams, cell_m: float, max_lanes: int,
                 max_steps: int = 40) -> None:
        self.blocked, self.seams, self.cell_m = blocked, tuple(seams), cell_m
        self.max_lanes, self.max_steps = max_lanes, max_steps
        self.goals = seam_goals(self.seams, cell_m, blocked)  # where a detour may end
        self.lanes = 0  # lane changes since the last x fix
        self.driven = self.cells = 0  # detours driven, cells driven on them (both ways)
        # the x fixes' corrections and the lane changes they came after, older ones
        # weighing less (RATE_MEMORY): their ratio is the drift's rate a lane
        self._drift_m = self._drift_lanes = 0.0

    @property
    def rate_m(self) -> float | None:
        """The belief's x drift a lane change, as the x fixes' corrections show it
        (None before any)."""
        return self._drift_m / self._drift_lanes if self._drift_lanes else None

    @property
    def due_lanes(self) -> int:
        """Lane changes without an x fix after which a detour is due: ``max_lanes``,
        or fewer where the drift's rate would take the belief further than
        DRIFT_BUDGET of a cell by then (at least MIN_DUE_LANES)."""
        rate = self.rate_m
        if not rate:
            return self.max_lanes
        lanes = math.floor(DRIFT_BUDGET * self.cell_m / rate)
        return max(min(MIN_DUE_LANES, self.max_lanes), min(self.max_lanes, lanes))

    def lane_changed(self) -> None:
        self.lanes += 1

    def fixed(self, dx_m: float | None = None) -> None:
        """The belief's x was fixed (a vertical seam or a rim seen); ``dx_m``, when
        known, how far the fix moved it: the first fix after lane changes measures
        the drift's rate (the fixes that follow it on the same seam do not)."""
        if dx_m is not None and self.lanes > 0:
            self._drift_m = RATE_MEMORY * self._drift_m + abs(dx_m)
            self._drift_lanes = RATE_MEMORY * self._drift_lanes + self.lanes
        self.lanes = 0

    def withdrawn(self, route: list[tuple[int, int]]) -> None:
        """A route :meth:`route` gave was not driven (the body cannot take it): it is
        not counted, and the detour stays due."""
        self.driven -= 1
        self.cells -= len(route)

    def route(self, here: tuple[int, int],
              step_ok: Callable[[tuple[int, int], tuple[int, int]], bool] | None = None,
              ) -> list[tuple[int, int]]:
        """The cells to drive from ``here`` (a lane's end) to the nearest seam of
        its row and back to ``here``, when a detour is due and a seam is near
        enough; else empty. With :attr:`any_row`: to the nearest cell that a vertical
        seam crosses, on any row (:func:`seam_goals`), by :func:`straight_path`'s way
        (fewest steps, then fewest turns), each step allowed by ``step_ok`` when given
        (the body's reach: :func:`.link_ends.body_steps`), and back the same way."""
        if self.lanes < self.due_lanes:
            return []
        if self.any_row:
            there = straight_path(self.blocked, here, self.goals, self.max_steps, step_ok)
        else:
            goals = seam_cells(self.seams, here[0], self.cell_m, self.blocked)
            there = grid_path(self.blocked, here, goals, self.max_steps)
        if not there:
            return []  # none near: again at the next lane's end
        back = [*there[-2::-1], here]
        self.driven += 1
        self.cells += len(there) + len(back)
        return there + back
