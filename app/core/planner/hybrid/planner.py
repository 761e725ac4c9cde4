"""Global path plus local avoidance (seed 000 §4.2.5, Fig. 15).

1. Global: A* or JPS on the map inflated by the robot's radius, shortened to
   an any-angle polyline and smoothed (anyangle.py), in world metres.
2. Follow it (pure pursuit on a look-ahead point).
3. When a moving obstacle within ``detect_range_m`` is a threat (its
   constant-velocity closest approach to the robot driving along the path
   falls under ``threat_gap_m``, or it is within ``close_range_m``), a local
   planner —
   the improved potential field (apf.py, eqs. 28–40) or the dynamic window
   (dwa.py) — steers towards a point of the global path beyond it.
4. Once no moving obstacle is in range, rejoin the path at the nearest point
   ahead and follow it again.

Every command (v, ω) respects the kinematic limits (seed 003 Table 3 by
default). A safety governor checks every command against the constant-
velocity prediction of the moving obstacles (a standing person's disc
growing with time, as he may set off) and keeps it only if

- held over ``safety_horizon_s`` it stays clear by ``safety_margin_m``, and
- held for ``commit_s`` and then braked to rest at the limits, the robot
  would stand clear for the rest of the horizon (a braking contingency:
  the robot never goes where it could no longer stop out of a walker's way;
  Fraichard & Asama's inevitable collision states, passive safety).

Otherwise it takes the reachable command nearest to the wanted one that
passes both (or, failing that, the contingency alone; counted in
``governor_count``). When none can stop clear (``cornered_count``): an
escape that never meets an obstacle as predicted, the clearest one (the
growing disc left out, so a robot beside a standing person backs away
rather than freezing); and when contact comes whatever it does, the braking
contingency slowest at contact, then latest (``estop_count``): the robot
stands, or moves as slowly as it can, when the contact comes. When the
dynamic window has no admissible arc, the potential field (under the
governor) takes over until it has one again.

World frame: x right, y up, metres; θ from +x, counter-clockwise.
"""

from __future__ import annotations

import math

import numpy as np

