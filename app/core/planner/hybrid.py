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

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from . import anyangle
from .apf import APFConfig, PotentialField
from .astar import astar
from .dwa import DWAConfig, DynamicWindow, Kinematics
from .grid import GridMap
from .jps import jps

log = logging.getLogger(__name__)

FOLLOWING = "following"
AVOIDING = "avoiding"
REJOINING = "rejoining"
REACHED = "reached"
BLOCKED = "blocked"
NO_PATH = "no_path"
WALL_SLACK_M = 1e-3  # a robot touching a wall by the map may not go deeper than this


@dataclass
class HybridConfig:
    robot_radius_m: float = 0.25
    inflation_margin_m: float = 0.1
    local_planner: str = "apf"  # "apf" | "dwa"
    global_planner: str = "jps"  # "jps" | "astar"
    smooth: bool = True
    detect_range_m: float = 2.5  # surface distance that starts local avoidance
    close_range_m: float = 0.6  # any moving obstacle this close is avoided
    threat_gap_m: float = 0.5  # predicted closest approach that counts as a threat
    threat_horizon_s: float = 20.0
    clear_time_s: float = 1.0  # obstacle-free time before rejoining
    replan_on_rejoin: bool = True  # rejoin by replanning from where the robot is
    stall_time_s: float = 8.0  # no progress along the path this long: replan
    avoid_replan_s: float = 10.0  # avoiding this long without progress: replan around obstacles
    obstacle_sweep_s: float = 3.0  # a replan around obstacles blocks their next seconds
    replan_window_m: float = 5.0  # ... and searches only this far around start and goal
    lookahead_m: float = 0.4
    rejoin_ahead_m: float = 1.5  # local goal: this far along the path past the robot
    goal_tolerance_m: float = 0.1
    heading_gain: float = 1.5
    safety_horizon_s: float = 5.0
    safety_margin_m: float = 0.03
    dwa_yield_margin_m: float = 0.15  # the governor's margin for DWA arcs
    # Passive safety: a command is kept only if, held for commit_s and then
    # braked to rest at the limits, the robot would stand clear of every
    # predicted obstacle for the rest of the safety horizon (0 turns it off).
    commit_s: float = 0.3
    # The governor's prediction of a slow moving obstacle (a person standing
    # may set off): its disc grows at slow_grow_mps (standing; less the
    # faster it goes, none from slow_below_mps) up to slow_grow_cap_m more.
    slow_grow_mps: float = 0.0
    slow_grow_cap_m: float = 0.0
    slow_below_mps: float = 0.5
    # ... and a moving one's at moving_grow_mps (its heading and speed are
    # estimates), up to the same cap.
    moving_grow_mps: float = 0.0
    kin: Kinematics = field(default_factory=Kinematics)
    apf: APFConfig = field(default_factory=APFConfig)
    dwa: DWAConfig = field(default_factory=DWAConfig)


@njit(cache=True)
def _growth(obs, grow, grow_below, grow_moving=0.0):
    """Per obstacle, how fast its predicted disc grows (m/s): ``grow`` for
    one standing, falling linearly to 0 at ``grow_below`` m/s and above, but
    never below ``grow_moving`` (the uncertainty of a walker's velocity)."""
    out = np.full(obs.shape[0], grow_moving)
    if grow > 0.0 and grow_below > 0.0:
        for m in range(obs.shape[0]):
            sp = math.hypot(obs[m, 2], obs[m, 3])
            if sp < grow_below:
                out[m] = max(grow * (1.0 - sp / grow_below), grow_moving)
    return out


@njit(cache=True)
def rollout_clearance(
    x,
    y,
    th,
    v,
    w,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
):
    """Smallest surface clearance along the arc (v, ω) over the horizon (from
    the first step on, so moves away from a near obstacle score higher),
    against the static field and constant-velocity moving obstacles (a slow
    one's disc growing with time, see rollout_ramp)."""
    dmin = 1e9
    steps = int(horizon / sdt + 0.5)
    h, wd = dist.shape
    rate = _growth(obs, grow, grow_below, grow_moving)
    for s in range(1, steps + 1):
        x += v * math.cos(th) * sdt
        y += v * math.sin(th) * sdt
        th += w * sdt
        c = int(math.floor((x - ox) / res))
        r = int(math.floor((y - oy) / res))
        if r < 0 or r >= h or c < 0 or c >= wd:
            d = -1.0
        else:
            d = dist[r, c] - robot_r
        t = s * sdt
        for m in range(obs.shape[0]):
            dd = math.hypot(x - obs[m, 0] - obs[m, 2] * t, y - obs[m, 1] - obs[m, 3] * t)
            dd -= obs[m, 4] + robot_r + min(rate[m] * t, grow_cap)
            if dd < d:
                d = dd
        if d < dmin:
            dmin = d
    return dmin


