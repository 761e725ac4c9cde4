"""Mapping mode: the operator drives the robot round the station by keyboard
and the map grows from its scans (seed 002 §2.3's laser landmarks, with loop
closure: app/core/localisation/mapping.py's ``LaserMapper``).

The navigation hands each lidar scan (pre-processed) with the odometry pose
to :meth:`MappingMode.add`; the relay publishes :meth:`map_image` every few
seconds so the desk watches the map grow (unknown cells grey), and
``save_map`` writes it in the ROS map_server format (YAML + PGM, unknown cells
kept unknown) under the robot's maps folder. The mapper works in the frame of
its first scan; the map is carried into the odometry's frame by that scan's
odometry pose (the odometry starts at the pose the robot was switched on at,
the dock), so a map made from the dock lines up with the station's.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np

from app.comm.protocol import MapImage
from app.core.localisation.map_io import FREE, OCCUPIED, OccupancyGrid, build_grid, save_map
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.se2 import compose
from app.core.mapimage import BLOCKED, UNKNOWN
from app.core.mapimage import FREE as PNG_FREE

log = logging.getLogger(__name__)

NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,40}$")


class MappingMode:
    def __init__(self, maps_dir: str | Path, resolution_m: float = 0.1) -> None:
        self.maps_dir = Path(maps_dir)
        self.resolution_m = resolution_m
        self.mapper: LaserMapper | None = None
        self.anchor: np.ndarray | None = None  # the first scan's odometry pose
        self.scans = 0

    @property
    def active(self) -> bool:
        return self.mapper is not None

    def start(self) -> None:
        self.mapper = LaserMapper(MappingConfig())
        self.anchor = None
        self.scans = 0
        log.info("mapping started")

    def stop(self) -> None:
        if self.mapper is not None and self.mapper.poses:
            self.mapper.finish()  # the final pose-graph solve
        self.mapper = None
        log.info("mapping stopped after %d scans", self.scans)

    def add(self, odom_pose, points: np.ndarray) -> None:
        if self.mapper is None or len(points) < 20:
            return
        if self.anchor is None:
            self.anchor = np.asarray(odom_pose, float)
        self.mapper.add_scan(np.asarray(odom_pose, float), points)
        self.scans += 1

    def grid(self) -> OccupancyGrid | None:
        if self.mapper is None or not self.mapper.landmarks:
            return None
        m = self.mapper
        poses = np.array([compose(self.anchor, m.poses[lm.node]) for lm in m.landmarks])
        return build_grid(poses, [lm.points for lm in m.landmarks], self.resolution_m)

    def map_image(self) -> MapImage | None:
        """The map so far as the desk's MapImage (PNG: 0 occupied, 205 unknown,
        255 free; row 0 = north)."""
        import cv2

        g = self.grid()
        if g is None:
            return None
        img = np.full(g.cells.shape, UNKNOWN, np.uint8)
        img[g.cells == FREE] = PNG_FREE
        img[g.cells == OCCUPIED] = BLOCKED
        ok, png = cv2.imencode(".png", np.flipud(img))
        if not ok:
            raise RuntimeError("PNG encoding of the map failed")
        h, w = img.shape
        return MapImage(g.resolution_m, float(g.origin_xy[0]), float(g.origin_xy[1]), w, h,
                        png.tobytes())

    def save(self, name: str) -> Path:
        """Write the map so far as maps_dir/NAME.yaml + NAME.pgm."""
        if not NAME_RE.match(name or ""):
            raise ValueError("a map name is 1-40 letters, digits, '-' or '_'")
        g = self.grid()
        if g is None:
            raise ValueError("no map yet: start mapping and drive first")
        self.maps_dir.mkdir(parents=True, exist_ok=True)
        return save_map(g, self.maps_dir / f"{name}.yaml")
