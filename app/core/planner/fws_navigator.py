"""The 4WS patrol robot's navigation (seed 004): the optimised A* plans, the
optimised TEB shapes the local trajectory, pure pursuit follows it.

Each leg, :meth:`FwsNavigator.plan` runs :func:`any_angle` (§2.2, Figs. 5–7)
on the station map inflated by the robot's radius and margin and smooths the
vertices with :func:`smooth_path` (non-uniform cubic spline, Fig. 9(c)).
Each control step, :meth:`FwsNavigator.step`:

1. every ``teb_period_s`` (sim time) runs one optimised TEB cycle
   (§2.3, Fig. 8, steps ①–⑦ in :mod:`teb`) from the pose to the path point
   ``local_goal_m`` ahead, with the clearance field of the static map and the
   tracked moving obstacles (their discs now and where they will be over the
   next ``predict_s``);
2. while the TEB turns in place (heading error over 30°, step ②) the base
   pivots (4WS PIVOT mode: v = 0, ω);
3. otherwise pure pursuit (:mod:`pure_pursuit`, look-ahead scheduled with the
   speed, counter-phase arcs) tracks the TEB band;
4. a safety check: when a moving obstacle's disc (swept over the next
   ``predict_s``) comes within the clearance of the next ``stop_horizon_m``
   of the band, the base stops ("blocked") until the band has been clear for
   ``resume_s``;
5. with ``crab_docking``, near the goal with the goal a little to one side
   (within ``crab_range_m``, within the servo travel of ahead) the base slides
   straight at it in CRAB mode instead (before a pivot: a slide of a few
   decimetres is not worth turning for); ``step`` returns its forward speed
   and puts the sideways one in ``lateral_mps`` for a base that takes it.

With ``background_teb`` the TEB cycles of step 1 run on a worker thread of
their own: ``step`` hands a cycle its inputs (the pose, the local goal and
path, the obstacle field) and goes on with the last finished cycle's band,
so a caller that holds a lock around ``step`` (the relay: its serial and
keep-alive threads wait on that lock) never waits for an optimisation. A
cycle started for a path that was replaced since is dropped. While the last
cycle says "turn in place", ``step`` steers the pivot itself towards the
band's direction (ω = err / 0.3 s, at most the TEB's yaw rate) and holds
still once within the TEB's ``turn_done_deg``, until the next cycle is in.

The face the mission executor (``sim_robot.patrol.PatrolExecutor``) asks of a
planner: ``plan``, ``step`` → (v, ω, status), ``path``, ``inflated``,
``set_path``, ``warm_up``, ``replan_count``, ``governor_count``. The last TEB
cycle is kept in ``last_teb`` for the desk's overlay.
"""

from __future__ import annotations

import logging
import math
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from ..kinematics import FwsGeometry, Mode, Twist, realise, select_mode
from .fws_yield import choose as choose_yield
from .grid import GridMap
from .optimised_astar import any_angle, smooth_path
from .pure_pursuit import PurePursuit, PurePursuitConfig
from .teb import ObstacleField, Teb, TebConfig, TebStep

log = logging.getLogger(__name__)

__all__ = ["FwsNavConfig", "FwsNavigator"]

FOLLOWING, AVOIDING, BLOCKED, REACHED, NO_PATH = ("following", "avoiding", "blocked",
                                                   "reached", "no_path")


