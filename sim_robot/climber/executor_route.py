"""The relay executor's route edits (:class:`.executor.InspectionExecutor`): the
cells it puts into its route as it goes — a detour to a vertical seam at a lane
change (:mod:`.seam_detour`), the way round after a target given up for contacts
(:mod:`.route_round`), the mop-ups at the end of the sweep — and the moves it
plans before each new target (the lane change's turns, :mod:`.turns`, or the
body's, :func:`.moves.body_moves`). Only the map and the estimate are read.
"""

from __future__ import annotations

import logging
import threading

import numpy as np

from app.core.planner.coverage import mop_up_route

from .link_ends import body_mop_up
from .moves import body_moves, lift_detour
from .route_round import way_round
from .seam_detour import grid_path, seam_cells
from .sure_ends import probe_sigma_y
from .turns import lane_change_turns, step_heading

log = logging.getLogger("sim_robot.climber.executor")

MOP_UPS = 2  # routes back to the cells the record missed, at the end of the sweep
# in the mop-up, the probe's σ_x beyond this many cells drives to a vertical seam first: the
# filter's σ_x overstates the x error about tenfold on the tank (docs/climber.md, "Sure lane
# ends"), and the sweep's lanes run with σ_x up to about D/2 between their detours by design
X_FIX_CELLS = 1.0


class _MopUpPlan:
    """A mop-up's route planned on a worker thread from a snapshot of what was missed
    (the relay's lock is not held meanwhile: on the tank the route of 15 000 cells took
    about 2 s of wall time, through which the relay read no reports)."""

    def __init__(self, plan, start: tuple[int, int], missed: np.ndarray) -> None:
        self.start, self.missed = start, missed
        self.route: list[tuple[int, int]] | None = None
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, args=(plan,), daemon=True,
                                       name="climber-mop-up")
        self.thread.start()

    def _run(self, plan) -> None:
        try:
            self.route = plan(self.start, self.missed)
        except BaseException as e:  # (handed to the executor, which plans in place)
            self.error = e

    def done(self) -> bool:
        return not self.thread.is_alive()


