"""The robot's navigation stack, one step at a time: localise, perceive, execute.

Shared by the relay (its navigation thread, wall-clock paced, sim-time steps)
and by :mod:`sim_robot.patrol_sim` (tests and the bench, stepped directly):

1. localisation (:mod:`localisation`): the odometry increment predicts, each
   lidar scan is matched to the station map (resources/station) and fused;
   when it is lost the robot stops, an event says so, and it waits for the
   operator's ``set_pose`` — it never drives on a guess;
2. perception: the same scan, interpreted with the *estimated* pose: returns
   off the static map clustered and tracked (:mod:`tracker`) — never the
   world's list of people;
3. the mission executor (:mod:`patrol`) turns pose, velocity and tracked
   obstacles into a speed command.

The world is used for the station's static layout (map, dock, gauges) and by
the lidar sensor (:class:`~sim_robot.lidar.MountedLidar`); the navigation never
reads the robot's true pose (tests/sim/test_localisation_patrol.py guards it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import cv2
import numpy as np

from app.comm.protocol import MapImage, Pose
from app.core.planner import GridMap

from .lidar import MountedLidar
from .localisation import RobotLocaliser, load_station_map
from .patrol import PatrolConfig, PatrolExecutor
from .tracker import ObstacleTracker
from .world import World

ODOM_LAG_MAX_S = 0.25  # the odometry is carried forward at most this far (sim time)


def map_image(grid: GridMap) -> MapImage:
    """The occupancy grid as a MapImage (PNG, 0 blocked / 255 free, row 0 = north)."""
    img = np.where(np.flipud(grid.blocked), 0, 255).astype(np.uint8)
    ok, png = cv2.imencode(".png", img)
    if not ok:
        raise RuntimeError("PNG encoding of the map failed")
    h, w = grid.blocked.shape
    return MapImage(grid.resolution_m, grid.origin_xy[0], grid.origin_xy[1], w, h,
                    png.tobytes())


class Navigation:
    def __init__(self, world: World, seed: int, emit: Callable[..., None],
                 publish: Callable[[object], None], look_at: Callable[[str | None], None],
                 config: PatrolConfig | None = None, lidar_beams: int = 360,
                 lidar_range_m: float = 12.0,
                 initial_pose: tuple[float, float, float] | None = None,
                 station_map: str | None = None) -> None:
        self.world = world
        self.emit = emit
        blocked, res, origin = world.occupancy_grid()
        self.grid = GridMap(blocked, res, origin)
        d = world.dock
        # the dock's pose, unless the robot was switched on elsewhere (then the
        # caller says where, as an operator would)
        start = initial_pose if initial_pose is not None else (d[0], d[1], d[2])
        loc_map = load_station_map(station_map) if station_map else load_station_map()
        self.localiser = RobotLocaliser(loc_map, start)
        self.lidar = MountedLidar(world, np.random.default_rng(seed + 4000), lidar_beams,
                                  lidar_range_m)
        self._odom_last = None  # (pose, velocity) of the last odometry sample
        self.odom_t: float | None = None  # its sim time (the MCU report's)
        self.mapping = None  # a MappingMode while the robot maps (the relay sets it)
        self.lost_reported = False
        self._stop_pending = False
        self.scan = None  # the last lidar scan (LidarScan)
        self.tracker = ObstacleTracker(world.clearance_m, res, origin)
        tanks = [(t["x"], t["y"]) for t in world.spec.get("tanks", [])]
        self.executor = PatrolExecutor(self.grid, (d[0], d[1], d[2]),
                                       {g.id: (g.x, g.y) for g in world.gauges}, tanks, emit,
                                       publish, look_at, config)
        self.step_ms: list[float] = []
        self.obstacles = np.zeros((0, 5))
        self.scan_t: float | None = None

    def warm_up(self) -> None:
        """Run the compiled kernels once (numba cache load) before the first mission."""
        d = self.world.dock
        hp = self.executor.planner
        hp.plan((d[0], d[1]), (d[0] - 1.0, d[1]))
        hp.step((d[0], d[1], d[2]), (0.0, 0.0), [(d[0] - 3, d[1], 0.1, 0.0, 0.3)], 0.1)
        hp.warm_up()
        hp.set_path([])

    def perceive(self, t_s: float) -> np.ndarray:
        """Read the lidar: match the scan to the map (localisation), then
        track what is not on the map, seen from the corrected estimate."""
        scan = self.lidar.read()
        self.scan = scan
        self._align_odometry(self.lidar.stamp_s)
        fused = self.localiser.scans
        self.localiser.correct(scan, self.obstacles)
        loc = self.localiser
        if (self.mapping is not None and self.mapping.active and loc.scans > fused
                and loc.odom_pose is not None):
            self.mapping.add(loc.odom_pose, loc.last_points)  # a new view only
        self._check_lost()
        if not self.localiser.lost:
            det = self.tracker.detect(scan.ranges_m, scan.angle_min_rad,
                                      scan.angle_increment_rad, self.localiser.pose)
            self.tracker.update(t_s, det)
            self.obstacles = self.tracker.obstacles()
        self.scan_t = t_s
        return self.obstacles

    def _align_odometry(self, scan_t: float | None) -> None:
        """Carry the odometry forward to the scan's time by its velocities:
        the last odometry sample may be a few MCU periods older than the scan
        (threads lag at a high time scale), as a real driver's timestamps
        would show."""
        if scan_t is None or self.odom_t is None or self._odom_last is None:
            return
        lag = min(max(scan_t - self.odom_t, 0.0), ODOM_LAG_MAX_S)
        if lag <= 0.0:
            return
        (x, y, th), (v, w) = self._odom_last
        mid = th + w * lag / 2
        self.localiser.predict((x + v * lag * math.cos(mid), y + v * lag * math.sin(mid),
                                th + w * lag), (v, w))

    def _check_lost(self) -> None:
        """On losing localisation: stop the mission and tell the operator, once."""
        loc = self.localiser
        if not loc.lost or self.lost_reported:
            return
        self.lost_reported = True
        q = loc.quality
        x, y, th = loc.pose
        self._stop_pending = True
        if self.executor.owns_motors:
            self.executor.pause("localisation lost")
        self.emit("alarm", "localisation_lost",
                  "localisation lost: the robot stopped; set its pose on the map to go on",
                  x_m=round(x, 3), y_m=round(y, 3), theta_rad=round(th, 4),
                  failures=q.failures_in_row if q else 0,
                  sigma_xy_m=round(q.sigma_xy_m, 3) if q else None)

    def set_pose(self, x: float, y: float, theta: float) -> None:
        """The operator's pose (``set_pose``): localisation starts again from it."""
        was_lost = self.localiser.lost
        self.localiser.set_pose(x, y, theta, sigma_xy_m=0.25, sigma_theta_rad=math.radians(8))
        self.lost_reported = False
        self.emit("info", "pose_set", f"pose set by the operator to ({x:.2f}, {y:.2f}, "
                  f"{math.degrees(theta):.0f}°)" + (" — localisation restored" if was_lost else ""),
                  x_m=x, y_m=y, theta_rad=theta, was_lost=was_lost)

    def pose_message(self, v_mps: float, omega_rps: float) -> Pose:
        """The published pose: the estimate and its quality (never the truth)."""
        loc = self.localiser
        x, y, th = loc.pose
        p = loc.covariance
        q = loc.quality
        status = Pose.STATUS_LOST if loc.lost else Pose.STATUS_TRACKING
        return Pose(x, y, th, v_mps, omega_rps, float(p[0, 0]), float(p[0, 1]), float(p[1, 1]),
                    float(p[2, 2]), float(q.inlier_fraction) if q else 0.0,
                    float(q.rmse_m) if q and math.isfinite(q.rmse_m) else 0.0, status)

    def step(self, t_s: float, dt: float, odom_xytheta: tuple[float, float, float],
             odom_velocity: tuple[float, float] = (0.0, 0.0),
             odom_t_s: float | None = None) -> tuple[float, float, bool]:
        """Localise (odometry prediction; a scan while a mission owns the
        motors), perceive, decide. Lost: stop, whatever the mission wanted."""
        t0 = time.perf_counter()
        loc = self.localiser
        loc.predict(odom_xytheta, odom_velocity)
        self._odom_last = (tuple(odom_xytheta), tuple(odom_velocity))
        self.odom_t = t_s if odom_t_s is None else odom_t_s
        ex = self.executor
        if ex.owns_motors:
            self.perceive(t_s)
        if loc.lost:
            self._check_lost()
            # one stop command; then the motors are the operator's (driving by
            # hand is allowed, missions are refused until the pose is set)
            stop, self._stop_pending = self._stop_pending, False
            return 0.0, 0.0, stop
        vel = (loc.v, loc.omega)
        v, w, send = ex.tick(t_s, dt, loc.pose, vel, self.obstacles)
        if ex.owns_motors:
            self.step_ms.append((time.perf_counter() - t0) * 1000.0)
        return v, w, send
