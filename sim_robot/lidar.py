"""A 2-D lidar: 360 beams over a full turn, ray cast on the world's occupancy grid."""

from __future__ import annotations

import math

import numpy as np

from app.comm.protocol import LidarScan, now_us

from .world import World


class Lidar:
    def __init__(self, world: World, rng: np.random.Generator, beams: int = 360,
                 range_max_m: float = 12.0, range_min_m: float = 0.15,
                 noise_m: float = 0.015, dropout: float = 0.005) -> None:
        self.world = world
        self.rng = rng
        self.beams = beams
        self.range_max_m = range_max_m
        self.range_min_m = range_min_m
        self.noise_m = noise_m
        self.dropout = dropout
        self.angle_min = -math.pi
        self.angle_inc = 2 * math.pi / beams
        self._rel = self.angle_min + self.angle_inc * np.arange(beams)

    def scan(self, x: float, y: float, theta: float) -> LidarScan:
        r, _ = self.world.raycast(x, y, theta + self._rel, self.range_max_m)
        r = r + self.noise_m * self.rng.standard_normal(self.beams).astype(np.float32)
        r[self.rng.random(self.beams) < self.dropout] = np.inf
        r[(r > self.range_max_m) | (r < self.range_min_m)] = np.inf
        return LidarScan(now_us(), self.angle_min, self.angle_inc, self.range_max_m,
                         r.astype(np.float32))


class MountedLidar:
    """The lidar on the robot's body: each reading is cast from where the
    robot really stands (the simulator's truth stays in here, the sensor; the
    navigation that calls :meth:`read` gets ranges only)."""

    def __init__(self, world: World, rng: np.random.Generator, beams: int = 360,
                 range_max_m: float = 12.0) -> None:
        self._world = world
        self._lidar = Lidar(world, rng, beams, range_max_m)
        self.stamp_s: float | None = None  # sim time the last reading saw the world at

    @property
    def range_max_m(self) -> float:
        return self._lidar.range_max_m

    def read(self) -> LidarScan:
        """One scan; ``stamp_s`` says when (the sim time of the world's last
        motion step, which lags the sim clock when the MCU model falls behind)."""
        p, self.stamp_s = self._world.pose_and_time()
        return self._lidar.scan(p.x, p.y, p.theta)
