"""The climber's relay-side brain (the Pi's job, no ground truth): its own
pose from encoders and gyro (the EKF of app/core/localisation, seed 003
eqs. 4–13) corrected by the weld seams the camera sees, and the inspection
mission — the coverage plan round the tank (seed 001, ``wrap_plan``: the
walker's plan or a lane tour across the seam, whichever turns less) steered
on that estimate, each probe reading filed under the cell
the robot believes its probe is over.

Steering is :mod:`.inspection`'s: the probe point, l = L/2 ahead of the axle,
is driven towards the next cell centre by feedback linearisation,
v = u·(cos θ, sin θ), ω = u·(−sin θ, cos θ)/l. With ``turns_in_place`` (the
relay's default) the lane changes and the detours' legs are made as the headless
inspection makes them: turn in place to face along the row, step, turn to face
the new lane (:mod:`.turns`).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.decompose import decompose
from app.core.planner.coverage.seam import wrap_plan

from .edge_seek import EdgeSeek
from .executor_record import CORE, Record
from .executor_route import MOP_UPS, RouteEdits
from .kinematics import ClimberParams
from .link_ends import SEEK, LinkEnds, body_steps
from .moves import Moves
from .odometry import ClimberOdometry
from .reach import Reach
from .seam_detour import SeamDetour
from .side_step import side_step
from .sure_ends import SureEnds
from .sure_lanes import SureLanes
from .turns import step_heading

__all__ = ["CORE", "MOP_UPS", "ClimberOdometry", "InspectionExecutor", "first_entries"]

log = logging.getLogger(__name__)

CELL_TIMEOUT_S = 60.0  # sim seconds to reach one cell before it is given up
FRESH_S = 0.1  # an estimate older than this slows the steering in proportion
LOOK_AHEAD_S = 1.0  # a steering turn that would touch within this is not made (along only)
TOUCHES_PER_TARGET = 3  # contacts reported on the way to a target before it is given up


def first_entries(labels: np.ndarray, cells: list[tuple[int, int]]) -> list[int]:
    """The regions in the order a path first enters them."""
    seen: dict[int, None] = {}
    for cell in cells:
        k = int(labels[cell])
        if k >= 0 and k not in seen:
            seen[k] = None
    return list(seen)


class InspectionExecutor(RouteEdits, Record):
    """The inspection mission on the relay: plan, steer, file readings, count (the
    route's edits: :mod:`.executor_route`; the record: :mod:`.executor_record`)."""

    def __init__(self, blocked: np.ndarray, cell_m: float, start: tuple[int, int],
                 params: ClimberParams, gain: float = 2.0, reach_m: float = 0.02,
                 seek_edges: bool = False, detour: SeamDetour | None = None,
                 turns_in_place: bool = False, reach: Reach | None = None,
                 sure_ends: bool = False, seams=(), first_fix_whole: bool = False) -> None:
        self.map_blocked = np.asarray(blocked, bool)  # the wall's obstacles
        # what the route keeps out of: the obstacles and, given ``reach``, the cells beside
        # them where the body does not fit (:meth:`.reach.Reach.body_blocked`)
        self.blocked = self.map_blocked if reach is None else reach.body_blocked()
        self.rows, self.cols = self.blocked.shape
        self.cell_m = cell_m
        self.circ_m = self.cols * cell_m
        self.params = params
        self.lead = params.length_m / 2
        self.gain, self.reach_m = gain, reach_m
        # lanes up and down the whole wall: each crosses the girth seams and
        # reaches the shell's edges, a height fix per course for the estimator
        # (horizontal lanes would creep a whole course unseen); whole lanes in
        # the order that turns least, across the seam, when that beats the walker
        plan = wrap_plan(self.blocked, start, regions=False, axis=1)
        self.cells: list[tuple[int, int]] = list(plan.cells)
        self._plan = tuple(self.cells)  # the sweep as planned (a new start drives it again)
        self.planned = len(self.cells)  # the sweep (with its detours); mop-ups come after it
        self.mop_ups = 0
        # plan the mop-up on a worker thread (the relay's lock not held meanwhile), the
        # robot held still until its route is ready (:meth:`.executor_route.RouteEdits._mop_up`)
        self.plan_apart = False
        self._mop_plan = None
        self.mop_replans = 0  # mop-up routes planned again: cells missed since the snapshot
        # the desk shows the wall's sub-regions (§3.2) in the order the lanes enter them
        self.labels = decompose(plan.labels < 0).labels
        self.order = first_entries(self.labels, self.cells)
        self.reachable_mask = np.zeros(self.blocked.shape, bool)
        for cell in self.cells:
            self.reachable_mask[cell] = True
        self.reachable = int(self.reachable_mask.sum())
        self.index = 0
        self.state = CoverageState.IDLE
        self.reason = ""
        self.covered = np.zeros(self.blocked.shape, bool)
        self.filed = np.full(self.blocked.shape, np.nan)
        self.visits = 0
        self._cell: tuple[int, int] | None = None  # the cell whose core the probe is in
        self._best: tuple[float, float, float, float] | None = None  # (d, x, y, mm)
        self._since = 0.0  # sim time the current target was taken
        self.pending: list[tuple[float, float, float]] = []  # readings not yet sent
        self.version = 0
        # an edge row's cell reached with the shell's edge unseen: climb (or descend) to
        # it until the camera sees it (a guarded move, :mod:`.edge_seek`); only with a
        # camera whose edge fixes come in through :meth:`edge_fixed`
        self.seek_edges = seek_edges
        self.seek = EdgeSeek(self.rows, self.rows * cell_m)
        # after so many lane changes without an x fix, a detour along the lane's end row to
        # a vertical seam and back (:mod:`.seam_detour`), inserted into the route; the
        # relay reports the x fixes through :meth:`x_fixed`
        self.detour = detour
        self._detour_start = self._detour_end = 0  # the last inserted detour's span of the route
        # at a lane change, turn in place to face along the row, step, turn to face the new
        # lane; along a detour, face each straight leg (:mod:`.turns`, as inspect_wall does).
        # Given ``reach`` (the body's footprint on the map, :mod:`.reach`), the moves keep
        # the body on the wall and off the obstacles instead (:func:`.moves.body_moves`)
        self.turns_in_place = turns_in_place
        self.reach = reach
        self.moves = Moves(reach, self.circ_m)  # the moves still to make before the target
        self.turn_visits = 0  # of the visits, those the probe's swing in a move in place made
        self.out_of_reach = 0  # route cells given up: the body fits round them no way
        self._touched_at, self._touches = -1, 0  # the target last touched on the way to, times
        self._pose: tuple[float, float, float] | None = None  # the estimate at the last step
        self.ways_round = 0  # ways round to a target after one given up for contacts
        self._replan = False  # plan the target's moves again (after a contact's recoil)
        self._side_for = -1  # the route index a sideways step was last looked for at
        self._seek_for = -1  # the plan index the last seek was made at
        self._seeking = False
        # the runs' ends judged by the estimate's height and its covariance; an unsure
        # one seeks the shell's edge or drives to a girth seam or an edge row and back
        # (:mod:`.link_ends`, :mod:`.sure_ends`; ``seams``: the map's, for those routes)
        self.steps = steps = None if reach is None else body_steps(reach, cell_m, self.cols)
        self.sure = (LinkEnds(SureEnds(self.rows, cell_m, blocked=self.blocked, seams=seams,
                                       step_ok=steps), self.seek, self.lead)
                     if sure_ends else None)
        # the cells filed since the last x fix, judged by the correction the next one makes
        # (``first_fix_whole``: the estimate's first x fix takes back all filed before it,
        # a lean of the first lanes it does not show)
        self.lanes = SureLanes(cell_m, self.circ_m, core=CORE, whole_first=first_fix_whole)
        self.anew = 0  # cells filed anew by an x fix's corrected track
        self._first = 0  # the visit's first sample (``lanes.count`` then)
        # in the mop-up, a fix before a target the estimate's σ cannot find (:meth:`_fix_first`)
        self._fix_for = -1  # the route index last looked at for it
        self.mop_fixes: dict[str, int] = {}  # such routes put in, by landmark

    # ---- mission commands (called with the relay's lock held) --------------------------
    @property
    def owns_motors(self) -> bool:
        return self.state == CoverageState.RUNNING

    @property
    def running(self) -> bool:
        return self.owns_motors

    @property
    def turns(self) -> int:
        """Turns in place made."""
        return self.moves.turns

    def _set(self, state: int, reason: str = "") -> tuple[bool, str]:
        self.state, self.reason = state, reason
        self.version += 1
        return True, ""

    def start(self, t: float) -> tuple[bool, str]:
        if self.state == CoverageState.RUNNING:
            return False, "the inspection is already running"
        if self.state in (CoverageState.DONE, CoverageState.ABORTED):
            self.index = 0
            self.cells = list(self._plan)
            self.planned = len(self.cells)
            self._detour_start = self._detour_end = 0
            self.mop_ups = 0
            self._mop_plan = None
            self._seek_for = self._side_for = self._fix_for = -1
            if self.sure is not None:
                self.sure.reset()
            self.lanes.reset()
            self._first = 0
        self._seeking = self._replan = False
        self.seek.abandon()
        self.moves.set(())
        self._since = t
        return self._set(CoverageState.RUNNING)

    def pause(self, reason: str = "operator") -> tuple[bool, str]:
        if self.state != CoverageState.RUNNING:
            return False, "no inspection is running"
        return self._set(CoverageState.PAUSED, reason)

    def resume(self, t: float) -> tuple[bool, str]:
        if self.state != CoverageState.PAUSED:
            return False, "no inspection is paused"
        self._since = t
        return self._set(CoverageState.RUNNING)

    def abort(self, reason: str = "operator") -> tuple[bool, str]:
        if self.state not in (CoverageState.RUNNING, CoverageState.PAUSED):
            return False, "no inspection to abort"
        return self._set(CoverageState.ABORTED, reason)

    # ---- each control period -----------------------------------------------------------
    def probe_point(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        x, y, th = pose
        return (x + self.lead * math.cos(th)) % self.circ_m, y + self.lead * math.sin(th)

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        r = math.floor(y / self.cell_m)
        if not 0 <= r < self.rows:
            return None
        return r, math.floor((x % self.circ_m) / self.cell_m) % self.cols

    def x_fixed(self, dx_m: float = 0.0, sigma_m: float = 0.0) -> None:
        """The belief's x was fixed (a vertical seam or a rim seen; the probe's believed x
        moved by ``dx_m``, its σ ``sigma_m`` after): the lanes since the last fix count from
        naught; the samples since then are filed again on the corrected track, and the
        cells filed since then that none of them is surely in are no longer covered, for
        the mop-up (:meth:`.executor_record.Record.refile`, :mod:`.sure_lanes`)."""
        if self.detour is not None:  # (its correction: the drift's rate, how soon a detour)
            self.detour.fixed(dx_m)
        self.refile(dx_m, sigma_m)

    def edge_fixed(self, seen_y: float) -> None:
        """A horizontal line fixed on, at ``seen_y`` as the corrected belief
        puts it (the relay calls this after an accepted girth-seam or edge fix)."""
        self.seek.fixed(seen_y)

    def step(self, pose: tuple[float, float, float], t: float,
             pose_t: float | None = None, cov: np.ndarray | None = None) -> tuple[float, float]:
        """Speeds (v, ω) towards the next planned cell; (0, 0) when not running.
        ``pose_t``: the time the estimate holds (its last MCU report); an
        estimate older than FRESH_S slows the probe in proportion (a starved
        relay steering on a stale pose overshoots and wobbles, and drives
        further between the fixes that keep x). An edge row's cell reached
        with its edge unseen starts the edge seek (:mod:`.edge_seek`) before
        the plan goes on. ``cov``: the estimate's covariance, for the sure ends
        (:mod:`.link_ends`; not judged without it)."""
        if self.state != CoverageState.RUNNING:
            return 0.0, 0.0
        self._pose = pose
        px, py = self.probe_point(pose)
        self.seek.moved(px, py)
        if self._seeking:
            u = self.seek.velocity(py) if t - self._since < CELL_TIMEOUT_S else None
            if u is not None:
                return self._speeds(pose, t, pose_t, *u)
            self.seek.abandon()  # (no-op when the edge was found or the guard ran out)
            self._seeking = False
            self._since = t  # the cell's time starts when the seek ends
        while self.index < len(self.cells) or self._mop_up():
            if self.index >= len(self.cells):  # the mop-up being planned apart: hold still
                self._since = t
                return 0.0, 0.0
            if self.moves:
                u = self.moves.step(pose, t)
                if u is not None:
                    return u
                self._since = t  # the cell's time starts when the moves end
                continue
            if self._replan:  # after a contact's recoil: the target's moves from here
                self._replan = False
                if self.reach is not None and self.turns_in_place and 0 < self.index:
                    self._plan_moves(None, pose)
                    continue
            if cov is not None and self._fix_first(pose, cov):  # σ too large: a fix first
                if self.turns_in_place:
                    self._plan_moves(None, pose)
                continue
            tx, ty = ((c + 0.5) * self.cell_m for c in self.cells[self.index][::-1])
            px, py = self.probe_point(pose)
            ex = (tx - px + self.circ_m / 2) % self.circ_m - self.circ_m / 2
            ey = ty - py
            if self._would_touch(pose, *self._speeds(pose, t, pose_t, self.gain * ex,
                                                     self.gain * ey)):
                # along the heading only, no corner swung in: the lateral error is left (the
                # cell reached level with its centre is read if within the core; outside it,
                # once a target, a sideways step first: :mod:`.side_step`)
                c, s = math.cos(pose[2]), math.sin(pose[2])
                along, side = ex * c + ey * s, ey * c - ex * s
                if abs(side) > CORE * self.cell_m and self._side_for != self.index:
                    self._side_for = self.index
                    self.moves.set(side_step(self.reach, pose, side) or ())
                    if self.moves:
                        continue
                ex, ey = along * c, along * s
            if math.hypot(ex, ey) >= self.reach_m and t - self._since < CELL_TIMEOUT_S:
                break
            if t - self._since >= CELL_TIMEOUT_S:
                log.warning("probe did not reach cell %s; going on", self.cells[self.index])
            elif (self.seek_edges and self._seek_for != self.index
                  and self.seek.arrived(self.cells[self.index][0], py)):
                # the camera should see the edge here and does not: climb (or descend)
                # to it, then this cell again on the corrected belief
                self._seek_for = self.index
                self._seeking = True
                self._since = t
                return self.step(pose, t, pose_t, cov)
            after = self._lane_turns(self.index)[1]  # (the plan's next cell, not a detour's)
            if self.sure is not None and cov is not None and t - self._since < CELL_TIMEOUT_S:
                k = self.index  # (a sweep's cell is judged; the mop-up's only an unsure end's)
                got = self.sure.reached(self.cells, k, py, cov, pose[2], k < self.planned
                                        and not self._detour_start <= k < self._detour_end,
                                        mop=k >= self.planned)
                if got == SEEK:  # an end (or a route's far end) unsure of its edge: seek it
                    self._seeking, self._since = True, t
                    return self.step(pose, t, pose_t, cov)
                if got:  # the route to a height landmark and back, driven next
                    self.cells[k + 1:k + 1] = got
                    self.planned += len(got)
                    after = None  # (its first leg is faced instead)
                elif self.sure.back_at(k) and k + 1 < len(self.cells):
                    after = step_heading(*self.cells[k:k + 2], self.cols)
            self._detour_after(self.index)
            self.index += 1
            self._since = t
            if cov is not None and self._fix_first(pose, cov):
                after = None  # (the route's first leg is faced instead)
            if self.turns_in_place:
                self._plan_moves(after, pose)
        else:
            self._flush()
            self._set(CoverageState.DONE)
            return 0.0, 0.0
        return self._speeds(pose, t, pose_t, self.gain * ex, self.gain * ey)

    def _would_touch(self, pose: tuple[float, float, float], v: float, w: float) -> bool:
        """The steering's (v, ω) (ω within the board's limit), held for LOOK_AHEAD_S,
        would take the body's footprint (on the estimate, grown by the reach's margin)
        further past the shell's edge or into an obstacle than it is now, anywhere on
        the way (:meth:`.reach.Reach.arc_depth`): steering the probe sideways swings a
        corner round the body's centre, near an edge or a nozzle into it; the probe is then
        driven along the heading only, or first stepped sideways (:mod:`.side_step`)."""
        if self.reach is None or abs(w) < 1e-6:
            return False
        x, y, th = pose
        now = max(0.0, self.reach.contact.depth(x % self.circ_m, y, th, self.reach.margin)[0])
        w = max(-self.params.omega_max_rps, min(self.params.omega_max_rps, w))
        return self.reach.arc_depth(x, y, th, v, w, LOOK_AHEAD_S, self.circ_m) > now + 1e-4

    def touched(self, t: float, last_v: float) -> None:
        """The board reported a contact (the body stopped at an edge or an obstacle,
        or still pressed against it): give up the moves at hand and back away
        (``last_v``: the speed last commanded); once backed away, the moves to the
        target are planned again from where the body is (a turn's sweep cleared
        first, a lane change's step), not left to the probe's steering alone, which
        swings the body's corners round; the target is given up at its
        TOUCHES_PER_TARGET-th contact."""
        if self.state != CoverageState.RUNNING:
            return
        self._touches = self._touches + 1 if self._touched_at == self.index else 1
        self._touched_at = self.index
        if self._seeking:  # a contact ends the guarded move (else it pushed on, each
            self.seek.abandon()  # contact renewing its time: a wedge against the edge)
            self._seeking = False
        turning = bool(self.moves) and self.moves.queue[0][0].startswith("turn")
        self.moves.recoil(last_v, turning, self._pose)
        self._replan = True  # the moves given up are planned again once the recoil is done
        if self._touches >= TOUCHES_PER_TARGET and self.index < len(self.cells):
            log.info("contacts on the way to cell %s; going on", self.cells[self.index])
            self.index += 1
            self._touches = 0
            self._round_to_next()
        self._since = t

    @staticmethod
    def _freshness(t: float, pose_t: float | None) -> float:
        """1, or less in proportion when the estimate is older than FRESH_S."""
        return FRESH_S / (t - pose_t) if pose_t is not None and t - pose_t > FRESH_S else 1.0

    def _speeds(self, pose: tuple[float, float, float], t: float, pose_t: float | None,
                ux: float, uy: float) -> tuple[float, float]:
        """(v, ω) that move the probe at (ux, uy), within the speed limit."""
        p = self.params
        speed = math.hypot(ux, uy)
        v_max = p.v_max_mps * self._freshness(t, pose_t)
        if speed > v_max:
            ux, uy = ux * v_max / speed, uy * v_max / speed
        c, s = math.cos(pose[2]), math.sin(pose[2])
        return ux * c + uy * s, (-ux * s + uy * c) / self.lead
