"""The hybrid planner's global path: planning (A* or JPS on the inflated map,
shortened and smoothed), replanning around moving obstacles within a window, and
the path's arc length (projection of the robot onto it, the point at a given
arc length). Mixed into :class:`~app.core.planner.hybrid.HybridPlanner`."""

from __future__ import annotations

import logging
import math

import numpy as np

from .. import anyangle
from ..astar import astar
from ..jps import jps
from .config import FOLLOWING, NO_PATH
from .rollout import _growth

log = logging.getLogger("app.core.planner.hybrid")  # the hybrid planner's one logger


class GlobalRoute:
    """Plan, replan and measure the global path (world metres)."""

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

