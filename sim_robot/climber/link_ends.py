"""Sure lane ends in the relay's executor (:class:`.executor.InspectionExecutor`,
the desk's path through the link), one control period at a time.

The judgement is :mod:`.sure_ends`'s, made as the headless inspection
(:func:`.inspection.inspect_wall`) makes it: when the route's cell at an end of
its vertical runs (:func:`.sure_ends.run_end`) has been reached as the belief
puts it, the estimate's height and its covariance say whether the probe is
surely in the cell's row (:meth:`.sure_ends.SureEnds.check`). The headless
inspection drives the remedy in one blocking call; the executor steps once a
control period, so the remedy is handed back to it:

- an unsure end near the shell's edge begins the executor's edge seek
  (:class:`.edge_seek.EdgeSeek`, the guarded move to the edge until the camera
  sees it); the executor then takes the cell again, and the end is judged again
  there on the corrected belief;
- an unsure end far from the edge hands back the route to the nearest height
  landmark (a row across a girth seam, or an edge row) and back, which the
  executor inserts into its own route after the cell, as it does a detour to a
  vertical seam; at the route's far end on an edge row whose edge the camera
  has not seen, the edge is sought; the end is judged again when the probe is
  back on it (the route's last cell). Given the body's reach on the map
  (:class:`.reach.Reach`), the route takes only steps the body fits along both
  ways, with the probe over the cell ahead (:func:`body_steps`): beside a nozzle
  the fewest-step route would otherwise have the body's side over the nozzle.

Only the ends of the sweep are judged, not a detour's cells nor a route's own
cells. An end never judged sure is taken back from the record before each mop-up
and at the end (:meth:`LinkEnds.take_back`): the record does not claim a cell the
estimate could not put surely in its row. The mop-up drives to it again and
judges it there, with no remedy (its own fix before a target,
:meth:`.executor_route.RouteEdits._fix_first`, has brought σ_y under D/2); judged
sure, it is filed and kept; else it is left out of the record and reported
(:attr:`.sure_ends.SureEnds.unsure`). Only the estimate, its covariance and
the wall's map are read; the simulator's truth never is.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from .edge_seek import EdgeSeek
from .reach import Reach
from .seam_detour import grid_path
from .sure_ends import SureEnds, probe_sigma_y, run_end
from .turns import step_heading

__all__ = ["SEEK", "LinkEnds", "body_mop_up", "body_steps"]

SEEK = "seek"  # what :meth:`LinkEnds.reached` hands back when it has begun an edge seek

Cell = tuple[int, int]

log = logging.getLogger(__name__)


def body_mop_up(blocked: np.ndarray, start: Cell, missed: np.ndarray, step_ok) -> list[Cell]:
    """The mop-up's route with the body's steps (``step_ok``, :func:`body_steps`): from
    ``start`` (not included) to the nearest cell of ``missed`` (a bool mask) over steps the
    body fits along, then on to the nearest one left, until none is reachable so.  Cells
    passed on the way count as visited.  The plain mop-up
    (:func:`app.core.planner.coverage.mop_up_route`) takes the fewest steps, which beside a
    nozzle put the body's side over it: pressed against the nozzle, the body gave up every
    target of that route in turn."""
    todo = {(int(r), int(c)) for r, c in np.argwhere(missed)}
    todo.discard(start)
    route: list[Cell] = []
    at = start
    while todo:
        leg = grid_path(blocked, at, todo, None, step_ok)
        if not leg:
            break  # the rest is not reachable along the body's steps
        route.extend(leg)
        todo.difference_update(leg)
        at = leg[-1]
    return route


def body_steps(reach: Reach, cell_m: float, cols: int):
    """``step_ok(a, b)`` for the routes to a height landmark, as the executor's moves
    drive them (:func:`.moves.body_moves`): a step along a row faces along it, so the
    body must fit with its probe over a and over b facing the step's way and facing
    back; a step up or down a column may be taken facing it or reversing, so the body
    must fit over a and over b facing up or down."""
    fits: dict[tuple[Cell, float], bool] = {}

    def fit(cell: Cell, heading: float) -> bool:
        key = (cell, heading)
        if key not in fits:
            fits[key] = reach.fits((cell[1] + 0.5) * cell_m, (cell[0] + 0.5) * cell_m, heading)
        return fits[key]

    def step_ok(a: Cell, b: Cell) -> bool:
        if a[0] != b[0]:  # up or down
            return all(fit(c, math.pi / 2) or fit(c, -math.pi / 2) for c in (a, b))
        way = step_heading(a, b, cols)
        back = step_heading(b, a, cols)
        return all(fit(c, h) for c in (a, b) for h in (way, back))

    return step_ok


class LinkEnds:
    """The sure ends of the executor's route. ``ends``: the judgement and its
    record (:class:`.sure_ends.SureEnds`, on the executor's route map);
    ``seek``: the executor's edge seek, which the relay's edge fixes feed;
    ``lead_m``: the probe's distance ahead of the axle."""

    def __init__(self, ends: SureEnds, seek: EdgeSeek, lead_m: float) -> None:
        self.ends, self.seek, self.lead = ends, seek, lead_m
        self.taken_back = 0  # filings of ends never judged sure taken back from the record
        self.reset()

    def reset(self) -> None:
        """A new run of the route: nothing pending."""
        self.start = self.end = 0  # the last route's span in the executor's route
        self.again = -1  # the route index of an end to judge again, finally, once reached
        self.far = -1  # the route index of a route's far end (its edge sought if unseen)

    def shift(self, at: int, n: int) -> None:
        """``n`` cells were put into the executor's route before index ``at``: the
        indices kept here from ``at`` on move on with their cells."""
        if self.start < self.end:
            if at <= self.start:
                self.start += n
            if at < self.end:
                self.end += n
        if self.again >= at:
            self.again += n
        if self.far >= at:
            self.far += n

    def on_route(self, k: int) -> bool:
        """Route index ``k`` is a cell of the last route to a height landmark (the
        end it leaves from not included; the end it comes back to included)."""
        return self.start <= k < self.end

    def holds(self, k: int) -> bool:
        """Route index ``k`` is the unsure end a route leaves from, or a cell of that
        route before the way back ends: the plan's next step (a lane change) comes
        only after the route."""
        return self.start - 1 <= k < self.end - 1

    def back_at(self, k: int) -> bool:
        """Route index ``k`` is the end a route has come back to."""
        return k == self.end - 1 and self.end > 0

    def take_back(self, covered: np.ndarray) -> list[Cell]:
        """The ends never judged sure that ``covered`` holds, set not covered there
        (for the mop-up, and so that the record does not claim them); returns them."""
        out = [c for c in sorted(self.ends.unsure) if covered[c]]
        for c in out:
            covered[c] = False
        self.taken_back += len(out)
        return out

    def reached(self, cells: list[Cell], k: int, py: float, cov: np.ndarray, theta: float,
                sweep: bool, mop: bool = False) -> str | list[Cell] | None:
        """Route cell ``k`` is reached as the belief puts it (probe at believed
        height ``py``; ``cov`` the estimate's covariance, ``theta`` its heading;
        ``sweep``: ``k`` is a cell of the sweep, not of a detour or the mop-up;
        ``mop``: of the mop-up, where an end never judged sure is judged again).
        Returns :data:`SEEK` when an edge seek has been begun (the executor seeks,
        then takes cell ``k`` again), the cells to insert after ``k`` (the route to
        a height landmark and back to ``k``), or None to go on."""
        if k == self.far:
            self.far = -1
            return SEEK if self.seek.arrived(cells[k][0], py) else None
        sigma_y = probe_sigma_y(cov, theta, self.lead)
        if k == self.again:  # back on the end after its remedy: the final judgement
            self.again = -1
            self.ends.judged(cells[k], self.ends.sure(cells[k][0], py, sigma_y))
            return None
        if not sweep:  # the mop-up back on an end never judged sure: judged there, no remedy
            if mop and cells[k] in self.ends.unsure and not self.on_route(k):
                self.ends.judged(cells[k], self.ends.sure(cells[k][0], py, sigma_y))
            return None
        if self.on_route(k) or not run_end(cells, k):
            return None
        sure, side, there, back = self.ends.check(cells[k], py, sigma_y)
        self.ends.judged(cells[k], sure)  # (unsure until judged sure again)
        if side:
            self.seek.begin(side, py)
            self.again = k
            return SEEK
        if not there:
            return None
        route = there + back
        log.info("unsure end %s: a route of %d cells to a height landmark and back",
                 cells[k], len(route))
        self.start, self.end = k + 1, k + 1 + len(route)
        self.again, self.far = self.end - 1, k + len(there)
        return route