class RouteEdits:
    """The route's edits and the moves before a target, for the executor (its
    ``cells``, ``index``, ``planned``, detour span, ``sure``, ``moves``, map)."""

    def _detour_after(self, i: int) -> None:
        """The probe is done with route cell ``i``: a move to another column next is a lane
        change, and when a detour is due its route (to the row's nearest vertical seam, or
        with ``any_row`` the nearest cell a vertical seam crosses, and back to cell ``i``)
        is driven first.  The detour's own steps are no lane changes."""
        if self.detour is None or i + 1 >= len(self.cells) or i < self._detour_end:
            return
        if self.sure is not None and self.sure.holds(i):
            return  # (the plan's next step comes after the route to a height landmark)
        here = self.cells[i]
        if here[1] == self.cells[i + 1][1]:
            return
        self.detour.lane_changed()
        any_row = self.detour.any_row
        # to a seam's cell on any row: given the body's reach, only by steps the body fits
        # along (facing along a row on the row's steps, up or down on the column's), so
        # from a lane's end on an edge row the way leaves up or down the lane's column
        route = self.detour.route(here, self.steps if any_row else None)
        if not route:
            return
        if self.reach is not None and not any_row:  # where the body fits facing along the row
            lifted = lift_detour(self.reach, route, self.blocked, self.cell_m)
            if not lifted:
                self.detour.withdrawn(route)
                log.info("detour from %s left for a later lane: the body does not fit "
                         "along its row", here)
                return
            route = lifted
        self.cells[i + 1:i + 1] = route
        self._detour_start, self._detour_end = i + 1, i + 1 + len(route)
        if i < self.planned:
            self.planned += len(route)
        log.info("detour to a vertical seam from %s: %d cells", here, len(route))

    def _leg_span(self, k: int) -> int | None:
        """The first index of the detour or route to a height landmark that route cell
        ``k`` is on, else None."""
        if self._detour_start <= k < self._detour_end:
            return self._detour_start
        if self.sure is not None and self.sure.on_route(k):
            return self.sure.start
        return None

    def _lane_turns(self, k: int) -> tuple[float | None, float | None]:
        """:func:`.turns.lane_change_turns` round route cell ``k`` (none inside a detour
        or a route to a height landmark)."""
        if self._leg_span(k) is not None or k >= len(self.cells):
            return None, None
        return lane_change_turns(self.cells[k - 1] if k else None, self.cells[k],
                                 self.cells[k + 1] if k + 1 < len(self.cells) else None,
                                 self.cols)

    def _turn_before(self, k: int) -> float | None:
        """The heading to face before driving to route cell ``k``: on a detour or a
        route to a height landmark, each straight leg's way when it changes; elsewhere
        a lane change's."""
        start = self._leg_span(k)
        if start is None:
            return self._lane_turns(k)[0]
        way = step_heading(self.cells[k - 1], self.cells[k], self.cols)
        if k > start and way == step_heading(self.cells[k - 2], self.cells[k - 1],
                                             self.cols):
            return None
        return way

    def _plan_moves(self, after: float | None, pose: tuple[float, float, float]) -> None:
        """The moves before the new target (:class:`.moves.Moves`): the lane change's
        turns (:func:`_lane_turns`, :func:`_turn_before`) or, given ``reach``, the body's
        (:func:`.moves.body_moves`), which also gives up the cells the body fits round
        no way. A turn's rate is not slowed on a stale estimate as the probe's speed
        is: the odometry takes each report's last gyro sample as the rate over the
        report's whole interval, and a rate changed from period to period left the
        heading degrees off after every turn at 40x (docs/climber.md)."""
        if self.reach is None:
            self.moves.set(("turn", h) for h in (after, self._turn_before(self.index))
                           if h is not None)
            return
        while self.index < len(self.cells):
            moves = body_moves(self.reach, self.cells, self.index, pose, self.cell_m,
                               self.rows, self.cols)
            if moves is not None:
                self.moves.set(moves)
                return
            log.info("cell %s is out of the body's reach; going on", self.cells[self.index])
            self.out_of_reach += 1
            self.index += 1

    def _round_to_next(self) -> None:
        """A target given up for contacts: when the next one is not beside the probe,
        the way round to it along the body's steps is driven first (:mod:`.route_round`)."""
        if self.steps is None or self._pose is None or self.index >= len(self.cells):
            return
        i = self.index
        way = way_round(self.blocked, self.cell_of(*self.probe_point(self._pose)),
                        self.cells[i], self.steps)
        if not way:
            return
        self.cells[i:i] = way
        if i < self.planned:
            self.planned += len(way)
        if self._detour_start < self._detour_end:  # (a detour's span further on moves on)
            if i <= self._detour_start:
                self._detour_start += len(way)
            if i < self._detour_end:
                self._detour_end += len(way)
        if self.sure is not None:
            self.sure.shift(i, len(way))
        self.ways_round += 1
        log.info("the way round to cell %s: %d cells", self.cells[i + len(way)], len(way))

    def _fix_first(self, pose: tuple[float, float, float], cov) -> bool:
        """In the mop-up, before driving to the target at hand: when the estimate's own σ of
        the probe's height is so large that even a probe believed at the target's centre
        would not surely be in its row (K·σ_y > D/2, :meth:`.sure_ends.SureEnds.sure` with
        dy = 0), the route from the cell before it to the nearest height landmark (a row
        across a girth seam, or an edge row, whose edge is sought at the far end when
        unseen) and back is put in first (:meth:`.sure_ends.SureEnds.fix_route`, the sure
        ends' own); else when σ_x exceeds X_FIX_CELLS cells, the route to the row's nearest
        vertical seam and back (:func:`.seam_detour.seam_cells`). The mop-up's lanes are
        short and cross no seam: without this it drove on a belief whose σ_y was metres
        (docs/climber.md). At most one such route a target. Returns whether one was put in."""
        k = self.index
        if (self.sure is None or k < self.planned or k == self._fix_for or k == 0
                or k >= len(self.cells) or self._leg_span(k) is not None):
            return False
        self._fix_for = k  # (looked at; moved on below when a route is put in)
        ends, here = self.sure.ends, self.cells[k - 1]
        sigma_y = probe_sigma_y(cov, pose[2], self.lead)
        far = True
        if ends.k * sigma_y > self.cell_m / 2:
            there, back = ends.fix_route(here)
            kind = "height"
        else:
            jx = np.array([1.0, 0.0, -self.lead * np.sin(pose[2])])
            sigma_x = float(np.sqrt(max(float(jx @ cov[:3, :3] @ jx), 0.0)))
            if self.detour is None or sigma_x <= X_FIX_CELLS * self.cell_m:
                return False
            goals = seam_cells(self.detour.seams, here[0], self.cell_m, self.blocked)
            there = grid_path(self.blocked, here, goals, self.detour.max_steps, self.steps)
            back = [*there[-2::-1], here] if there else []
            kind, far = "vertical seam", False
            sigma_y = sigma_x
        if not there:
            return False
        route = there + back
        self.cells[k:k] = route
        if self._detour_start < self._detour_end:  # (a detour's span further on moves on)
            if k <= self._detour_start:
                self._detour_start += len(route)
            if k < self._detour_end:
                self._detour_end += len(route)
        self.sure.shift(k, len(route))
        self.sure.start, self.sure.end = k, k + len(route)  # faced leg by leg
        if far:  # (its far end on an edge row: the edge sought when unseen)
            self.sure.far = k + len(there) - 1
        self._fix_for = k + len(route)
        self.mop_fixes[kind] = self.mop_fixes.get(kind, 0) + 1
        log.info("mop-up: σ %.2f m before cell %s; a route of %d cells to a %s and back",
                 sigma_y, self.cells[k + len(route)], len(route), kind)
        return True

    def _mop_route(self, start: tuple[int, int], missed: np.ndarray) -> list[tuple[int, int]]:
        """The mop-up's route from ``start`` to the cells of ``missed``, nearest first."""
        return (mop_up_route(self.blocked, start, missed, wrap=True)
                if self.steps is None else  # with the body's reach: the steps it fits along
                body_mop_up(self.blocked, start, missed, self.steps))

    def _mop_up(self) -> bool:
        """At the end of the route: back to the reachable cells the robot's own
        record has no reading for (given up at the time limit, skimmed outside
        the core, taken back by an x fix, or an end of the sweep the estimate never
        judged surely in its row, :meth:`.link_ends.LinkEnds.take_back`), nearest
        first (:func:`mop_up_route`), at most MOP_UPS times. Returns whether cells
        were added, or (with ``plan_apart``) whether a route is being planned: the
        executor holds the robot still until it is ready (the route is planned on a
        worker thread from a snapshot, and taken only if no cell has been missed since
        that it does not know of; else planned again)."""
        job = self._mop_plan
        if job is not None and not job.done():
            return True  # (hold still; the visit at hand goes on, not filed each step)
        self._flush()
        if self.sure is not None:  # ends never judged sure: not claimed, driven to again
            back = self.sure.take_back(self.covered)
            if back:
                log.info("ends never judged sure taken back from the record: %s", back)
        missed = self.reachable_mask & ~self.covered
        if self.mop_ups >= MOP_UPS or not missed.any():
            self._mop_plan = None
            return False
        start = self.cells[-1]
        if self.plan_apart and (job is None or job.done() and job.error is None
                                and (job.start != start or (missed & ~job.missed).any())):
            if job is not None:
                self.mop_replans += 1
                log.info("mop-up planned again: %d cells missed that its snapshot had not",
                         int((missed & ~job.missed).sum()))
            self._mop_plan = _MopUpPlan(self._mop_route, start, missed.copy())
            return True
        self._mop_plan = None
        route = job.route if job is not None and job.error is None else \
            self._mop_route(start, missed)
        self.mop_ups += 1
        log.info("mop-up %d: %d cells missed, a route of %d cells", self.mop_ups,
                 int(missed.sum()), len(route))
        self.cells.extend(route)
        return bool(route)
