"""The robot's localisation on its own sensors: lidar scans matched to the
station map, fused with the encoder/IMU odometry.

:class:`RobotLocaliser` wraps app/core/localisation's ``MapLocaliser``
(scan-to-map ICP, correlative search, Kalman fusion; seed 002 §2.3 with the
map as the landmark) for the robot's navigation:

- the odometry (:mod:`sim_robot.odometry`, the encoder/gyro EKF of seed 003)
  gives a pose in its own drifting frame; each step its increment since the
  last step, expressed in the robot frame, is the localiser's prediction;
- each lidar scan is pre-processed (seed 002 Fig. 2) and matched to the map,
  leaving out the points on obstacles the navigation tracks (people, the cart);
  a scan taken before the latest odometry sample is matched from where the
  robot was then (the odometry pose at the scan's time, ``scan_odom``): the
  estimate lives at the odometry's time, and the scan's points are carried
  into that robot frame by the odometry between the two;
- the initial pose comes from the dock (or whoever switched the robot on at
  another place) and later from the operator's ``set_pose``;
- standing still, only every ``still_every``-th scan is fused (as AMCL's
  update_min_d / update_min_a): where the map constrains a direction weakly
  (a straight road) each match there wanders a little, and many matches of one
  view would walk the estimate; one in ten keeps a kidnapped robot noticed;
- once the map localiser is lost, the pose stops changing and ``lost`` stays
  set until :meth:`set_pose` — the navigation stops the robot on it;
- standing still, a lost robot may find itself again (:meth:`relocalise`, as
  AMCL's global localisation but within ``RELOC_WINDOW_M`` of where it lost
  itself): every heading and every position on a grid around the last
  estimate is scored on the map's likelihood field, the best few distinct
  candidates are refined by ICP, and the best is taken only if it explains
  nearly all of the scan and no distinct other candidate comes close (a place
  the scan cannot tell from another is left to the operator's ``set_pose``).
  The dock is such a place (its view also fits one 1.1 m away turned round,
  97 % of the scan against 100 %); a robot whose board says it is on its
  charger searches only within the dock's radius.

It never sees the simulator's ground truth: the lidar hands it ranges, the
odometry hands it an integrated pose, and that is all.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from app.comm.protocol import LidarScan
from app.core.localisation.free_space import no_return_rays
from app.core.localisation.icp import correlative_search, icp
from app.core.localisation.localiser import LocaliserConfig, MapLocaliser, Quality
from app.core.localisation.map_io import OccupancyGrid, load_map
from app.core.localisation.preprocess import PreprocessConfig, preprocess
from app.core.localisation.se2 import compose, relative, transform_points
from app.core.paths import resource

log = logging.getLogger(__name__)

MOVER_MARGIN_M = 0.25  # around a tracked obstacle's disc, its points are not matched
RELOC_WINDOW_M = 3.0  # a lost robot searches for itself this far around its last estimate
RELOC_STEP_M = 0.2  # ... on this grid
RELOC_STEP_RAD = math.radians(3.0)  # ... at every heading, this far apart
RELOC_CANDIDATES = 6  # the best distinct candidates refined by ICP
RELOC_MIN_INLIERS = 0.9  # the fit taken must explain this share of the scan
RELOC_MAX_RMSE_M = 0.05
RELOC_DISTINCT_M = 1.0  # candidates farther apart than this (or turned by more than
RELOC_DISTINCT_RAD = math.radians(20)  # this) are different places
RELOC_MARGIN = 0.1  # ... and every other must explain this much less of the scan
STATION_MAP = resource("station", "station_map.yaml")


def load_station_map(path: str | Path = STATION_MAP) -> OccupancyGrid:
    """The station's saved map (ROS map_server YAML + image)."""
    return load_map(path)


