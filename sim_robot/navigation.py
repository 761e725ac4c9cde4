"""The robot's navigation stack, one step at a time: localise, perceive, execute.

Shared by the relay (its navigation thread, wall-clock paced, sim-time steps)
and by :mod:`sim_robot.patrol_sim` (tests and the bench, stepped directly):

1. localisation (:mod:`localisation`, a stand-in for a scan matcher): odometry
   increment + a fix toward the true pose with bounded noise;
2. perception: a lidar scan from the true pose, interpreted with the
   *estimated* pose: returns off the static map clustered and tracked
   (:mod:`tracker`) — never the world's list of people;
3. the mission executor (:mod:`patrol`) turns pose, velocity and tracked
   obstacles into a speed command.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import cv2
import numpy as np

from app.comm.protocol import MapImage
from app.core.planner import GridMap

from .lidar import Lidar
from .localisation import Localiser
from .patrol import PatrolConfig, PatrolExecutor
from .tracker import ObstacleTracker
from .world import World


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
                 lidar_range_m: float = 12.0) -> None:
        self.world = world
        blocked, res, origin = world.occupancy_grid()
        self.grid = GridMap(blocked, res, origin)
        d = world.dock
        p = world.pose
        self.localiser = Localiser(p.x, p.y, p.theta, seed)
        self.lidar = Lidar(world, np.random.default_rng(seed + 4000), lidar_beams,
                           lidar_range_m)
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

    def localise(self, odom_xytheta: tuple[float, float, float]) -> tuple[float, float, float]:
        tp = self.world.pose
        self.localiser.predict(odom_xytheta)
        return self.localiser.correct((tp.x, tp.y, tp.theta), (tp.v, tp.omega))

    def perceive(self, t_s: float) -> np.ndarray:
        tp = self.world.pose
        scan = self.lidar.scan(tp.x, tp.y, tp.theta)
        det = self.tracker.detect(scan.ranges_m, scan.angle_min_rad, scan.angle_increment_rad,
                                  self.localiser.pose)
        self.tracker.update(t_s, det)
        self.obstacles = self.tracker.obstacles()
        self.scan_t = t_s
        return self.obstacles

    def step(self, t_s: float, dt: float, odom_xytheta: tuple[float, float, float]
             ) -> tuple[float, float, bool]:
        """Localise, perceive (while a mission owns the motors), decide."""
        t0 = time.perf_counter()
        pose = self.localise(odom_xytheta)
        ex = self.executor
        if ex.owns_motors:
            self.perceive(t_s)
        vel = (self.localiser.v, self.localiser.omega)
        v, w, send = ex.tick(t_s, dt, pose, vel, self.obstacles)
        if ex.owns_motors:
            self.step_ms.append((time.perf_counter() - t0) * 1000.0)
        return v, w, send