@njit(cache=True)
def rollout_ramp(
    x,
    y,
    th,
    vc,
    wc,
    vt,
    wt,
    acc,
    alpha,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    phi=np.nan,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
    stop_after=np.inf,
):
    """Drive from (vc, ω_c) towards the target (vt, ωt) at the acceleration
    limits, then hold it; or, with a heading phi, stop and turn in place
    (|ωt| as turn rate) until facing phi, then drive straight at vt. With a
    finite ``stop_after`` the motion is a contingency: after that many
    seconds the robot brakes to rest at the limits and stands there for the
    rest of the horizon. Every rollout is checked against
    the static clearance field and the
    constant-velocity prediction of every moving obstacle. A slow obstacle
    (a person standing may set off in any direction) is predicted as a disc
    growing with time: its radius + min(rate · t, grow_cap), rate = grow for
    one standing, falling linearly to 0 at grow_below m/s (grow 0: no
    growth), and at least grow_moving for any. Returns (smallest static
    clearance, smallest clearance to a moving obstacle, time of the first
    contact with anything or +inf)."""
    d_static = 1e9
    d_moving = 1e9
    t_hit = math.inf
    steps = int(horizon / sdt + 0.5)
    h, wd = dist.shape
    v = vc
    w = wc
    turn = not math.isnan(phi)
    rate = _growth(obs, grow, grow_below, grow_moving)
    for s in range(1, steps + 1):
        tv = vt
        tw = wt
        if (s - 1) * sdt >= stop_after:
            tv = 0.0
            tw = 0.0
        elif turn:
            err = (phi - th + math.pi) % (2.0 * math.pi) - math.pi
            if abs(err) > 0.2:
                tv = 0.0
                tw = abs(wt) if err > 0 else -abs(wt)
            else:
                tw = min(max(2.0 * err, -abs(wt)), abs(wt))
        v += min(max(tv - v, -acc * sdt), acc * sdt)
        w += min(max(tw - w, -alpha * sdt), alpha * sdt)
        x += v * math.cos(th) * sdt
        y += v * math.sin(th) * sdt
        th += w * sdt
        c = int(math.floor((x - ox) / res))
        r = int(math.floor((y - oy) / res))
        if r < 0 or r >= h or c < 0 or c >= wd:
            d = -1.0
        else:
            d = dist[r, c] - robot_r
        if d < d_static:
            d_static = d
        t = s * sdt
        for m in range(obs.shape[0]):
            dd = math.hypot(x - obs[m, 0] - obs[m, 2] * t, y - obs[m, 1] - obs[m, 3] * t)
            dd -= obs[m, 4] + robot_r + min(rate[m] * t, grow_cap)
            if dd < d_moving:
                d_moving = dd
            if dd < d:
                d = dd
        if d <= 0.0 and t < t_hit:
            t_hit = t
    return d_static, d_moving, t_hit


