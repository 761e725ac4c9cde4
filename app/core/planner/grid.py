"""Occupancy grid map (seed 000 §4.1, eqs. 22–23).

D = {(m, n)} is the set of cells (eq. 22) and B[m][n] = 1 marks an obstacle
(eq. 23); here ``blocked[row, col]`` is True for an obstacle.

World frame: x to the right, y up, metres. Row r covers
y ∈ [oy + r·res, oy + (r+1)·res) and column c covers x ∈ [ox + c·res, …), so
``origin_xy`` is the lower-left corner of cell (0, 0) — the ROS map_server
convention once the image is flipped (image row 0 is the top line).

Moving AI maps keep their file order (row 0 = top line), resolution 1 and
origin (0, 0): they are used in cell units only.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from ..localisation.map_io import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, load_map, save_map

log = logging.getLogger(__name__)


@dataclass
class GridMap:
    blocked: np.ndarray
    resolution_m: float = 1.0
    origin_xy: tuple[float, float] = (0.0, 0.0)
    unknown: np.ndarray | None = None  # cells never observed (kept when saved)
    _dist_m: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        b = np.asarray(self.blocked)
        if b.ndim != 2:
            raise ValueError(f"a grid map needs a 2-D array, got shape {b.shape}")
        if not self.resolution_m > 0:
            raise ValueError(f"resolution must be positive, got {self.resolution_m}")
        self.blocked = np.ascontiguousarray(b, dtype=bool)
        if self.unknown is not None:
            self.unknown = np.asarray(self.unknown, dtype=bool)
            if self.unknown.shape != b.shape:
                raise ValueError(f"unknown mask {self.unknown.shape} does not match {b.shape}")

    @property
    def shape(self) -> tuple[int, int]:
        return self.blocked.shape  # type: ignore[return-value]

    @property
    def size_m(self) -> tuple[float, float]:
        h, w = self.shape
        return w * self.resolution_m, h * self.resolution_m

    # -- frames -----------------------------------------------------------------
    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding world point (x, y); may lie outside."""
        ox, oy = self.origin_xy
        return (
            int(math.floor((y - oy) / self.resolution_m)),
            int(math.floor((x - ox) / self.resolution_m)),
        )

    def cell_to_world(self, row: float, col: float) -> tuple[float, float]:
        """World (x, y) of the centre of cell (row, col)."""
        ox, oy = self.origin_xy
        return ox + (col + 0.5) * self.resolution_m, oy + (row + 0.5) * self.resolution_m

    def in_bounds(self, row: int, col: int) -> bool:
        h, w = self.shape
        return 0 <= row < h and 0 <= col < w

    def is_free_xy(self, x: float, y: float) -> bool:
        r, c = self.world_to_cell(x, y)
        return self.in_bounds(r, c) and not self.blocked[r, c]

    # -- derived maps -------------------------------------------------------------
    def inflate(self, radius_m: float) -> GridMap:
        """A new map where every cell whose centre lies within radius_m (plus half
        a cell, to stay conservative) of an obstacle cell's centre is blocked."""
        if radius_m <= 0:
            return GridMap(self.blocked.copy(), self.resolution_m, self.origin_xy)
        dist_cells = self._distance_cells()
        grown = dist_cells < radius_m / self.resolution_m + 0.5
        return GridMap(grown, self.resolution_m, self.origin_xy)

    def _distance_cells(self) -> np.ndarray:
        """Distance from each cell centre to the nearest blocked cell centre, in
        cells; the outside of the map counts as blocked."""
        free = np.pad(~self.blocked, 1, constant_values=False).astype(np.uint8)
        d = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        return d[1:-1, 1:-1].astype(np.float64)

    @property
    def distance_m(self) -> np.ndarray:
        """Clearance field: metres from each cell centre to the nearest obstacle
        surface (centre distance minus half a cell); 0 inside obstacles."""
        if self._dist_m is None:
            d = (self._distance_cells() - 0.5) * self.resolution_m
            self._dist_m = np.maximum(d, 0.0)
        return self._dist_m


# ---- ROS map_server files (read and written by app/core/localisation/map_io) ---------


def load_ros_map(yaml_path: str | Path, unknown_blocked: bool = True) -> GridMap:
    """Load a ROS map_server map (YAML + PGM/PNG). Trinary mode: a pixel's
    occupancy p = (255 − v)/255 (v/255 when negate: 1); p > occupied_thresh is
    blocked, p < free_thresh is free, anything between is unknown. Unknown
    cells are blocked for planning unless told otherwise, and kept in
    ``GridMap.unknown`` so that saving the map writes them back as unknown."""
    occ = load_map(yaml_path)
    unknown = occ.unknown
    blocked = occ.occupied | (unknown if unknown_blocked else False)
    return GridMap(blocked, occ.resolution_m, occ.origin_xy, unknown=unknown)


def save_ros_map(grid: GridMap, yaml_path: str | Path) -> None:
    """Write grid as a PGM + YAML pair that load_ros_map reads back; cells in
    ``grid.unknown`` are written as unknown, not as obstacles."""
    cells = np.where(grid.blocked, OCCUPIED, FREE).astype(np.int8)
    if grid.unknown is not None:
        cells[grid.unknown] = UNKNOWN
    save_map(OccupancyGrid(cells, grid.resolution_m, grid.origin_xy), yaml_path)


_MOVINGAI_FREE = frozenset(".GS")


def parse_movingai_map(text: str) -> np.ndarray:
    """Blocked array of a Moving AI .map text (row 0 = first map line)."""
    lines = text.splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines) and lines[i].strip() != "map":
        parts = lines[i].split()
        if len(parts) >= 2:
            header[parts[0]] = parts[1]
        i += 1
    if i == len(lines) or "height" not in header or "width" not in header:
        raise ValueError("not a Moving AI map: needs 'height', 'width' and 'map' lines")
    h, w = int(header["height"]), int(header["width"])
    rows = lines[i + 1 : i + 1 + h]
    if len(rows) != h or any(len(r) < w for r in rows):
        raise ValueError(f"Moving AI map: expected {h} rows of {w} characters")
    return np.array([[ch not in _MOVINGAI_FREE for ch in r[:w]] for r in rows], dtype=bool)


def load_movingai_map(path: str | Path) -> GridMap:
    return GridMap(parse_movingai_map(Path(path).read_text(encoding="ascii")), 1.0, (0.0, 0.0))


@dataclass(frozen=True)
class ScenQuery:
    bucket: int
    start: tuple[int, int]  # (row, col)
    goal: tuple[int, int]
    optimal_length: float


def load_movingai_scen(path: str | Path) -> list[ScenQuery]:
    """Queries of a .scen file; x is the column, y the row."""
    out = []
    for line in Path(path).read_text(encoding="ascii").splitlines():
        parts = line.split("\t")
        if len(parts) < 9 or parts[0].startswith("version"):
            continue
        b, sx, sy, gx, gy = (
            int(parts[0]),
            int(parts[4]),
            int(parts[5]),
            int(parts[6]),
            int(parts[7]),
        )
        out.append(ScenQuery(b, (sy, sx), (gy, gx), float(parts[8])))
    return out