@dataclass(frozen=True)
class FwsNavConfig:
    robot_radius_m: float = 0.35
    inflation_margin_m: float = 0.1
    v_max_mps: float = 0.6
    goal_tolerance_m: float = 0.12
    teb_period_s: float = 0.3
    local_goal_m: float = 3.0
    detect_range_m: float = 3.5
    predict_s: float = 1.5  # moving obstacles: where they will be
    stop_horizon_m: float = 1.0
    resume_s: float = 1.0  # after a stop, the band must stay clear this long
    # yielding (step 4): where standing would leave the robot in a tracked
    # person's predicted way, drive on along the band or back away instead
    yield_horizon_s: float = 3.0  # how far ahead the predictions are checked
    yield_margin_m: float = 0.1  # a standing robot this far clear of them is safe
    yield_back_mps: float = 0.3  # the speed of stepping aside
    yield_turn_rps: float = 0.4  # ... and its yaw rate on the arcs (radius 0.75 m)
    brake_mps2: float = 1.5  # the braking the rollouts assume (the base: 2.0)
    # the TEB keeps this much more from a tracked person than from a wall: one
    # standing at the road's edge may set off into the robot's way as it passes
    person_berth_m: float = 0.3
    accel_mps2: float = 0.8
    smooth_step_cells: float = 2.0
    background_teb: bool = False  # TEB cycles on a worker thread (see the module docstring)
    crab_docking: bool = False  # close a small sideways offset at the goal in CRAB mode
    crab_range_m: float = 0.5  # ... within this distance of the goal
    crab_max_offset_m: float = 0.3  # ... for offsets up to this across the chassis
    crab_speed_mps: float = 0.15
    geometry: FwsGeometry = field(default_factory=FwsGeometry)


