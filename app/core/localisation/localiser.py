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
   grows). After ``lost_after``
   failures in a row, or when the position σ exceeds ``lost_sigma_m``, the
   localiser is *lost*: it stops changing its pose and says so until an
   operator (or the dock) sets the pose again. It never reports a guess as a
   fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .icp import IcpConfig, LikelihoodField, Reference, correlative_search, icp, warm_up
from .map_io import OccupancyGrid
from .se2 import compose, transform_points, wrap


@dataclass(frozen=True)
class LocaliserConfig:
    max_points: int = 180  # scan points used per match (evenly thinned)
    min_inlier_fraction: float = 0.5
    max_rmse_m: float = 0.08
    lost_after: int = 8  # failed matches in a row
    lost_sigma_m: float = 0.5
    search_max_m: float = 1.0
    search_theta_rad: float = math.radians(10)
    icp_cov_scale: float = 4.0
    recheck_below: float = 0.995  # a fit explaining less of the scan gets a second opinion
    recheck_m: float = 0.3  # its search window (± metres) around the fit
    recheck_gain: float = 0.008  # the other fit must explain more of the scan (2 in 180 points)
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


def wall_points(grid: OccupancyGrid) -> np.ndarray:
    """The surface a lidar sees, in world metres (see :func:`wall_surface`)."""
    return wall_surface(grid)[0]


def wall_surface(grid: OccupancyGrid) -> tuple[np.ndarray, np.ndarray]:
    """The surface a lidar sees, in world metres: for each occupied cell that
    touches a non-occupied 4-neighbour, its centre moved half a cell towards
    those neighbours (a beam stops at the cell's face, not its centre); and
    the unit direction it faces (towards those neighbours; zero for a lone
    cell, seen from all sides)."""
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
    facing = np.where(norm > 1e-6, s / norm, 0.0)
    ox, oy = grid.origin_xy
    centres = np.column_stack((ox + (cols + 0.5) * grid.resolution_m,
                               oy + (rows + 0.5) * grid.resolution_m))
    return centres + facing * 0.5 * grid.resolution_m, facing


class MapLocaliser:
    def __init__(self, grid: OccupancyGrid, cfg: LocaliserConfig | None = None) -> None:
        self.cfg = cfg or LocaliserConfig()
        pts, facing = wall_surface(grid)
        if len(pts) < self.cfg.icp.min_points:
            raise ValueError("the map has too few occupied cells to localise in")
        # the faces are known: a scan point never matches a wall's far side
        self.reference = Reference(pts, self.cfg.icp.normal_neighbours, facing,
                                   bucket_m=grid.resolution_m)
        self.field = LikelihoodField(pts, res_m=max(grid.resolution_m, 0.05), margin_m=1.0)
        # load (or compile, once per install) the compiled matcher now, not on the first scan
        icp(pts[:self.cfg.icp.min_points], self.reference, np.zeros(3), self.cfg.icp)
        correlative_search(pts[:2], self.field, np.zeros(3), 0.0, 0.0)
        warm_up(self.reference)
        self._x = np.zeros(3)
        self._p = np.eye(3)
        self._initialised = False
        self.failures_in_row = 0
        self.lost = True  # until a pose is given
        self.last_quality: Quality | None = None
        self.rechecks_taken = 0  # fits replaced by the second opinion

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
        s_xy = c.odom_trans_frac * d + c.odom_trans_min_m
        s_th = c.odom_rot_frac * abs(u[2]) + c.odom_rot_per_m * d + c.odom_rot_min_rad
        q = rot @ np.diag([s_xy ** 2, s_xy ** 2, s_th ** 2]) @ rot.T
        self._x = compose(self._x, u)
        self._p = j @ self._p @ j.T + q

    def update(self, points: np.ndarray, sensor_pose=(0.0, 0.0, 0.0)) -> Quality:
        """Match a pre-processed scan (points in the sensor frame; the sensor at
        ``sensor_pose`` in the robot frame) and fuse it."""
        c = self.cfg
        if self.lost:
            return self._quality(False, 0.0, math.inf)
        pts = transform_points(sensor_pose, np.asarray(points, float).reshape(-1, 2))
        if len(pts) < c.icp.min_points:
            # nothing in range (open ground): dead reckoning goes on, the
            # covariance grows, and only that can make the localiser lost
            return self._check_lost(matched=False, inliers=0.0, rmse=math.inf)
        if len(pts) > c.max_points:
            pts = pts[np.linspace(0, len(pts) - 1, c.max_points).astype(int)]
        org = np.asarray(sensor_pose, float)[:2]
        r = icp(pts, self.reference, self._x, c.icp, org)
        if not self._good(r):
            sig = math.sqrt(max(float(np.linalg.eigvalsh(self._p[:2, :2]).max()), 0.0))
            win = min(max(3 * sig, 0.2), c.search_max_m)
            wth = min(max(3 * math.sqrt(self._p[2, 2]), math.radians(3)), c.search_theta_rad)
            seed, _ = correlative_search(pts, self.field, self._x, win, wth,
                                         step_xy_m=0.05, step_theta_rad=math.radians(1))
            r = icp(pts, self.reference, seed, c.icp, org)
        elif r.inlier_fraction < c.recheck_below:
            r = self._second_opinion(pts, r, org)
        if self._good(r):
            rc = r.covariance * c.icp_cov_scale + np.diag([1e-6, 1e-6, 1e-8])
            k = self._p @ np.linalg.inv(self._p + rc)
            innov = r.pose - self._x
            innov[2] = float(wrap(innov[2]))
            self._x = self._x + k @ innov
            self._x[2] = float(wrap(self._x[2]))
            self._p = (np.eye(3) - k) @ self._p
            self.failures_in_row = 0
        else:
            self.failures_in_row += 1
        return self._check_lost(self.failures_in_row == 0, r.inlier_fraction, r.rmse_m)

    def _second_opinion(self, pts: np.ndarray, r, org: np.ndarray):
        """ICP is local: started a few cells off where the map pins one
        direction with few points (a road between tanks), the final gate
        drops exactly those points as outliers and the fit stays off with
        most of the scan on the map and a covariance that claims centimetres.
        A fit that leaves points unexplained gets a second opinion: the best
        pose on the likelihood field within ``recheck_m`` of it seeds ICP
        again, and the fit that explains more of the scan is kept."""
        c = self.cfg
        seed, _ = correlative_search(pts, self.field, r.pose, c.recheck_m, math.radians(1),
                                     step_xy_m=0.05, step_theta_rad=math.radians(1))
        if math.hypot(seed[0] - r.pose[0], seed[1] - r.pose[1]) < 0.05:
            return r  # the field agrees with the fit
        r2 = icp(pts, self.reference, seed, c.icp, org)
        if self._good(r2) and r2.inlier_fraction > r.inlier_fraction + c.recheck_gain:
            self.rechecks_taken += 1
            return r2
        return r

    def _check_lost(self, matched: bool, inliers: float, rmse: float) -> Quality:
        sig = math.sqrt(max(float(np.linalg.eigvalsh(self._p[:2, :2]).max()), 0.0))
        if self.failures_in_row >= self.cfg.lost_after or sig > self.cfg.lost_sigma_m:
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
                    self.failures_in_row, self.lost)
        self.last_quality = q
        return q
