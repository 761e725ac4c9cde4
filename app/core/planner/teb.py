"""Timed elastic band (TEB) local planner: the optimised TEB of seed 004 §2.3
(Fig. 8, steps ①–⑦) for the 4WS base, and a plain TEB beside it.

The band b = (s0, ΔT0, s1, ΔT1, …, s_{n−1}) holds n poses si = (xi, yi, θi) and
n − 1 time intervals (step ③; the control inputs are implied by neighbouring
poses, so they are not separate unknowns here). Each control cycle:

① initialise: poses taken along the global path (optimised) — or on the
  straight line to the local goal (plain TEB, as in Rösmann et al. 2012) —
  spaced by the time resolution ΔT_ref at the top speed;
② in-place turn (optimised only): if the heading differs from the band's
  initial direction by more than ``turn_in_place_deg`` (30°), the base turns
  on the spot (4WS PIVOT mode) instead of driving, so it never backs out;
③ the band starts at the current pose and ends at the local goal pose;
④ re-size with hysteresis: an interval longer than ΔT_ref + ΔT_hyst gets a
  pose inserted in its middle (two intervals of half the length); one shorter
  than ΔT_ref − ΔT_hyst loses the pose after it (the intervals merge) — the
  dead band ±ΔT_hyst stops the size from oscillating;
⑤–⑥ optimise: the objective is a sum of squared penalties — total time,
  the kinematic model (poses on circular arcs tangent to both headings, as the
  counter-phase 4WS base drives, with the radius no tighter than its minimum
  turning radius), velocity and acceleration limits, never reversing
  (optimised; the plain TEB allows reverse up to ``max_reverse_mps``),
  clearance from obstacles and, optimised, distance from the global path —
  and the first interval gives the command;
⑦ laser-odometry correction: ``pose_correction`` (a callable pose → pose)
  corrects the measured pose before it becomes s0, so the band and the
  kinematic constraint start from the corrected state. The scan matching that
  supplies it lives with the localisation work; the default is the identity.

Solver: Levenberg–Marquardt on the banded normal equations (teb_solver.py).
Each penalty touches at most two neighbouring poses and intervals, so with
the unknowns interleaved (ΔT0, s1, ΔT1, s2, …) JᵀJ is a band matrix of
half-bandwidth ≤ 10, factored by a banded Cholesky; the Jacobian is written
out analytically (teb_jacobian.py), or, for comparison
(``TebConfig.jacobian = "fd"``), comes from forward differences on column
groups that share no row (about ten batched function calls per Jacobian
whatever the band size). SciPy's
``least_squares`` (trust-region reflective with LSMR, dense, or MINPACK's LM)
stays selectable through ``TebConfig.solver`` for comparison. Chosen over g2o
(the seed's library: not on PyPI) and CasADi (a large extra dependency)
because the problem has ~150 unknowns.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.optimize import least_squares
from scipy.sparse import csr_matrix, lil_matrix

from ..kinematics import FwsGeometry, Mode, Twist, limit_twist, min_turn_radius
from .teb_jacobian import JacobianLayout, bilinear_grad, jacobian_values
from .teb_solver import BandedPattern, levenberg_marquardt

log = logging.getLogger(__name__)

__all__ = ["ObstacleField", "Teb", "TebConfig", "TebStep"]


@dataclass(frozen=True)
class TebConfig:
    optimised: bool = True
    dt_ref_s: float = 0.3
    dt_hyst_s: float = 0.1
    min_poses: int = 5
    max_poses: int = 50
    max_speed_mps: float = 0.8
    max_reverse_mps: float = 0.3  # plain TEB only
    max_yaw_rate: float = 1.2
    max_accel_mps2: float = 0.8
    clearance_m: float = 0.5  # robot radius + margin
    turn_in_place_deg: float = 30.0
    turn_done_deg: float = 8.0
    w_time: float = 1.0
    w_kin: float = 30.0
    w_radius: float = 10.0
    w_limits: float = 20.0
    w_reverse: float = 200.0
    w_obstacle: float = 60.0
    w_path: float = 3.0
    max_nfev: int = 12
    # "analytic": the Jacobian written out (teb_jacobian.py); "fd": forward
    # differences on column groups, kept for comparison.
    jacobian: str = "analytic"
    # "banded": Levenberg–Marquardt on the banded normal equations
    # (teb_solver.py); "lsmr" (sparse), "exact" (dense) or "lm": SciPy's
    # least_squares, kept for comparison.
    solver: str = "banded"
    lsmr_maxiter: int = 30
    geometry: FwsGeometry = field(default_factory=FwsGeometry)


class ObstacleField:
    """Distance to the nearest obstacle (metres) from an occupancy grid:
    Euclidean distance transform of the free cells (centre to the nearest
    blocked centre) less half a cell, so it does not overstate the distance to
    the blocked cell's edge, interpolated bilinearly."""

    def __init__(self, blocked: np.ndarray, resolution_m: float, origin_xy=(0.0, 0.0)):
        b = np.asarray(blocked, dtype=bool)
        if b.ndim != 2:
            raise ValueError("blocked must be a 2-D grid")
        self.res = float(resolution_m)
        self.origin = np.asarray(origin_xy, dtype=float)
        self.dist = np.maximum(ndimage.distance_transform_edt(~b) - 0.5, 0.0) * self.res
        self.blocked = b

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """xy: (..., 2) points (x = column direction, y = row direction)."""
        p = (np.asarray(xy, dtype=float) - self.origin) / self.res - 0.5
        coords = np.stack([p[..., 1].ravel(), p[..., 0].ravel()])
        d = ndimage.map_coordinates(self.dist, coords, order=1, mode="constant", cval=0.0)
        return d.reshape(np.shape(xy)[:-1])

    def distance_and_grad(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`distance` and its gradient (…, 2): the bilinear
        interpolation's own derivative (teb_jacobian.bilinear_grad)."""
        xy = np.asarray(xy, dtype=float)
        pts = np.ascontiguousarray(xy.reshape(-1, 2))
        d, g = np.empty(len(pts)), np.empty((len(pts), 2))
        bilinear_grad(self.dist, float(self.origin[0]), float(self.origin[1]), self.res, pts, d, g)
        return d.reshape(xy.shape[:-1]), g.reshape(xy.shape)


@dataclass
class TebStep:
    """One control cycle: the command, the band after optimising, and
    whether the base is turning in place."""

    twist: Twist
    poses: np.ndarray  # n × 3
    dts: np.ndarray  # n − 1
    turning_in_place: bool
    cost: float


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def _seg_dist(p: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance of each point in p (k × 2) to the polyline path (m × 2)."""
    if len(path) < 2:
        return np.linalg.norm(p - path[:1], axis=1)
    a, b = path[:-1], path[1:]
    ab = b - a
    L2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    t = np.clip(np.einsum("kmj,mj->km", p[:, None, :] - a[None], ab) / L2, 0.0, 1.0)
    proj = a[None] + t[..., None] * ab[None]
    return np.min(np.linalg.norm(p[:, None, :] - proj, axis=2), axis=1)


class Teb:
    """The TEB planner for one robot. ``plan_step(pose, goal_pose, path,
    field, v_now)`` runs steps ①–⑦ once and returns a :class:`TebStep`."""

    def __init__(self, config: TebConfig | None = None,
                 pose_correction: Callable[[np.ndarray], np.ndarray] | None = None):
        self.cfg = config or TebConfig()
        self.pose_correction = pose_correction
        self.r_min = min_turn_radius(self.cfg.geometry, Mode.COUNTER)
        self.poses: np.ndarray | None = None
        self.dts: np.ndarray | None = None
        self._goal: np.ndarray | None = None
        self._sparsity_cache: dict = {}
        self._pattern_cache: dict = {}
        self._layout_cache: dict = {}
        self._pivoting = False

    # ---- ① initialisation ------------------------------------------------------------

    def _init_band(self, start: np.ndarray, goal: np.ndarray, path: np.ndarray | None) -> None:
        c = self.cfg
        step = c.dt_ref_s * c.max_speed_mps
        if c.optimised and path is not None and len(path) >= 2:
            pts = np.vstack([start[:2], _from_nearest(path, start[:2]), goal[:2]])
        else:
            pts = np.vstack([start[:2], goal[:2]])
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        n = int(np.clip(np.ceil(s[-1] / step) + 1, c.min_poses, c.max_poses))
        u = np.linspace(0.0, s[-1], n)
        xy = np.column_stack([np.interp(u, s, pts[:, 0]), np.interp(u, s, pts[:, 1])])
        d = np.diff(xy, axis=0)
        th = np.arctan2(d[:, 1], d[:, 0])
        if not c.optimised:
            # Plain TEB: headings interpolated from start to goal (it may reverse).
            th = start[2] + _wrap(goal[2] - start[2]) * np.linspace(0, 1, n)[:-1]
        poses = np.column_stack([xy, np.r_[th, goal[2]]])
        poses[0] = start
        poses[-1] = goal
        self.poses = poses
        self.dts = np.full(n - 1, max(s[-1] / max(n - 1, 1) / c.max_speed_mps, 0.05))
        self._goal = goal.copy()

    # ---- ④ re-sizing with hysteresis ----------------------------------------------------

    def _resize(self) -> None:
        c = self.cfg
        poses, dts = list(self.poses), list(self.dts)
        i = 0
        while i < len(dts):
            if dts[i] > c.dt_ref_s + c.dt_hyst_s and len(poses) < c.max_poses:
                a, b = poses[i], poses[i + 1]
                mid = np.array([(a[0] + b[0]) / 2, (a[1] + b[1]) / 2,
                                a[2] + _wrap(b[2] - a[2]) / 2])
                poses.insert(i + 1, mid)
                dts[i:i + 1] = [dts[i] / 2, dts[i] / 2]
                i += 2
            elif (dts[i] < c.dt_ref_s - c.dt_hyst_s and len(poses) > c.min_poses
                  and i + 1 < len(dts)):
                del poses[i + 1]
                dts[i:i + 2] = [dts[i] + dts[i + 1]]
                i += 1  # the merged interval is looked at again next cycle
            else:
                i += 1
        self.poses = np.array(poses)
        self.dts = np.array(dts)

    # ---- ⑤–⑥ the objective ---------------------------------------------------------------

    def _residuals(self, z, n, start, goal, field, path, v0):
        """The penalty vector for the unknowns z (or a batch: B × len(z))."""
        c = self.cfg
        z = np.atleast_2d(z)
        B = z.shape[0]
        inner = z[:, : 3 * (n - 2)].reshape(B, n - 2, 3)
        dts = np.maximum(z[:, 3 * (n - 2):], 1e-3)
        P = np.concatenate([np.broadcast_to(start, (B, 1, 3)), inner,
                            np.broadcast_to(goal, (B, 1, 3))], axis=1)
        d = np.diff(P[..., :2], axis=1)
        dist = np.linalg.norm(d, axis=2)
        th = P[..., 2]
        dth = _wrap(np.diff(th, axis=1))
        c0, s0 = np.cos(th), np.sin(th)
        # Arc model: the chord makes equal angles with both headings.
        kin = (c0[:, :-1] + c0[:, 1:]) * d[..., 1] - (s0[:, :-1] + s0[:, 1:]) * d[..., 0]
        # Signed speed along the heading (negative = reversing).
        v = (c0[:, :-1] * d[..., 0] + s0[:, :-1] * d[..., 1]) / dts
        om = dth / dts
        radius = np.maximum(0.0, self.r_min * np.abs(dth) - dist)
        vmax = np.maximum(0.0, v - c.max_speed_mps)
        if c.optimised:
            back = c.w_reverse * np.maximum(0.0, -v)
        else:
            back = c.w_limits * np.maximum(0.0, -v - c.max_reverse_mps)
        wmax = np.maximum(0.0, np.abs(om) - c.max_yaw_rate)
        vv = np.concatenate([np.full((B, 1), v0), v], axis=1)
        tacc = np.concatenate([dts[:, :1], 0.5 * (dts[:, :-1] + dts[:, 1:])], axis=1)
        amax = np.maximum(0.0, np.abs(np.diff(vv, axis=1) / tacc) - c.max_accel_mps2)
        obs = np.maximum(0.0, c.clearance_m - field.distance(inner[..., :2]))
        mids = 0.5 * (P[:, :-1, :2] + P[:, 1:, :2])
        obs_mid = np.maximum(0.0, c.clearance_m - field.distance(mids))
        parts = [
            c.w_time * dts,
            c.w_kin * kin,
            c.w_radius * radius,
            c.w_limits * vmax,
            back,
            c.w_limits * wmax,
            c.w_limits * amax,
            c.w_obstacle * obs,
            c.w_obstacle * obs_mid,
        ]
        if c.optimised and path is not None:
            pd = _seg_dist(inner[..., :2].reshape(-1, 2), path).reshape(B, n - 2)
            parts.append(c.w_path * pd)
        out = np.concatenate(parts, axis=1)
        return out[0] if B == 1 else out

    def _jacobian(self, z, n, start, goal, field, path, v0):
        """Sparse Jacobian for least_squares: analytic (``TebConfig.jacobian``)
        or by forward differences on column groups that share no row (greedy
        colouring of the sparsity pattern), every group's perturbed copy
        evaluated in one batched call of the residuals."""
        rows, cols, grp, n_groups, shape = self._sparsity(n, path is not None)
        if self.cfg.jacobian == "analytic":
            vals = self._analytic_values(z, n, start, goal, field, path, v0)
            J = csr_matrix((vals, (rows, cols)), shape=shape)
            return J if self.cfg.solver == "lsmr" else J.toarray()
        h = 1e-6
        Z = np.repeat(z[None], n_groups + 1, axis=0)
        Z[grp + 1, np.arange(z.size)] += h
        F = self._residuals(Z, n, start, goal, field, path, v0)
        D = (F[1:] - F[0]) / h
        J = csr_matrix((D[grp[cols], rows], (rows, cols)), shape=shape)
        return J if self.cfg.solver == "lsmr" else J.toarray()

    def _analytic_values(self, z, n, start, goal, field, path, v0):
        """The analytic Jacobian (teb_jacobian.py) in the pattern's COO order."""
        key = (n, path is not None)
        if key not in self._layout_cache:
            rows, cols, _grp, _ng, _shape = self._sparsity(*key)
            self._layout_cache[key] = JacobianLayout(n, key[1], rows, cols)
        return jacobian_values(self.cfg, self.r_min, self._layout_cache[key],
                               z, n, start, goal, field, path, v0)

    def _jacobian_values(self, z, r, n, start, goal, field, path, v0):
        """The Jacobian's values on the sparsity pattern (COO order): analytic
        (``TebConfig.jacobian``) or the same forward differences as
        :meth:`_jacobian`, reusing r = residuals(z)."""
        if self.cfg.jacobian == "analytic":
            return self._analytic_values(z, n, start, goal, field, path, v0)
        rows, cols, grp, n_groups, _shape = self._sparsity(n, path is not None)
        h = 1e-6
        Z = np.repeat(z[None], n_groups, axis=0)
        Z[grp, np.arange(z.size)] += h
        F = np.atleast_2d(self._residuals(Z, n, start, goal, field, path, v0))
        return (F[grp[cols], rows] - r[rows]) / h

    def _pattern(self, n: int, with_path: bool) -> BandedPattern:
        """The pattern with the unknowns interleaved as ΔT0, s1, ΔT1, s2, …,
        ΔT_{n−2}: every penalty then touches a window of at most 11 of them."""
        key = (n, with_path)
        if key not in self._pattern_cache:
            rows, cols, _grp, _ng, shape = self._sparsity(n, with_path)
            pose_pos = 4 * np.repeat(np.arange(n - 2), 3) + 1 + np.tile(np.arange(3), n - 2)
            order = np.concatenate([pose_pos, 4 * np.arange(n - 1)])
            self._pattern_cache[key] = BandedPattern(rows, cols, shape[0], shape[1], order)
        return self._pattern_cache[key]

    def _sparsity(self, n: int, with_path: bool):
        key = (n, with_path)
        if key not in self._sparsity_cache:
            S = self._build_sparsity(n, with_path).tocsc()
            coo = S.tocoo()
            # Greedy colouring: a column joins the first group none of whose
            # columns shares a row with it.
            grp = np.empty(S.shape[1], dtype=np.int64)
            used: list[set] = []
            for j in range(S.shape[1]):
                r = set(S.indices[S.indptr[j]:S.indptr[j + 1]].tolist())
                for k, u in enumerate(used):
                    if not (u & r):
                        u |= r
                        grp[j] = k
                        break
                else:
                    used.append(set(r))
                    grp[j] = len(used) - 1
            self._sparsity_cache[key] = (coo.row, coo.col, grp, len(used), S.shape)
        return self._sparsity_cache[key]

    def _build_sparsity(self, n: int, with_path: bool):
        m_seg = n - 1
        nv = 3 * (n - 2) + m_seg
        rows = 8 * m_seg + (n - 2) + (n - 2 if with_path else 0)
        S = lil_matrix((rows, nv), dtype=np.int8)

        def pose_cols(i):  # pose index 0..n-1 -> its variable columns
            return [] if i in (0, n - 1) else [3 * (i - 1), 3 * (i - 1) + 1, 3 * (i - 1) + 2]

        r = 0
        for i in range(m_seg):  # time
            S[r + i, 3 * (n - 2) + i] = 1
        r += m_seg
        for _block in range(5):  # kin, radius, vmax, back, wmax: segment i
            for i in range(m_seg):
                for col in pose_cols(i) + pose_cols(i + 1) + [3 * (n - 2) + i]:
                    S[r + i, col] = 1
            r += m_seg
        for i in range(m_seg):  # acceleration: segments i−1 and i
            cols = pose_cols(i) + pose_cols(i + 1) + [3 * (n - 2) + i]
            if i > 0:
                cols += pose_cols(i - 1) + [3 * (n - 2) + i - 1]
            for col in cols:
                S[r + i, col] = 1
        r += m_seg
        for i in range(n - 2):  # obstacle at the inner poses
            S[r + i, 3 * i:3 * i + 2] = 1
        r += n - 2
        for i in range(m_seg):  # obstacle at the segment midpoints
            for col in pose_cols(i)[:2] + pose_cols(i + 1)[:2]:
                S[r + i, col] = 1
        r += m_seg
        if with_path:
            for i in range(n - 2):
                S[r + i, 3 * i:3 * i + 2] = 1
        return S.tocsr()

    # ---- one control cycle --------------------------------------------------------------

    def plan_step(self, pose, goal_pose, path, field: ObstacleField, v_now: float = 0.0,
                  path_is_new: bool = False) -> TebStep:
        c = self.cfg
        pose = np.asarray(pose, dtype=float)
        if self.pose_correction is not None:  # ⑦ laser-odometry correction
            pose = np.asarray(self.pose_correction(pose), dtype=float)
        goal = np.asarray(goal_pose, dtype=float)
        path = None if path is None else np.asarray(path, dtype=float)
        if (self.poses is None or path_is_new or self._goal is None
                or np.linalg.norm(goal[:2] - self._goal[:2]) > 0.3):
            self._init_band(pose, goal, path)  # ① and ③
        else:
            self._advance(pose, goal)
        # ② in-place turn (optimised): compare the heading with the band's direction.
        if c.optimised:
            look = self._band_direction(pose)
            err = _wrap(look - pose[2]) if look is not None else 0.0
            # Start turning past the threshold and keep turning until aligned
            # within ``turn_done_deg``, so the base does not hop between
            # turning and driving at the threshold.
            limit = c.turn_done_deg if self._pivoting else c.turn_in_place_deg
            self._pivoting = abs(err) > math.radians(limit)
            if self._pivoting:
                om = math.copysign(min(c.max_yaw_rate, abs(err) / 0.3), err)
                self._init_band(pose, goal, path)
                return TebStep(Twist(0.0, 0.0, om), self.poses, self.dts, True, 0.0)
        self._resize()  # ④
        n = len(self.poses)
        if n < 3:
            self._init_band(pose, goal, path)
            n = len(self.poses)
        z0 = np.concatenate([self.poses[1:-1].ravel(), self.dts])
        with_path = c.optimised and path is not None
        args = (n, pose, goal, field, path if with_path else None, v_now)
        if with_path:
            args = (*args[:4], _thin(path, 0.4), v_now)
        sol = self._solve(z0, args)
        inner = sol.x[: 3 * (n - 2)].reshape(n - 2, 3)
        self.poses = np.vstack([pose, inner, goal])
        self.poses[:, 2] = _wrap(self.poses[:, 2])
        self.dts = np.maximum(sol.x[3 * (n - 2):], 1e-3)
        return TebStep(self._command(), self.poses, self.dts, False, float(2 * sol.cost))

    def _solve(self, z0, args):
        """⑤–⑥: minimise the penalties from z0 with the configured solver."""
        c = self.cfg
        if c.solver == "banded":
            return levenberg_marquardt(
                lambda z: self._residuals(z, *args),
                lambda z, r: self._jacobian_values(z, r, *args),
                z0, self._pattern(args[0], args[4] is not None), max_nfev=c.max_nfev)
        if c.solver == "lm":
            kw = {"method": "lm"}
        else:
            kw = {"method": "trf", "tr_solver": c.solver}
            if c.solver == "lsmr":
                kw["tr_options"] = {"maxiter": c.lsmr_maxiter}
        return least_squares(self._residuals, z0, jac=self._jacobian, args=args,
                             max_nfev=c.max_nfev, **kw)

    def _band_direction(self, pose) -> float | None:
        """Direction from the robot to the band point ~0.5 m ahead."""
        d = np.linalg.norm(self.poses[:, :2] - pose[:2], axis=1)
        far = np.nonzero(d > 0.5)[0]
        if len(far) == 0:
            return None if d[-1] < 0.05 else float(self._goal[2])
        p = self.poses[far[0], :2]
        return math.atan2(p[1] - pose[1], p[0] - pose[0])

    def _advance(self, pose, goal) -> None:
        """Drop the poses the robot has passed, then pin s0 and the goal."""
        d = np.linalg.norm(self.poses[:, :2] - pose[:2], axis=1)
        k = int(np.argmin(d[:-1])) if len(d) > 2 else 0
        if k > 0:
            self.poses = self.poses[k:]
            self.dts = self.dts[k:]
        self.poses[0] = pose
        self.poses[-1] = goal
        self._goal = goal.copy()

    def _command(self) -> Twist:
        """The twist of the band's first interval (⑥), within the 4WS limits."""
        c = self.cfg
        p0, p1 = self.poses[0], self.poses[1]
        d = p1[:2] - p0[:2]
        dt = float(self.dts[0])
        v = (math.cos(p0[2]) * d[0] + math.sin(p0[2]) * d[1]) / dt
        om = _wrap(p1[2] - p0[2]) / dt
        if c.optimised:
            v = max(0.0, v)
        v = float(np.clip(v, -c.max_reverse_mps, c.max_speed_mps))
        om = float(np.clip(om, -c.max_yaw_rate, c.max_yaw_rate))
        return limit_twist(c.geometry, Twist(v, 0.0, om))


def _from_nearest(path: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """The path's points after the one nearest to xy."""
    k = int(np.argmin(np.linalg.norm(path - xy, axis=1)))
    return path[k + 1:]


def _thin(path: np.ndarray, step_m: float) -> np.ndarray:
    """The path with points about ``step_m`` apart (ends kept)."""
    if len(path) < 3:
        return path
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    k = np.unique(np.searchsorted(s, np.arange(0.0, s[-1], step_m)))
    return np.vstack([path[k], path[-1:]])
