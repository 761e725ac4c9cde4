"""Run laser mapping over a CARMEN log: pre-process each FLASER scan
(seed 002 Fig. 2) and feed it with its odometry pose to the mapper
(seed 002 Fig. 5). Used by the command line and the benchmarks."""

from __future__ import annotations

import numpy as np

from .carmen import CarmenLog
from .free_space import no_return_rays
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


# The logs' map keeps map_io.build_grid's l_free (−0.6: a cell is a wall
# while hits are over 40 % of its beams) and draws no free rays of no-return
# beams. The station's mapping mode draws both (sim_robot/mapping_mode.py
# MAP_L_FREE −0.3, GMapping's 25 %); on the logs that drawing covered more of
# the reference map but left more occupied cells far from it, on both logs
# (bench/carmen_map_bench.py's docstring), so the logs' map keeps its own.
LOG_MAP_L_FREE = -0.6


def usable_range_m(log: CarmenLog, cfg: PreprocessConfig | None = None) -> float:
    """The range beyond which a reading is no return, as the pre-processing
    sees it: its max range, or just below the log's no-return value when that
    is nearer."""
    cfg = cfg or PreprocessConfig()
    no_return = log.no_return_m()
    return cfg.max_range_m if no_return is None else min(cfg.max_range_m, no_return - 1e-3)


def free_rays(log: CarmenLog, cfg: PreprocessConfig | None = None) -> list[np.ndarray]:
    """Per scan, the ends (sensor frame) of the free rays of its beams that
    returned nothing (free_space.no_return_rays at the usable range)."""
    max_r = usable_range_m(log, cfg)
    return [no_return_rays(s.ranges_m, log.beam_angles(s.ranges_m.size), max_r)
            for s in log.scans]


def landmark_grid(mapper: LaserMapper, resolution_m: float = 0.05,
                  free: list[np.ndarray] | None = None, l_free: float = LOG_MAP_L_FREE,
                  poses: np.ndarray | None = None) -> OccupancyGrid:
    """The map: an occupancy grid from the landmarks' scans at their poses.
    ``free``: per scan of the log (mapper node), its no-return rays
    (free_rays), drawn from the landmarks' scans too. ``poses``: per node,
    poses to draw at instead of the mapper's (a bench's aligned or reference
    poses)."""
    allp = mapper.poses if poses is None else poses
    nodes = [lm.node for lm in mapper.landmarks]
    at = np.array([allp[k] for k in nodes])
    return build_grid(at, [lm.points for lm in mapper.landmarks], resolution_m, l_free=l_free,
                      free_scans=None if free is None else [free[k] for k in nodes])
