"""Localisation in a known map: scan-to-map matching fused with odometry.

The map is an occupancy grid (map_io.OccupancyGrid, e.g. one saved by the
laser mapper). Its wall surface — occupied cells next to a free cell — makes
the ICP reference (icp.Reference: points, line normals, k-d tree) and a
likelihood field for the correlative search.

Per lidar scan:

1. predict: the pose moves by the odometry increment u (from the EKF of
   ekf.py or plain dead reckoning), P ← J P Jᵀ + Q(u), Q as in the mapper's
   dead-reckoning noise (seed 002 eqs. 1–5);
2. match: point-to-line ICP of the pre-processed scan against the map from
   the prediction; if it fails, a correlative search within ±3σ of the
   prediction (at most ``search_max_m``) seeds ICP again;
3. update: an accepted match z (covariance R) is fused by the Kalman update
   x = x̂ + K (z − x̂), K = P (P + R)⁻¹ (seed 002 eqs. 12–14 with the map as the
   landmark);
4. quality: the match's inlier fraction, RMS residual and the covariance; a
   scan whose points do not fit the map counts as a failure (a scan with
   nothing in range does not: dead reckoning goes on and the covariance
   grows);
5. gate: a fit is fused only if it agrees with the prediction — the squared
   Mahalanobis distance of the correction, dᵀ (P + R + G)⁻¹ d, below
   ``gate_chi2`` (χ²₃ at 99.9 %; G a floor for the map's own error) — and if
   its inliers are a large enough share of the whole scan (people close by
   hide most of it, and a fit of the rest can slide). A rejected fit is not a
   failure: the pose coasts on the odometry for that scan. R is made honest
   first: the ICP covariance is floored (``match_floor_*``) and inflated along
   the direction the Hessian pins weakly (its smallest eigenvalue), as scans
   of one straight road are not independent measurements.

Lost: after ``lost_after`` scans in a row without an accepted fit (failures
   and rejections together), or ``lost_travel_m`` of travel without one, or
   when the position σ exceeds ``lost_sigma_m``, the
   localiser is *lost*: it stops changing its pose and says so until an
   operator (or the dock) sets the pose again. It never reports a guess as a
   fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .icp import IcpConfig, LikelihoodField, Reference, correlative_search, icp
from .map_io import OccupancyGrid
from .se2 import compose, transform_points, wrap


@dataclass(frozen=True)
class LocaliserConfig:
    max_points: int = 180  # scan points used per match (evenly thinned)
    min_inlier_fraction: float = 0.35  # the gate below guards a loose fit
    max_rmse_m: float = 0.08
    lost_after: int = 100  # scans in a row without an accepted match (10 s at 10 Hz)
    lost_travel_m: float = 10.0  # travel without an accepted match (odometry drifts ~5 %)
    gate_chi2: float = 16.27  # χ²(3 dof) at 99.9 %
    gate_floor_xy_m: float = 0.05
    gate_floor_theta_rad: float = math.radians(1.0)
    min_scan_share: float = 0.25  # inliers / all points of the scan (people hide walls)
    match_floor_xy_m: float = 0.02
    match_floor_theta_rad: float = math.radians(0.3)
    weak_ratio: float = 10.0  # Hessian eigenvalue ratio above which a direction is weak
    lost_sigma_m: float = 0.5
    search_max_m: float = 1.0
    search_theta_rad: float = math.radians(10)
    icp_cov_scale: float = 4.0
    odom_trans_frac: float = 0.05
    odom_trans_min_m: float = 0.005
    odom_rot_frac: float = 0.05
    odom_rot_per_m: float = 0.02
    odom_rot_min_rad: float = math.radians(0.2)
    icp: IcpConfig = field(default_factory=lambda: IcpConfig(max_corr_dist_m=0.5,
                                                             min_corr_dist_m=0.15))


@dataclass(frozen=True)
class Quality:
    """What the desk is told with each estimate."""

    matched: bool
    inlier_fraction: float
    rmse_m: float
    sigma_xy_m: float  # largest position standard deviation
    sigma_theta_rad: float
    failures_in_row: int
    lost: bool
    rejections_in_row: int = 0  # good fits rejected by the gate (coasting)


def wall_points(grid: OccupancyGrid) -> np.ndarray:
    """The surface a lidar sees, in world metres: for each occupied cell that
    touches a non-occupied 4-neighbour, its centre moved half a cell towards
    those neighbours (a beam stops at the cell's face, not its centre)."""
    occ = grid.occupied
    pad = np.pad(occ, 1, constant_values=False)
    opens = [(~pad[2:, 1:-1], (0, 1)), (~pad[:-2, 1:-1], (0, -1)),
             (~pad[1:-1, 2:], (1, 0)), (~pad[1:-1, :-2], (-1, 0))]  # (mask, (dx, dy))
    shift = np.zeros(occ.shape + (2,))
    count = np.zeros(occ.shape)
    for mask, (dx, dy) in opens:
        m = mask & occ
        shift[m] += (dx, dy)
        count[m] += 1
    rows, cols = np.nonzero(count > 0)
    s = shift[rows, cols]
    norm = np.maximum(np.hypot(s[:, 0], s[:, 1]), 1e-9)[:, None]
    s = np.where(norm > 1e-6, s / norm, 0.0) * 0.5 * grid.resolution_m
    ox, oy = grid.origin_xy
    centres = np.column_stack((ox + (cols + 0.5) * grid.resolution_m,
                               oy + (rows + 0.5) * grid.resolution_m))
    return centres + s


class MapLocaliser:
    def __init__(self, grid: OccupancyGrid, cfg: LocaliserConfig | None = None) -> None:
        self.cfg = cfg or LocaliserConfig()
        pts = wall_points(grid)
        if len(pts) < self.cfg.icp.min_points:
            raise ValueError("the map has too few occupied cells to localise in")
        self.reference = Reference(pts, self.cfg.icp.normal_neighbours)
        self.field = LikelihoodField(pts, res_m=max(grid.resolution_m, 0.05), margin_m=1.0)
        self._x = np.zeros(3)
        self._p = np.eye(3)
        self._initialised = False
        self.failures_in_row = 0
        self.rejections_in_row = 0
        self.rejections = 0  # all gate rejections
        self._since_fix = 0  # scans since the last accepted fit
        self._travel = 0.0  # metres since the last accepted fit
        self.lost = True  # until a pose is given
        self.last_quality: Quality | None = None

    @property
    def pose(self) -> np.ndarray:
        return self._x.copy()

    @property
    def covariance(self) -> np.ndarray:
        return self._p.copy()

    def set_pose(self, pose, sigma_xy_m: float = 0.1, sigma_theta_rad: float = 0.05) -> None:
        """An initial pose: the dock's, or the operator's 'set pose'."""
        self._x = np.array(pose, float)
        self._p = np.diag([sigma_xy_m ** 2, sigma_xy_m ** 2, sigma_theta_rad ** 2])
        self._initialised = True
        self.failures_in_row = 0
        self.rejections_in_row = 0
        self._since_fix = 0
        self._travel = 0.0
        self.lost = False

    def predict(self, u) -> None:
        """Move by an odometry increment u = (Δx, Δy, Δθ) in the robot frame."""
        if self.lost:
            return
        c = self.cfg
        u = np.asarray(u, float)
        th = self._x[2]
        cs, sn = math.cos(th), math.sin(th)
        j = np.array([[1, 0, -sn * u[0] - cs * u[1]], [0, 1, cs * u[0] - sn * u[1]], [0, 0, 1]])
        rot = np.array([[cs, -sn, 0], [sn, cs, 0], [0, 0, 1]])
        d = math.hypot(u[0], u[1])
        self._travel += d
        s_xy = c.odom_trans_frac * d + c.odom_trans_min_m
        s_th = c.odom_rot_frac * abs(u[2]) + c.odom_rot_per_m * d + c.odom_rot_min_rad
        q = rot @ np.diag([s_xy ** 2, s_xy ** 2, s_th ** 2]) @ rot.T
        self._x = compose(self._x, u)
        self._p = j @ self._p @ j.T + q

    def update(self, points: np.ndarray, sensor_pose=(0.0, 0.0, 0.0),
               scan_points: int | None = None) -> Quality:
        """Match a pre-processed scan (points in the sensor frame; the sensor at
        ``sensor_pose`` in the robot frame) and fuse it. ``scan_points``: how
        many points the whole scan had before some were left out (on tracked
        obstacles); the inlier share is taken of that."""
        c = self.cfg
        if self.lost:
            return self._quality(False, 0.0, math.inf)
        pts = transform_points(sensor_pose, np.asarray(points, float).reshape(-1, 2))
        total = max(len(pts), scan_points or 0)
        if len(pts) < c.icp.min_points:
            # nothing in range (open ground): dead reckoning goes on, the
            # covariance grows, and only that can make the localiser lost
            self._travel = 0.0
            return self._check_lost(matched=False, inliers=0.0, rmse=math.inf)
        kept = len(pts)
        if len(pts) > c.max_points:
            pts = pts[np.linspace(0, len(pts) - 1, c.max_points).astype(int)]
        r = icp(pts, self.reference, self._x, c.icp)
        if not self._good(r):
            sig = math.sqrt(max(float(np.linalg.eigvalsh(self._p[:2, :2]).max()), 0.0))
            win = min(max(3 * sig, 0.2), c.search_max_m)
            wth = min(max(3 * math.sqrt(self._p[2, 2]), math.radians(3)), c.search_theta_rad)
            seed, _ = correlative_search(pts, self.field, self._x, win, wth,
                                         step_xy_m=0.05, step_theta_rad=math.radians(1))
            r = icp(pts, self.reference, seed, c.icp)
        self._since_fix += 1
        if self._good(r):
            rc = self._honest_covariance(r)
            innov = r.pose - self._x
            innov[2] = float(wrap(innov[2]))
            share = r.inlier_fraction * kept / total  # of the whole scan
            if self._plausible(innov, rc) and share >= c.min_scan_share:
                k = self._p @ np.linalg.inv(self._p + rc)
                self._x = self._x + k @ innov
                self._x[2] = float(wrap(self._x[2]))
                self._p = (np.eye(3) - k) @ self._p
                self._p = 0.5 * (self._p + self._p.T)
                self.failures_in_row = 0
                self.rejections_in_row = 0
                self._since_fix = 0
                self._travel = 0.0
            else:  # coast on the odometry for this scan
                self.rejections_in_row += 1
                self.rejections += 1
        else:
            self.failures_in_row += 1
        return self._check_lost(self._since_fix == 0, r.inlier_fraction, r.rmse_m)

    def _honest_covariance(self, r) -> np.ndarray:
        """The fit's covariance, floored and inflated along a weakly pinned
        direction: ICP-3 treats the scan's points as independent, but a view
        of one straight road gives correlated errors along it."""
        c = self.cfg
        rc = r.covariance * c.icp_cov_scale
        rc = 0.5 * (rc + rc.T)
        w, v = np.linalg.eigh(rc[:2, :2])  # ascending variances: v[:, 1] the weakest
        w = np.maximum(w, c.match_floor_xy_m ** 2)
        ratio = w[1] / w[0]
        if ratio > c.weak_ratio:  # pinned in one direction only
            w[1] *= ratio / c.weak_ratio
        resid = max(r.rmse_m if math.isfinite(r.rmse_m) else 0.0, c.match_floor_xy_m)
        w = np.maximum(w, resid ** 2)
        out = rc.copy()
        out[:2, :2] = (v * w) @ v.T
        out[2, 2] = max(out[2, 2], c.match_floor_theta_rad ** 2)
        return out

    def _plausible(self, innov: np.ndarray, rc: np.ndarray) -> bool:
        """The Mahalanobis gate: the correction against the predicted
        covariance, the fit's and a floor for the map's own error."""
        c = self.cfg
        s = self._p + rc + np.diag([c.gate_floor_xy_m ** 2, c.gate_floor_xy_m ** 2,
                                    c.gate_floor_theta_rad ** 2])
        d2 = float(innov @ np.linalg.solve(s, innov))
        return d2 <= c.gate_chi2

    def _check_lost(self, matched: bool, inliers: float, rmse: float) -> Quality:
        sig = math.sqrt(max(float(np.linalg.eigvalsh(self._p[:2, :2]).max()), 0.0))
        c = self.cfg
        if (self._since_fix >= c.lost_after or self._travel >= c.lost_travel_m
                or sig > c.lost_sigma_m):
            self.lost = True
        return self._quality(matched, inliers, rmse)

    def _good(self, r) -> bool:
        """A tight fit of most points. Convergence is not required: along a
        corridor ICP keeps sliding, and the covariance (large along it) makes
        the update ignore that direction."""
        return (r.inlier_fraction >= self.cfg.min_inlier_fraction
                and r.rmse_m <= self.cfg.max_rmse_m)

    def _quality(self, matched: bool, inliers: float, rmse: float) -> Quality:
        sig = math.sqrt(max(float(np.linalg.eigvalsh(self._p[:2, :2]).max()), 0.0))
        q = Quality(matched, inliers, rmse, sig, math.sqrt(self._p[2, 2]),
                    self.failures_in_row, self.lost, self.rejections_in_row)
        self.last_quality = q
        return q