@njit(cache=True)
def rollout_many(
    x,
    y,
    th,
    vc,
    wc,
    cands,
    acc,
    alpha,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
    stop_after=np.inf,
):
    """rollout_ramp for every candidate row (v_target, ω_target, phi) of
    cands; rows of (static clearance, moving clearance, first contact)."""
    out = np.empty((cands.shape[0], 3))
    for i in range(cands.shape[0]):
        ds, dm, t_hit = rollout_ramp(
            x,
            y,
            th,
            vc,
            wc,
            cands[i, 0],
            cands[i, 1],
            acc,
            alpha,
            horizon,
            sdt,
            dist,
            res,
            ox,
            oy,
            obs,
            robot_r,
            cands[i, 2],
            grow,
            grow_cap,
            grow_below,
            grow_moving,
            stop_after,
        )
        out[i, 0] = ds
        out[i, 1] = dm
        out[i, 2] = t_hit
    return out


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class HybridPlanner:
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

    # -- global ------------------------------------------------------------------
    def _nearest_free(self, cell: tuple[int, int], b: np.ndarray) -> tuple[int, int] | None:
        r, c = cell
        if not self.inflated.in_bounds(r, c):
            return None
        if not b[r, c]:
            return cell
        rad = int(math.ceil((self.cfg.robot_radius_m * 2) / self.grid.resolution_m)) + 2
        r0, r1 = max(0, r - rad), min(b.shape[0], r + rad + 1)
        c0, c1 = max(0, c - rad), min(b.shape[1], c + rad + 1)
        free = np.argwhere(b[r0:r1, c0:c1] == 0)
        if len(free) == 0:
            return None
        d = np.hypot(free[:, 0] + r0 - r, free[:, 1] + c0 - c)
        i = int(np.argmin(d))
        return int(free[i, 0] + r0), int(free[i, 1] + c0)

    def plan(self, start_xy, goal_xy) -> list[tuple[float, float]]:
        """Plan a smoothed global path; [] when there is none. Start or goal
        outside the map raises ValueError; one that lies within the inflation
        of an obstacle is moved to the nearest free cell close by."""
        xy = self._plan(start_xy, goal_xy, self._inflated_u8)
        return [(float(x), float(y)) for x, y in xy]

    def _plan(self, start_xy, goal_xy, blocked: np.ndarray) -> np.ndarray:
        """The smoothed path (N × 2, metres) on ``blocked`` (uint8, 1 =
        blocked), also set as the path to follow; empty when there is none."""
        g = self.grid
        cells = []
        for name, xy in (("start", start_xy), ("goal", goal_xy)):
            rc = g.world_to_cell(*xy)
            if not g.in_bounds(*rc):
                raise ValueError(f"{name} {tuple(xy)} lies outside the map")
            free = self._nearest_free(rc, blocked)
            if free is None:
                log.warning("%s %s is inside an obstacle's inflation", name, tuple(xy))
                self._set_path(np.zeros((0, 2)))
                return np.zeros((0, 2))
            cells.append(free)
        search = jps if self.cfg.global_planner == "jps" else astar
        res = search(blocked, cells[0], cells[1])
        self.last_plan = res
        if not res.found:
            self._set_path(np.zeros((0, 2)))
            return np.zeros((0, 2))
        verts = anyangle.shorten(blocked, res.cells)
        if self.cfg.smooth:
            curve = anyangle.smooth_curve(blocked, verts, step=0.5)
        else:
            curve = anyangle.densify(np.asarray(verts, float), 0.5)
        xy = np.column_stack(
            [
                g.origin_xy[0] + (curve[:, 1] + 0.5) * g.resolution_m,
                g.origin_xy[1] + (curve[:, 0] + 0.5) * g.resolution_m,
            ]
        )
        xy[0] = start_xy
        xy[-1] = goal_xy
        self._set_path(xy)
        return xy

    def _blocked_with(self, q: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """The inflated map with each moving obstacle's swept disc over the
        next obstacle_sweep_s (inflated by the robot's radius and margin)
        blocked, and everything outside the search window (``_window``);
        the robot's own surroundings stay free so it can start."""
        b = self._inflated_u8.copy()
        g = self.grid
        res = g.resolution_m
        ox, oy = g.origin_xy
        infl = self.cfg.robot_radius_m + self.cfg.inflation_margin_m
        # A standing (or slow) person's disc as the governor will grow it, so
        # the new path keeps the distance the governor asks for.
        grow, cap, below, _moving = self._grow
        rates = _growth(obs, grow, below) if len(obs) else np.zeros(0)
        for (x, y, vx, vy, r), rate in zip(obs, rates, strict=True):
            extra = min(rate * self.cfg.safety_horizon_s, cap) + self.cfg.safety_margin_m
            for t in np.arange(0.0, self.cfg.obstacle_sweep_s + 1e-9, 0.5):
                cx, cy = x + vx * t, y + vy * t
                rad = min(r + infl + extra, math.hypot(cx - q[0], cy - q[1]) - 0.05)
                if rad <= 0:
                    continue
                r0, r1 = int((cy - rad - oy) / res), int((cy + rad - oy) / res) + 1
                c0, c1 = int((cx - rad - ox) / res), int((cx + rad - ox) / res) + 1
                r0, c0 = max(r0, 0), max(c0, 0)
                r1, c1 = min(r1, b.shape[0]), min(c1, b.shape[1])
                if r0 >= r1 or c0 >= c1:
                    continue
                yy, xx = np.mgrid[r0:r1, c0:c1]
                d2 = (ox + (xx + 0.5) * res - cx) ** 2 + (oy + (yy + 0.5) * res - cy) ** 2
                b[r0:r1, c0:c1] |= d2 <= rad * rad
        return self._window(b, q, self.path[-1])

    def _window(self, b: np.ndarray, a_xy, b_xy) -> np.ndarray:
        """Block ``b`` (in place) outside the box around two points grown by
        replan_window_m: a search that fails (the goal cut off by moving
        obstacles) then explores the box, not the whole map."""
        g = self.grid
        pad = int(math.ceil(self.cfg.replan_window_m / g.resolution_m))
        (ra, ca), (rb, cb) = g.world_to_cell(*a_xy), g.world_to_cell(*b_xy)
        r0, r1 = max(min(ra, rb) - pad, 0), min(max(ra, rb) + pad + 1, b.shape[0])
        c0, c1 = max(min(ca, cb) - pad, 0), min(max(ca, cb) + pad + 1, b.shape[1])
        b[:r0, :] = 1
        b[r1:, :] = 1
        b[:, :c0] = 1
        b[:, c1:] = 1
        return b

    def _replan(self, q: np.ndarray, obs: np.ndarray | None = None) -> bool:
        """Plan again from q to the current goal, keeping the mode; with obs,
        around the moving obstacles too (falling back to the map alone)."""
        mode = self._mode
        goal = tuple(self.path[-1])
        start = (float(q[0]), float(q[1]))
        try:
            ok = False
            if obs is not None and len(obs):
                ok = len(self._plan(start, goal, self._blocked_with(q, obs))) > 0
            ok = ok or len(self._plan(start, goal, self._inflated_u8)) > 0
        except ValueError:
            ok = False
        if not ok:
            log.debug("replan from %s failed", tuple(q))
            return False
        self._mode = mode
        self.replan_count += 1
        return True

    def set_path(self, path_xy) -> None:
        """Follow a path planned elsewhere."""
        self._set_path(np.asarray(path_xy, dtype=float).reshape(-1, 2))

    def _set_path(self, xy: np.ndarray) -> None:
        self.path = xy
        seg = np.linalg.norm(np.diff(xy, axis=0), axis=1) if len(xy) > 1 else np.zeros(0)
        self._s = np.concatenate([[0.0], np.cumsum(seg)]) if len(xy) else np.zeros(0)
        self._idx = 0
        self._mode = FOLLOWING if len(xy) else NO_PATH
        self._clear_for_s = 0.0
        self._best_goal_dist = math.inf
        self._stall_s = 0.0
        self.apf.reset()

    @property
    def mode(self) -> str:
        return self._mode

    # -- local -------------------------------------------------------------------
    def _point_at(self, s: float) -> np.ndarray:
        s = min(max(s, 0.0), self._s[-1])
        i = int(np.searchsorted(self._s, s))
        if i == 0:
            return self.path[0]
        t = (s - self._s[i - 1]) / max(self._s[i] - self._s[i - 1], 1e-12)
        return self.path[i - 1] + t * (self.path[i] - self.path[i - 1])

    def _project(self, q: np.ndarray) -> float:
        """Arc length of the nearest path point in a window ahead of progress."""
        lo = max(0, self._idx - 4)
        hi = int(np.searchsorted(self._s, self._s[self._idx] + 4.0)) + 1
        hi = min(len(self.path), max(hi, lo + 2))
        d = np.linalg.norm(self.path[lo:hi] - q, axis=1)
        self._idx = max(self._idx, lo + int(np.argmin(d)))
        return float(self._s[self._idx])

    def _track(self, q, th, target, v_cap):
        """Heading controller towards a point: turn in place beyond 60°."""
        k = self.cfg.kin
        err = _wrap(math.atan2(target[1] - q[1], target[0] - q[0]) - th)
        w = float(np.clip(self.cfg.heading_gain * err, -k.omega_max_rps, k.omega_max_rps))
        v = v_cap * max(0.0, math.cos(err)) ** 2 if abs(err) < math.radians(60) else 0.0
        if v == 0.0 and abs(w) < k.omega_min_rps and abs(err) > 0.05:
            w = math.copysign(k.omega_min_rps, err)
        return v, w

    def _limit(self, v, w, vc, wc, dt):
        k = self.cfg.kin
        v = min(max(v, k.v_min_mps, vc - k.accel_mps2 * dt), k.v_max_mps, vc + k.accel_mps2 * dt)
        w = min(
            max(w, -k.omega_max_rps, wc - k.alpha_rps2 * dt),
            k.omega_max_rps,
            wc + k.alpha_rps2 * dt,
        )
        return float(v), float(w)

    def _clearance(self, q, th, v, w, obs):
        ox, oy = self.grid.origin_xy
        return rollout_clearance(
            q[0],
            q[1],
            th,
            v,
            w,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            *self._grow,
        )

    def _govern(self, q, th, v, w, vc, wc, dt, obs, margin=None):
        """Keep (v, ω) if its rollout stays clear by the safety margin (or, with
        no moving obstacle in view and the robot already inside the margin,
        by half of what is left, so it can still move along a wall; and a
        robot the map has touching a wall already, by going no deeper).
        Otherwise take the safe reachable command nearest to (v, ω); when no
        reachable command is safe, the one whose rollout stays clearest."""
        margin = self.cfg.safety_margin_m if margin is None else margin
        d = self._clearance(q, th, v, w, obs)
        now = self._clearance(q, th, 0.0, 0.0, obs[:0])
        # The walls' floor. Half of what is left has no motion above it once
        # nothing is left (the body on or past the map's surface, which a
        # bumped robot or a pose estimate a few centimetres off reaches): the
        # robot then stood for good. There, any motion that goes no deeper.
        wall_ok = min(margin, 0.5 * now) if now > 0.0 else now - WALL_SLACK_M

        def safe(dd):
            return dd > margin or (len(obs) == 0 and dd > min(0.5 * min(now, margin), wall_ok))

        if safe(d) and (len(obs) == 0 or self._can_stop(q, th, vc, wc, v, w, obs) > margin):
            return v, w
        self.governor_count += 1
        # Search the whole velocity space within the kinematic limits: each
        # target (v, ω) is reached at the acceleration limits and then held;
        # the rollout checks every obstacle's predicted motion. Reversing is
        # a candidate whenever v_min < 0 (backing away from a squeeze). Safe:
        # clear of the moving obstacles by the margin, and of the walls by the
        # margin or half of what is left (a robot already close to a wall may
        # still move along it).
        k = self.cfg.kin
        vs = np.unique(np.concatenate([np.linspace(k.v_min_mps, k.v_max_mps, 7), [0.0, v]]))
        ws = np.unique(np.concatenate([np.linspace(-k.omega_max_rps, k.omega_max_rps, 9), [w]]))
        grid_v, grid_w = np.meshgrid(vs, ws, indexing="ij")
        # Turn in place to one of 12 headings, then drive off straight.
        phis = th + np.linspace(-math.pi, math.pi, 12, endpoint=False)[1:]
        errs = (phis - th + math.pi) % (2 * math.pi) - math.pi
        n_grid = grid_v.size
        cands = np.empty((n_grid + len(phis), 3))
        cands[:n_grid, 0] = grid_v.ravel()
        cands[:n_grid, 1] = grid_w.ravel()
        cands[:n_grid, 2] = np.nan
        cands[n_grid:, 0] = k.v_max_mps
        cands[n_grid:, 1] = np.copysign(k.omega_max_rps, errs)
        cands[n_grid:, 2] = phis
        out = self._rollouts(q, th, vc, wc, cands, obs, self._grow, math.inf)
        ds, dm, t_hit = out[:, 0], out[:, 1], out[:, 2]
        commit = self.cfg.commit_s
        if commit > 0.0 and len(obs):
            # The contingency of each candidate: held for commit_s, then
            # braked to rest; standing there must stay clear as well.
            brake = self._rollouts(q, th, vc, wc, cands, obs, self._grow, commit)
            can_stop = (brake[:, 1] > margin) & (brake[:, 0] > wall_ok)
        else:
            can_stop = np.ones(len(cands), bool)
        # Each candidate's first step, as in its rollout: a turn-then-go
        # stands and turns while more than 0.2 rad off its heading.
        tv, tw = cands[:, 0].copy(), cands[:, 1].copy()
        turn = np.zeros(len(cands), bool)
        turn[n_grid:] = True
        err_all = np.concatenate([np.zeros(n_grid), errs])
        far = turn & (np.abs(err_all) > 0.2)
        tv[far] = 0.0
        near = turn & ~far
        tw[near] = np.clip(2.0 * err_all[near], -k.omega_max_rps, k.omega_max_rps)
        lv = np.clip(
            tv, max(k.v_min_mps, vc - k.accel_mps2 * dt), min(k.v_max_mps, vc + k.accel_mps2 * dt)
        )
        lw = np.clip(
            tw,
            max(-k.omega_max_rps, wc - k.alpha_rps2 * dt),
            min(k.omega_max_rps, wc + k.alpha_rps2 * dt),
        )
        cost = np.where(
            turn,
            np.abs(lv - v) / k.v_max_mps + np.abs(lw - w) / k.omega_max_rps + 0.5,
            np.abs(cands[:, 0] - v) / k.v_max_mps + np.abs(cands[:, 1] - w) / k.omega_max_rps,
        )
        ok = (dm > margin) & (ds > wall_ok) & can_stop
        if not ok.any():  # nothing safe both ways: a motion it can at least stop from
            ok = can_stop & (ds > wall_ok)
        self.escape_found = bool(ok.any())
        if self.escape_found:
            i = int(np.flatnonzero(ok)[np.argmin(cost[ok])])
            return float(lv[i]), float(lw[i])
        self.cornered_count += 1
        # No motion the robot could stop clear from. An escape that never
        # meets an obstacle as predicted (a standing one's growing disc is a
        # precaution, left out here; a walker's uncertainty is kept) is
        # taken, the clearest one: a robot beside a standing person moves
        # away instead of freezing.
        if (self._grow[0] > 0.0 or self._grow[3] > 0.0) and len(obs):
            g = self._grow
            nominal = self._rollouts(q, th, vc, wc, cands, obs, (0.0, g[1], 0.0, g[3]), math.inf)
            t_hit = nominal[:, 2]
        clear = np.minimum(dm, ds - wall_ok)
        free = ~np.isfinite(t_hit) & (ds > wall_ok)
        if free.any():
            i = int(np.flatnonzero(free)[np.argmax(clear[free])])
            return float(lv[i]), float(lw[i])
        # Contact is coming whatever the robot does (passive safety): be at
        # rest, or as slow as possible, when it comes. Of the braking
        # contingencies, the one slowest at its contact, then the one whose
        # contact comes latest, then the clearest; without contingencies,
        # brake at the limit.
        self.estop_count += 1
        if not (commit > 0.0 and len(obs)):
            return self._limit(0.0, 0.0, vc, wc, dt)
        tb = np.minimum(brake[:, 2], self.cfg.safety_horizon_s)
        a = k.accel_mps2
        v_commit = vc + np.clip(tv - vc, -a * commit, a * commit)
        v_hit = np.where(
            tb <= commit,
            np.abs(vc + np.clip(tv - vc, -a * tb, a * tb)),
            np.maximum(np.abs(v_commit) - a * (tb - commit), 0.0),
        )
        cb = np.minimum(brake[:, 1], brake[:, 0] - wall_ok)
        i = int(np.lexsort((-np.arange(len(cands)), cb, tb, -np.round(v_hit, 2)))[-1])
        return float(lv[i]), float(lw[i])

    def _rollouts(self, q, th, vc, wc, cands, obs, grow, stop_after) -> np.ndarray:
        """rollout_many for the candidates from the robot's state, with the
        disc growth ``grow`` (as self._grow) and the contingency stop time."""
        k = self.cfg.kin
        ox, oy = self.grid.origin_xy
        return rollout_many(
            q[0],
            q[1],
            th,
            vc,
            wc,
            cands,
            k.accel_mps2,
            k.alpha_rps2,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            *grow,
            stop_after,
        )

    def _can_stop(self, q, th, vc, wc, v, w, obs) -> float:
        """Clearance to the moving obstacles of the contingency for (v, ω):
        held for commit_s, then braked to rest and standing (+inf if off)."""
        if self.cfg.commit_s <= 0.0:
            return math.inf
        k = self.cfg.kin
        ox, oy = self.grid.origin_xy
        _, dm, _ = rollout_ramp(
            q[0],
            q[1],
            th,
            vc,
            wc,
            v,
            w,
            k.accel_mps2,
            k.alpha_rps2,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            np.nan,
            *self._grow,
            self.cfg.commit_s,
        )
        return dm

    def govern(self, pose_xytheta, velocity, v, w, obstacles=(), dt: float = 0.1):
        """A command made elsewhere (a recovery manoeuvre), within the
        kinematic limits and through the safety governor: (v_mps, omega_rps)."""
        q = np.array([float(pose_xytheta[0]), float(pose_xytheta[1])])
        th = float(pose_xytheta[2])
        vc, wc = (float(velocity), 0.0) if np.ndim(velocity) == 0 else map(float, velocity)
        obs = np.asarray(list(obstacles), dtype=np.float64).reshape(-1, 5)
        v, w = self._limit(v, w, vc, wc, dt)
        return self._govern(q, th, v, w, vc, wc, dt, obs)

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