class RobotLocaliser:
    def __init__(self, grid: OccupancyGrid, start_pose: tuple[float, float, float],
                 cfg: LocaliserConfig | None = None,
                 pre: PreprocessConfig | None = None,
                 start_sigma_xy_m: float = 0.05,
                 start_sigma_theta_rad: float = math.radians(2.0),
                 still_m: float = 0.01, still_rad: float = math.radians(0.5),
                 still_every: int = 10) -> None:
        self.map = MapLocaliser(grid, cfg)
        self.pre = pre or PreprocessConfig(max_range_m=11.9)
        self.map_pre = replace(self.pre, min_segment_points=1)  # map_points()
        self._for_map: tuple | None = None  # the last fused scan, for map_points()
        self.start_sigma = (start_sigma_xy_m, start_sigma_theta_rad)
        self.v = 0.0
        self.omega = 0.0
        self._odom: tuple[float, float, float] | None = None
        self._angles: tuple[float, float, int, np.ndarray] | None = None
        self.still = (still_m, still_rad, still_every)
        self._moved = np.zeros(2)  # |translation|, |rotation| since the last fused scan
        self._still_scans = 0
        self.skipped = 0  # scans not fused because the robot stood still
        self.mover_points = 0  # scan points left out as on a tracked obstacle
        self.fixes = 0  # matched scans
        self.scans = 0  # scans offered
        self.failures = 0  # scans that did not fit the map
        self.lost_count = 0  # times localisation was lost
        self.relocalisations = 0  # times a lost robot found itself on the map
        self.reloc_tries = 0  # searches for itself
        self.last_points = np.zeros((0, 2))  # the last scan, pre-processed (sensor frame)
        # ...less its points on tracked obstacles (people, the cart): what a map may keep
        self.static_points = np.zeros((0, 2))
        self.odom_pose: tuple[float, float, float] | None = None  # the last odometry pose
        self.scan_odom_pose: tuple[float, float, float] | None = None  # at the last scan
        self.set_pose(*start_pose, *self.start_sigma)

    # ------------------------------------------------------------------ state

    @property
    def pose(self) -> tuple[float, float, float]:
        x, y, th = self.map.pose
        return float(x), float(y), float(th)

    @property
    def covariance(self) -> np.ndarray:
        return self.map.covariance

    @property
    def lost(self) -> bool:
        return self.map.lost

    @property
    def quality(self) -> Quality | None:
        return self.map.last_quality

    def set_pose(self, x: float, y: float, theta: float, sigma_xy_m: float | None = None,
                 sigma_theta_rad: float | None = None) -> None:
        """An initial pose (the dock's, or the operator's ``set_pose``)."""
        sxy = self.start_sigma[0] if sigma_xy_m is None else sigma_xy_m
        sth = self.start_sigma[1] if sigma_theta_rad is None else sigma_theta_rad
        self.map.set_pose((x, y, theta), sxy, sth)
        self._still_scans = 0
        log.info("localisation: pose set to (%.2f, %.2f, %.1f°)", x, y, math.degrees(theta))

    # ------------------------------------------------------------------ steps

    def predict(self, odom_xytheta: tuple[float, float, float],
                velocity: tuple[float, float] = (0.0, 0.0)) -> None:
        """Move by the odometry increment since the last call (taken in the
        robot frame, so the odometry frame's drift does not leak in)."""
        if self._odom is not None:
            u = relative(self._odom, odom_xytheta)
            self._moved += (math.hypot(u[0], u[1]), abs(u[2]))
            self.map.predict(u)
        self._odom = tuple(odom_xytheta)
        self.odom_pose = self._odom
        self.v, self.omega = velocity

    def pose_at(self, odom_xytheta) -> tuple[float, float, float]:
        """The estimate carried to where the odometry said ``odom_xytheta``
        (an earlier or a later odometry pose than the last predicted one)."""
        if self._odom is None:
            return self.pose
        x, y, th = compose(self.map.pose, relative(self._odom, odom_xytheta))
        return float(x), float(y), float(th)

    def correct(self, scan: LidarScan, movers: np.ndarray | None = None,
                scan_odom: tuple[float, float, float] | None = None) -> Quality:
        """Match one lidar scan to the map and fuse it. ``movers``: rows
        (x, y, vx, vy, radius) of tracked obstacles (world frame); scan points
        on them are left out of the match — a cart beside the robot can hide
        half the view, and its points fit no wall. ``scan_odom``: the
        odometry pose at the scan's time (default: the last one predicted)."""
        was_lost = self.map.lost
        still_m, still_rad, every = self.still
        if not was_lost and self._moved[0] < still_m and self._moved[1] < still_rad:
            self._still_scans += 1
            if self._still_scans % every and self.map.last_quality is not None:
                self.skipped += 1
                return self.map.last_quality
        self._moved[:] = 0.0
        scan_odom = self._odom if scan_odom is None else tuple(scan_odom)
        self.scan_odom_pose = scan_odom
        # the robot at the scan's time, in the robot frame at the estimate's time
        seen_from = (0.0, 0.0, 0.0) if self._odom is None else relative(self._odom, scan_odom)
        ranges = np.asarray(scan.ranges_m, float)
        pts = preprocess(ranges, self._beam_angles(scan), self.pre)
        self.last_points = pts
        self._for_map = (ranges, self._beam_angles(scan), movers,
                         compose(self.map.pose, seen_from))
        keep = _off_movers(pts, movers, self._for_map[3])
        self.mover_points += int(len(pts) - keep.sum())
        pts = pts[keep]
        self.static_points = pts
        q = self.map.update(pts, seen_from)
        self.scans += 1
        if q.matched:
            self.fixes += 1
        elif not was_lost:
            self.failures += 1
        if q.lost and not was_lost:
            self.lost_count += 1
        return q

    def map_points(self) -> np.ndarray:
        """The last fused scan for a map (mapping mode's occupancy grid): as
        ``static_points`` (off the tracked obstacles), but a lone return
        between two range jumps is kept. Matching drops it (a mixed point or
        clutter, no line to pair with), but on a far wall seen at a grazing
        angle every beam is such a lone return, and the map would miss the wall."""
        if self._for_map is None:
            return np.zeros((0, 2))
        ranges, angles, movers, pose = self._for_map
        pts = preprocess(ranges, angles, self.map_pre)
        return pts[_off_movers(pts, movers, pose)]

    def free_points(self) -> np.ndarray:
        """The last fused scan's beams that returned nothing, as the ends of
        their free rays (sensor frame; app/core/localisation/free_space.py):
        what a map learns of open ground, where nothing comes back."""
        if self._for_map is None:
            return np.zeros((0, 2))
        ranges, angles, _movers, _pose = self._for_map
        return no_return_rays(ranges, angles, self.pre.max_range_m)

    def relocalise(self, scan: LidarScan, around: tuple[float, float] | None = None,
                   window_m: float = RELOC_WINDOW_M, confined: bool = False
                   ) -> tuple[tuple[float, float, float], float] | None:
        """Find a lost robot on the map from one scan taken standing still:
        ``((x, y, θ), inlier fraction)`` of the fit taken (and the estimate set
        there), or None when the scan fits nowhere near well enough, or fits
        two different places alike. It searches within ``window_m`` of
        ``around`` (default: the last estimate); ``confined``: the robot is
        known to be there, and fits that ICP carried farther are dropped."""
        ranges = np.asarray(scan.ranges_m, float)
        pts = preprocess(ranges, self._beam_angles(scan), self.pre)
        cfg = self.map.cfg
        if len(pts) < cfg.icp.min_points:
            return None
        if len(pts) > cfg.max_points:
            pts = pts[np.linspace(0, len(pts) - 1, cfg.max_points).astype(int)]
        x0, y0 = self.pose[:2] if around is None else around
        seeds = []  # (score, pose): the best position at each heading
        for th in np.arange(-math.pi, math.pi, RELOC_STEP_RAD):
            best, score = correlative_search(pts, self.map.field, (x0, y0, th), window_m,
                                             0.0, step_xy_m=RELOC_STEP_M)
            seeds.append((score, best))
        seeds.sort(key=lambda s: -s[0])
        fits = []
        for _, seed in seeds:
            if len(fits) >= RELOC_CANDIDATES:
                break
            if any(not _distinct(seed, f.pose) for f in fits):
                continue
            fits.append(icp(pts, self.map.reference, seed, cfg.icp))
        if confined:
            fits = [r for r in fits if math.hypot(float(r.pose[0]) - x0,
                                                  float(r.pose[1]) - y0) <= window_m]
        fits.sort(key=lambda r: (-r.inlier_fraction, r.rmse_m))
        self.reloc_tries += 1
        if not fits:
            log.info("relocalisation: no fit within %.1f m: not taken", window_m)
            return None
        best = fits[0]
        if best.inlier_fraction < RELOC_MIN_INLIERS or not best.rmse_m <= RELOC_MAX_RMSE_M:
            log.info("relocalisation: best fit %.0f %% of the scan, rmse %.3f m: not taken",
                     100 * best.inlier_fraction, best.rmse_m)
            return None
        rival = max((r.inlier_fraction for r in fits[1:] if _distinct(r.pose, best.pose)),
                    default=0.0)
        if rival > best.inlier_fraction - RELOC_MARGIN:
            log.info("relocalisation: two places fit (%.0f %% and %.0f %%): not taken",
                     100 * best.inlier_fraction, 100 * rival)
            return None
        x, y, th = (float(v) for v in best.pose)
        self.set_pose(x, y, th, sigma_xy_m=0.1, sigma_theta_rad=math.radians(3))
        self.relocalisations += 1
        return (x, y, th), float(best.inlier_fraction)

    def _beam_angles(self, scan: LidarScan) -> np.ndarray:
        n = len(scan.ranges_m)
        key = (scan.angle_min_rad, scan.angle_increment_rad, n)
        if self._angles is None or self._angles[:3] != key:
            a = scan.angle_min_rad + scan.angle_increment_rad * np.arange(n)
            self._angles = (*key, a)
        return self._angles[3]


def _off_movers(pts: np.ndarray, movers: np.ndarray | None, pose) -> np.ndarray:
    """Mask of the sensor-frame points (taken at world ``pose``) that lie off
    every tracked obstacle's disc (rows x, y, vx, vy, radius) and its margin."""
    if movers is None or not len(movers) or not len(pts):
        return np.ones(len(pts), bool)
    world = transform_points(pose, pts)
    d = np.hypot(world[:, None, 0] - movers[None, :, 0], world[:, None, 1] - movers[None, :, 1])
    return ~(d <= movers[None, :, 4] + MOVER_MARGIN_M).any(axis=1)


def _distinct(a, b) -> bool:
    """Two poses that are different places (not one fit seen twice)."""
    turn = abs((float(a[2]) - float(b[2]) + math.pi) % (2 * math.pi) - math.pi)
    return math.hypot(float(a[0]) - float(b[0]), float(a[1]) - float(b[1])) > RELOC_DISTINCT_M \
        or turn > RELOC_DISTINCT_RAD
