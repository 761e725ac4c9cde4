"""Run laser mapping over a CARMEN log: pre-process each FLASER scan
(seed 002 Fig. 2) and feed it with its odometry pose to the mapper
(seed 002 Fig. 5). Used by the command line and the benchmarks."""

from __future__ import annotations

import numpy as np

from .carmen import CarmenLog
from .map_io import OccupancyGrid, build_grid
from .mapping import LaserMapper, MappingConfig
from .preprocess import PreprocessConfig, preprocess
from .se2 import relative


def scan_points(log: CarmenLog, cfg: PreprocessConfig | None = None) -> list[np.ndarray]:
    """Pre-processed points (sensor frame) of every scan; the beam angles
    follow each scan's own beam count over the log's field of view."""
    no_return = log.no_return_m()
    return [preprocess(s.ranges_m, log.beam_angles(s.ranges_m.size), cfg, no_return)
            for s in log.scans]


def log_odometry(log: CarmenLog) -> np.ndarray:
    """The FLASER odometry poses, in the frame of the first one."""
    odo = np.array([s.odom for s in log.scans], dtype=float)
    return np.array([relative(odo[0], p) for p in odo]) if len(odo) else odo.reshape(0, 3)


def run_mapping(points: list[np.ndarray], odometry: np.ndarray,
                cfg: MappingConfig | None = None) -> tuple[np.ndarray, LaserMapper]:
    """Poses (N, 3) of every scan after the final pose-graph solve, in the
    frame of the first pose, and the mapper (landmarks, edges, counters)."""
    mapper = LaserMapper(cfg or MappingConfig())
    for odo, pts in zip(odometry, points, strict=True):
        mapper.add_scan(odo, pts)
    return mapper.finish(), mapper


def landmark_grid(mapper: LaserMapper, resolution_m: float = 0.05) -> OccupancyGrid:
    """The map: an occupancy grid from the landmarks' scans at their poses."""
    poses = np.array([mapper.poses[lm.node] for lm in mapper.landmarks])
    return build_grid(poses, [lm.points for lm in mapper.landmarks], resolution_m)