class _WithObstacles:
    """The static clearance field with moving obstacles' discs folded in."""

    def __init__(self, static: ObstacleField, discs: np.ndarray) -> None:
        self.static = static
        self.discs = discs  # k × 3: x, y, radius

    def distance(self, xy: np.ndarray) -> np.ndarray:
        d = self.static.distance(xy)
        if len(self.discs):
            p = np.asarray(xy, dtype=float)[..., None, :]
            dd = np.linalg.norm(p - self.discs[:, :2], axis=-1) - self.discs[:, 2]
            d = np.minimum(d, np.maximum(np.min(dd, axis=-1), 0.0))
        return d

    def distance_and_grad(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`distance` and its gradient (…, 2), for the TEB's analytic
        Jacobian: the nearest disc's outward unit vector where a disc is
        nearer than the static field (0 inside a disc), else the field's."""
        d, g = self.static.distance_and_grad(xy)
        if len(self.discs):
            p = np.asarray(xy, dtype=float)[..., None, :]
            off = p - self.discs[:, :2]
            norm = np.linalg.norm(off, axis=-1)
            dd = norm - self.discs[:, 2]
            k = np.argmin(dd, axis=-1)[..., None]
            near = np.take_along_axis(dd, k, axis=-1)[..., 0]
            nk = np.take_along_axis(norm, k, axis=-1)
            unit = np.take_along_axis(off, k[..., None], axis=-2)[..., 0, :]
            unit = np.divide(unit, nk, out=np.zeros_like(unit), where=nk > 0)
            disc = np.maximum(near, 0.0)
            use = disc < d
            d = np.where(use, disc, d)
            g = np.where(use[..., None], unit * (near > 0)[..., None], g)
        return d, g


class FwsNavigator:
    """Global plan, TEB local plan and pure pursuit for the 4WS base on ``grid``."""

    def __init__(self, grid: GridMap, config: FwsNavConfig | None = None) -> None:
        self.grid = grid
        self.cfg = c = config or FwsNavConfig()
        self.clearance_m = c.robot_radius_m + c.inflation_margin_m
        self.inflated = grid.inflate(self.clearance_m)
        self.field = ObstacleField(grid.blocked, grid.resolution_m, grid.origin_xy)
        self.teb = Teb(TebConfig(max_speed_mps=c.v_max_mps, clearance_m=self.clearance_m,
                                 geometry=c.geometry))
        self.pp_cfg = PurePursuitConfig(speed_mps=c.v_max_mps, geometry=c.geometry)
        self.path = np.zeros((0, 2))
        self._s = np.zeros(0)
        self._path_new = False
        self._teb_due = 0.0
        self._pp: PurePursuit | None = None
        self.last_teb: TebStep | None = None
        self.replan_count = 0
        self.governor_count = 0
        self.yield_count = 0  # control steps spent backing away from a person's way
        self._tracks = np.zeros((0, 5))
        self.teb_cycles = 0
        self._hold_s = 0.0
        self.mode = NO_PATH
        self._gen = 0  # the path's generation: a cycle started for an older one is dropped
        self._pool: ThreadPoolExecutor | None = None
        self._job: Future | None = None
        self._job_lock = threading.Lock()
        self._pivot_to: float | None = None  # the heading a pivot turns to
        self.command: tuple[Mode, Twist] | None = None  # the last step's mode and twist
        # the last step's sideways speed (CRAB docking; 0 otherwise): ``step`` returns
        # (vx, ω) as every planner does, and a 4WS base reads this beside them
        self.lateral_mps = 0.0
        self._crabbing = False  # the last step slid in CRAB mode

    # ---- global --------------------------------------------------------------------
    def _free_cell(self, xy, name: str) -> tuple[int, int] | None:
        g = self.inflated
        r, c = g.world_to_cell(float(xy[0]), float(xy[1]))
        if not g.in_bounds(r, c):
            raise ValueError(f"{name} {tuple(xy)} lies outside the map")
        if not g.blocked[r, c]:
            return r, c
        rad = int(math.ceil(2 * self.cfg.robot_radius_m / g.resolution_m)) + 2
        r0, c0 = max(0, r - rad), max(0, c - rad)
        free = np.argwhere(~g.blocked[r0:r + rad + 1, c0:c + rad + 1])
        if len(free) == 0:
            return None
        k = int(np.argmin(np.hypot(free[:, 0] + r0 - r, free[:, 1] + c0 - c)))
        return int(free[k, 0] + r0), int(free[k, 1] + c0)

    def plan(self, start_xy, goal_xy) -> list[tuple[float, float]]:
        """The smoothed any-angle path from start to goal (metres), also set as the
        path to follow; [] when there is none. ValueError for a point off the map."""
        s = self._free_cell(start_xy, "start")
        t = self._free_cell(goal_xy, "goal")
        if s is None or t is None:
            self.set_path([])
            return []
        res = any_angle(self.inflated.blocked, s, t)
        if not res.points:
            self.set_path([])
            return []
        curve = smooth_path(self.inflated.blocked, res.points, safety_cells=1.0,
                            step=self.cfg.smooth_step_cells)
        g = self.grid
        xy = np.column_stack([g.origin_xy[0] + curve[:, 1] * g.resolution_m,
                              g.origin_xy[1] + curve[:, 0] * g.resolution_m])
        xy[0] = start_xy
        xy[-1] = goal_xy
        self.set_path(xy)
        return [(float(x), float(y)) for x, y in xy]

    def set_path(self, path_xy) -> None:
        p = np.asarray(path_xy, dtype=float).reshape(-1, 2)
        if len(p) > 1:
            p = p[np.r_[True, np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-6]]
        self.path = p
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1) if len(p) > 1 else np.zeros(0)
        self._s = np.concatenate([[0.0], np.cumsum(seg)]) if len(p) else np.zeros(0)
        self._path_new = True
        self._teb_due = -math.inf
        self._pp = None
        self.last_teb = None
        self._pivot_to = None
        self._crabbing = False
        self._hold_s = 0.0
        self._gen += 1
        self.mode = FOLLOWING if len(p) else NO_PATH

    def warm_up(self) -> None:
        """One TEB cycle and one pure-pursuit command on an open stretch of the map."""
        r, c = np.unravel_index(int(np.argmax(self.field.dist)), self.field.dist.shape)
        x, y = self.grid.cell_to_world(r, c)
        self.set_path([(x - 1.0, y), (x + 1.0, y)])
        goal, piece = self._local_goal(np.array([x - 1.0, y]))
        self._cycle(self._gen, np.array([x - 1.0, y, 0.0]), goal, piece,
                    _WithObstacles(self.field, np.zeros((0, 3))), 0.0, True)
        PurePursuit(piece, self.pp_cfg).command(np.array([x - 1.0, y, 0.0]), 0.0)
        self.set_path([])

    def close(self) -> None:
        """Stop the TEB worker (background mode); a cycle under way finishes first."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    # ---- local ---------------------------------------------------------------------
    def _local_goal(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The goal pose ``local_goal_m`` along the path from its point nearest xy,
        and the piece of path up to it."""
        p, s = self.path, self._s
        if len(p) < 2:  # start and goal in one cell
            d = p[-1] - xy
            return np.array([p[-1, 0], p[-1, 1], math.atan2(d[1], d[0])]), np.vstack([xy, p])
        k = int(np.argmin(np.linalg.norm(p - xy, axis=1)))
        end = s[k] + self.cfg.local_goal_m
        j = int(np.searchsorted(s, end))
        if j >= len(p) - 1:
            gxy, seg = p[-1], p[-1] - p[-2]
            piece = p[k:]
        else:
            f = (end - s[j - 1]) / max(s[j] - s[j - 1], 1e-9)
            gxy = p[j - 1] + f * (p[j] - p[j - 1])
            seg = p[j] - p[j - 1]
            piece = np.vstack([p[k:j], gxy])
        if len(piece) < 2:
            piece = np.vstack([xy, gxy])
        return np.array([gxy[0], gxy[1], math.atan2(seg[1], seg[0])]), piece

    def _discs(self, q: np.ndarray, obstacles) -> np.ndarray:
        """Tracked obstacles within range as discs where they are and where they
        will be every half second up to ``predict_s`` (k × 3); the tracks
        themselves (x, y, vx, vy, r) are kept in ``_tracks`` for yielding."""
        obs = np.asarray(obstacles, dtype=float).reshape(-1, 5)
        self._tracks = obs[:0]
        if not len(obs):
            return np.zeros((0, 3))
        near = np.hypot(obs[:, 0] - q[0], obs[:, 1] - q[1]) < self.cfg.detect_range_m
        obs = obs[near]
        self._tracks = obs
        taus = np.arange(0.0, self.cfg.predict_s + 1e-9, 0.5)
        return np.vstack([np.column_stack([obs[:, :2] + tau * obs[:, 2:4], obs[:, 4]])
                          for tau in taus]) if len(obs) else np.zeros((0, 3))

    def _berth(self, discs: np.ndarray) -> np.ndarray:
        """People's discs as the TEB's clearance field takes them: widened by
        ``person_berth_m`` (the stop check and yielding use the discs as seen)."""
        if not len(discs) or self.cfg.person_berth_m <= 0:
            return discs
        out = discs.copy()
        out[:, 2] += self.cfg.person_berth_m
        return out

    def step(self, pose_xytheta, velocity, obstacles=(), dt: float = 0.1):
        """One control step: (v_mps, omega_rps, status); the sideways speed of a
        CRAB step in ``lateral_mps``."""
        self.lateral_mps = 0.0
        if len(self.path) == 0:
            return 0.0, 0.0, NO_PATH
        pose = np.array([float(v) for v in pose_xytheta[:3]])
        q = pose[:2]
        v_now = float(velocity[0]) if np.ndim(velocity) else float(velocity)
        if np.linalg.norm(self.path[-1] - q) <= self.cfg.goal_tolerance_m:
            self.mode = REACHED
            return 0.0, 0.0, REACHED
        discs = self._discs(q, obstacles)
        self._teb_due -= dt
        if self.cfg.background_teb:
            self._collect()
        t = self.last_teb
        due = self._teb_due <= 0 or (t is not None and t.turning_in_place) or self._pp is None
        if self.cfg.background_teb:
            if due and self._job is None:
                self._start_cycle(pose, q, discs, v_now)
        elif due:
            goal, piece = self._local_goal(q)
            gen, step, band = self._cycle(self._gen, pose, goal, piece,
                                          _WithObstacles(self.field, self._berth(discs)), v_now,
                                          self._path_new)
            self._path_new = False
            self._teb_due = self.cfg.teb_period_s
            self._apply(step, band)
        t = self.last_teb
        self.command = None
        # docking alignment first: a goal within reach of a straight slide is not
        # worth a pivot (the TEB turns in place past 30° of heading error)
        crab = self._crab(pose) if self.cfg.crab_docking else None
        if crab is None and t is not None and t.turning_in_place:
            self.mode = FOLLOWING
            back = self._yield(pose, v_now, along_band=False) if len(discs) else None
            if back is not None:  # a pivot stands where it is: not in someone's way
                return self._yielding(back)
            om = self._pivot_rate(pose, t)
            self.command = (Mode.PIVOT, Twist(0.0, 0.0, om))
            return 0.0, om, FOLLOWING
        if self._pp is None:
            return 0.0, 0.0, FOLLOWING
        status = AVOIDING if len(discs) else FOLLOWING
        if len(discs) and self._threat(pose, discs):
            self.governor_count += 1
            self._hold_s = self.cfg.resume_s
        if self._hold_s > 0:
            way = self._yield(pose, v_now, along_band=True)
            if way == "on":  # stopping here would leave it in a person's way
                self._hold_s = 0.0
            elif way is not None:
                return self._yielding(way)
            else:
                self._hold_s -= dt
                self.mode = BLOCKED
                return 0.0, 0.0, BLOCKED
        self.mode = status
        if crab is not None:
            self.command = (Mode.CRAB, crab)
            self.lateral_mps = crab.vy
            return crab.vx, 0.0, status
        tw = self._pp.command(pose, v_now)
        m = select_mode(self.cfg.geometry, Twist(float(tw.vx), 0.0, float(tw.omega)))
        self.command = (m, realise(self.cfg.geometry, m, tw))
        return float(tw.vx), float(tw.omega), status

    def _yielding(self, vw: tuple[float, float]) -> tuple[float, float, str]:
        self.governor_count += 1
        self.yield_count += 1
        self.mode = BLOCKED
        self.command = (Mode.COUNTER, Twist(vw[0], 0.0, vw[1]))
        return vw[0], vw[1], BLOCKED

    def _yield(self, pose: np.ndarray, v_now: float, along_band: bool):
        """Stand (None), drive on along the band ("on") or step aside ((v, ω)):
        :func:`fws_yield.choose` on the robot's own tracks."""
        band = self._pp.path if along_band and self._pp is not None else None
        return choose_yield(self.cfg, self.field, self._tracks, pose, v_now, band)

    def _crab(self, pose: np.ndarray) -> Twist | None:
        """Docking alignment: near the goal, with the heading right but the goal
        a little to one side (an arc cannot close an offset shorter than the
        turning radius), translate straight at it in CRAB mode — all four
        wheels at one angle, no rotation."""
        c = self.cfg
        d = self.path[-1] - pose[:2]
        dist = float(np.hypot(*d))
        if dist > c.crab_range_m or dist < 1e-6:
            self._crabbing = False
            return None
        cs, sn = math.cos(pose[2]), math.sin(pose[2])
        ex, ey = cs * d[0] + sn * d[1], -sn * d[0] + cs * d[1]  # the goal in the body frame
        # a slide once begun goes on to the goal however small the offset left
        # (else the pose estimate's noise near the goal ends it, and the TEB pivots)
        lim = c.geometry.servo_range_rad
        if self._crabbing:
            if abs(ey) > c.crab_max_offset_m:
                self._crabbing = False
                return None
            return Twist(*_slide_towards(ex, ey, lim, min(c.crab_speed_mps, 0.8 * dist)), 0.0)
        if not (c.goal_tolerance_m / 2 < abs(ey) <= c.crab_max_offset_m) or ex < -0.05 or \
                abs(math.atan2(ey, max(ex, 1e-9))) > lim:
            return None  # (steeper than the servos turn: left to the arcs)
        self._crabbing = True
        s = min(c.crab_speed_mps, 0.8 * dist)
        return Twist(s * ex / dist, s * ey / dist, 0.0)

    # ---- TEB cycles -----------------------------------------------------------------
    def _cycle(self, gen: int, pose, goal, piece, fld, v_now: float, path_new: bool):
        """One TEB cycle: (gen, TebStep or None, the band pure pursuit follows)."""
        try:
            st = self.teb.plan_step(pose, goal, piece, fld, max(v_now, 0.0),
                                    path_is_new=path_new)
        except (ValueError, np.linalg.LinAlgError) as e:
            log.warning("TEB cycle failed (%s); following the global path", e)
            st = None
        return gen, st, (piece if st is None else st.poses[:, :2])

    def _apply(self, step: TebStep | None, band: np.ndarray) -> None:
        self.last_teb = step
        self.teb_cycles += 1
        self._pivot_to = _heading_along(step.poses) if step is not None and \
            step.turning_in_place else None
        try:
            self._pp = PurePursuit(band, self.pp_cfg)
        except ValueError:
            self._pp = None

    def _start_cycle(self, pose, q, discs, v_now: float) -> None:
        goal, piece = self._local_goal(q)
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="fws-teb")
        with self._job_lock:
            self._job = self._pool.submit(self._cycle, self._gen, pose.copy(), goal, piece,
                                          _WithObstacles(self.field, self._berth(discs)), v_now,
                                          self._path_new)
        self._path_new = False
        self._teb_due = self.cfg.teb_period_s

    def _collect(self) -> None:
        """Take the worker's finished cycle (dropped when the path changed since)."""
        with self._job_lock:
            job = self._job
            if job is None or not job.done():
                return
            self._job = None
        gen, st, band = job.result()
        if gen == self._gen:
            self._apply(st, band)

    def _pivot_rate(self, pose: np.ndarray, t: TebStep) -> float:
        """The yaw rate of a pivot: the TEB's own, or (background mode, where the
        cycle may be old) steered from the pose towards the band's direction,
        0 once within the TEB's ``turn_done_deg``."""
        if not self.cfg.background_teb or self._pivot_to is None:
            return float(t.twist.omega)
        c = self.teb.cfg
        err = math.remainder(self._pivot_to - float(pose[2]), 2 * math.pi)
        if abs(err) <= math.radians(c.turn_done_deg):
            return 0.0
        return math.copysign(min(c.max_yaw_rate, abs(err) / 0.3), err)

    def _threat(self, pose: np.ndarray, discs: np.ndarray) -> bool:
        """A disc within the clearance of the band's next ``stop_horizon_m``."""
        band = self._pp.path
        d = np.linalg.norm(np.diff(band, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(d)])
        pts = band[(s >= 0.2) & (s <= self.cfg.stop_horizon_m)]
        if not len(pts):
            return False
        gap = np.linalg.norm(pts[:, None, :] - discs[None, :, :2], axis=2) - discs[:, 2]
        return bool(np.min(gap) < self.cfg.robot_radius_m + 0.05)


def _slide_towards(ex: float, ey: float, lim: float, speed: float) -> tuple[float, float]:
    """The body velocity (vx, vy) of a crab slide at ``speed`` towards the goal
    at (ex, ey) in the body frame, with the wheels within ±``lim`` of straight:
    backwards (the speed reversed) to a goal behind, which a late control step
    carried the slide past; at the servo's limit when the goal lies further to
    the side (a late or lagging pose estimate: within ``lim`` of the goal's
    direction, so the distance still shrinks), rather than a pivot."""
    a = math.atan2(ey, ex)
    back = abs(a) > math.pi / 2
    wheel = a - math.copysign(math.pi, a) if back else a
    travel = max(-lim, min(lim, wheel)) + (math.pi if back else 0.0)
    return speed * math.cos(travel), speed * math.sin(travel)


def _heading_along(poses: np.ndarray, ahead_m: float = 0.5) -> float | None:
    """The direction from the band's first pose to its first pose ``ahead_m`` away."""
    d = np.linalg.norm(poses[:, :2] - poses[0, :2], axis=1)
    far = np.nonzero(d > ahead_m)[0]
    if not len(far):
        return None
    v = poses[far[0], :2] - poses[0, :2]
    return math.atan2(float(v[1]), float(v[0]))