from ..apf import PotentialField
from ..dwa import DynamicWindow
from ..grid import GridMap
from .config import AVOIDING, BLOCKED, FOLLOWING, NO_PATH, REACHED, REJOINING, HybridConfig
from .governor import SafetyGovernor
from .rollout import _growth
from .route import GlobalRoute


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class HybridPlanner(GlobalRoute, SafetyGovernor):
    """Global planning and local avoidance in the world frame (metres).

    >>> hp = HybridPlanner(grid, HybridConfig(local_planner="dwa"))
    >>> path = hp.plan((1.0, 1.0), (9.0, 7.5))          # [(x, y), ...]
    >>> v, omega, status = hp.step((x, y, theta), (v, omega), obstacles, 0.1)
    """

    def __init__(self, grid: GridMap, config: HybridConfig | None = None):
        self.grid = grid
        self.cfg = config or HybridConfig()
        if self.cfg.local_planner not in ("apf", "dwa"):
            raise ValueError(
                f"local_planner must be 'apf' or 'dwa', not {self.cfg.local_planner!r}"
            )
        r = self.cfg.robot_radius_m
        self.inflated = grid.inflate(r + self.cfg.inflation_margin_m)
        # The kernels' layout (uint8, C order), converted once: replanning
        # then costs the search, not copies of the map.
        self._inflated_u8 = np.ascontiguousarray(self.inflated.blocked, dtype=np.uint8)
        self._dist = np.ascontiguousarray(grid.distance_m, dtype=np.float64)
        self.apf = PotentialField(grid, r, self.cfg.apf)
        self.dwa = DynamicWindow(grid, r, self.cfg.kin, self.cfg.dwa)
        c = self.cfg
        self._grow = (c.slow_grow_mps, c.slow_grow_cap_m, c.slow_below_mps, c.moving_grow_mps)
        self.path = np.zeros((0, 2))
        self._s = np.zeros(0)
        self._idx = 0
        self._mode = NO_PATH
        self._clear_for_s = 0.0
        self.governor_count = 0
        self.cornered_count = 0  # governor steps with no contact-free motion
        self.estop_count = 0  # of those, steps braking to rest (contact imminent)
        self.escape_found = True
        self.replan_count = 0
        self.last_plan = None
        self._best_goal_dist = math.inf
        self._stall_s = 0.0
        self._avoid_s = 0.0
        self._avoid_best = math.inf

    def warm_up(self) -> None:
        """Load (or compile) the governor's kernels now rather than at the first
        threat: one candidate search beside the map's most open cell. The
        counters are left as they were."""
        counts = (self.governor_count, self.cornered_count, self.estop_count)
        r, c = np.unravel_index(int(np.argmax(self._dist)), self._dist.shape)
        ox, oy = self.grid.origin_xy
        res = self.grid.resolution_m
        q = np.array([ox + (c + 0.5) * res, oy + (r + 0.5) * res])
        obs = np.array([[q[0] + 0.6, q[1], -0.5, 0.0, 0.3]])
        self._govern(q, 0.0, 0.5, 0.0, 0.5, 0.0, 0.1, obs)
        self._can_stop(q, 0.0, 0.5, 0.0, 0.5, 0.0, obs)
        _growth(obs, self._grow[0], self._grow[2])  # as a replan around obstacles calls it
        self.governor_count, self.cornered_count, self.estop_count = counts

    # -- local -------------------------------------------------------------------
    def _track(self, q, th, target, v_cap):
        """Heading controller towards a point: turn in place beyond 60°."""
        k = self.cfg.kin
        err = _wrap(math.atan2(target[1] - q[1], target[0] - q[0]) - th)
        w = float(np.clip(self.cfg.heading_gain * err, -k.omega_max_rps, k.omega_max_rps))
        v = v_cap * max(0.0, math.cos(err)) ** 2 if abs(err) < math.radians(60) else 0.0
        if v == 0.0 and abs(w) < k.omega_min_rps and abs(err) > 0.05:
            w = math.copysign(k.omega_min_rps, err)
        return v, w

    def _apf_command(self, q, th, s, vc, wc, v_cap, local_goal, obs, dt):
        """(v, ω) from the improved potential field, through the governor."""
        k = self.cfg.kin
        vel = np.array([vc * math.cos(th), vc * math.sin(th)])
        ahead = self._point_at(s + 0.5) - self._point_at(s)
        n = np.hypot(*ahead)
        v_goal = ahead / n * k.v_max_mps if n > 1e-9 else np.zeros(2)
        f = self.apf.desired_velocity(q, vel, local_goal, obs, dt, v_goal)
        if np.hypot(*f) < 1e-9:
            v, w = 0.0, 0.0
        else:
            v, w = self._track(q, th, q + f, min(v_cap, k.v_max_mps))
        v, w = self._limit(v, w, vc, wc, dt)
        return self._govern(q, th, v, w, vc, wc, dt, obs)

    def _threat(self, q: np.ndarray, s: float, obs: np.ndarray) -> bool:
        """A moving obstacle within detect_range_m that, at constant velocity
        against the robot driving along its path at full speed, comes within
        threat_gap_m in the next threat_horizon_s; or any within close_range_m."""
        cfg = self.cfg
        surf = np.hypot(obs[:, 0] - q[0], obs[:, 1] - q[1]) - obs[:, 4] - cfg.robot_radius_m
        if np.any(surf <= cfg.close_range_m):
            return True
        ahead = self._point_at(s + cfg.lookahead_m) - q
        n = float(np.hypot(*ahead))
        v_robot = ahead / n * cfg.kin.v_max_mps if n > 1e-9 else np.zeros(2)
        p = obs[:, :2] - q
        u = obs[:, 2:4] - v_robot
        uu = np.maximum(np.sum(u * u, axis=1), 1e-12)
        t = np.clip(-np.sum(p * u, axis=1) / uu, 0.0, cfg.threat_horizon_s)
        gap = np.hypot(p[:, 0] + u[:, 0] * t, p[:, 1] + u[:, 1] * t) - obs[:, 4]
        gap -= cfg.robot_radius_m
        return bool(np.any((surf <= cfg.detect_range_m) & (gap <= cfg.threat_gap_m)))

    def step(self, pose_xytheta, velocity, obstacles=(), dt: float = 0.1):
        """One control step: (v_mps, omega_rps, status).

        velocity: the robot's current (v_mps, omega_rps) (or just v_mps);
        obstacles: moving obstacles seen now, [(x, y, vx, vy, radius), ...].
        """
        if self._mode == NO_PATH or len(self.path) == 0:
            return 0.0, 0.0, NO_PATH
        cfg, k = self.cfg, self.cfg.kin
        q = np.array([float(pose_xytheta[0]), float(pose_xytheta[1])])
        th = float(pose_xytheta[2])
        if np.ndim(velocity) == 0:
            vc, wc = float(velocity), 0.0
        else:
            vc, wc = float(velocity[0]), float(velocity[1])
        obs = np.asarray(list(obstacles), dtype=np.float64).reshape(-1, 5)
        goal = self.path[-1]
        d_goal = float(np.hypot(*(goal - q)))
        if d_goal <= cfg.goal_tolerance_m:
            self._mode = REACHED
            return 0.0, 0.0, REACHED
        s = self._project(q)
        near = self._threat(q, s, obs) if len(obs) else False
        v_cap = min(
            k.v_max_mps,
            math.sqrt(2 * k.accel_mps2 * max(d_goal - 0.02, 0.0)),
            max(0.6 * d_goal, 0.03),
        )
        if near:
            if self._mode != AVOIDING:
                self.apf.reset()
                self._avoid_s = 0.0
                self._avoid_best = d_goal
            self._mode = AVOIDING
            # Avoiding without getting closer to the goal (e.g. herded by a
            # slow obstacle): plan a new global path around the obstacles.
            self._avoid_s += dt
            if d_goal < self._avoid_best - 0.1:
                self._avoid_best = d_goal
                self._avoid_s = 0.0
            elif self._avoid_s >= cfg.avoid_replan_s:
                self._avoid_s = 0.0
                self._avoid_best = d_goal
                if self._replan(q, obs):
                    s = self._project(q)
            self._clear_for_s = 0.0
            local_goal = self._point_at(s + cfg.rejoin_ahead_m)
            if cfg.local_planner == "dwa":
                v, w, ok = self.dwa.step((q[0], q[1], th), (vc, wc), local_goal, obs, dt)
                if ok:
                    # A DWA arc must leave a wider gap to the moving obstacles
                    # (yield early, before a squeeze closes).
                    v, w = self._govern(q, th, v, w, vc, wc, dt, obs, cfg.dwa_yield_margin_m)
                    return v, w, AVOIDING
                # No admissible arc over the whole horizon: the potential
                # field (its repulsion flees the obstacles) under the governor.
                v, w = self._apf_command(q, th, s, vc, wc, v_cap, local_goal, obs, dt)
                return v, w, BLOCKED
            v, w = self._apf_command(q, th, s, vc, wc, v_cap, local_goal, obs, dt)
            return v, w, AVOIDING

        if self._mode == AVOIDING:
            self._clear_for_s += dt
            if self._clear_for_s >= cfg.clear_time_s:
                self._mode = REJOINING
                if cfg.replan_on_rejoin and self._replan(q):
                    s = self._project(q)
        # Stall watch: no new best distance to the goal for stall_time_s.
        if d_goal < self._best_goal_dist - 0.05:
            self._best_goal_dist = d_goal
            self._stall_s = 0.0
        else:
            self._stall_s += dt
            if self._stall_s >= cfg.stall_time_s and self._replan(q):
                s = self._project(q)
        target = self._point_at(s + cfg.lookahead_m)
        if s + cfg.lookahead_m >= self._s[-1]:
            target = goal
        v, w = self._track(q, th, target, v_cap)
        v, w = self._limit(v, w, vc, wc, dt)
        v, w = self._govern(q, th, v, w, vc, wc, dt, obs)
        if self._mode == REJOINING:
            lateral = float(
                np.min(np.linalg.norm(self.path[max(0, self._idx - 2) : self._idx + 3] - q, axis=1))
            )
            if lateral < 0.1:
                self._mode = FOLLOWING
        status = REJOINING if self._mode in (AVOIDING, REJOINING) else FOLLOWING
        return v, w, status
