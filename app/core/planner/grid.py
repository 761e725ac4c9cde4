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

log = logging.getLogger(__name__)


@dataclass
class GridMap:
    blocked: np.ndarray
    resolution_m: float = 1.0
    origin_xy: tuple[float, float] = (0.0, 0.0)
    _dist_m: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        b = np.asarray(self.blocked)
        if b.ndim != 2:
            raise ValueError(f"a grid map needs a 2-D array, got shape {b.shape}")
        if not self.resolution_m > 0:
            raise ValueError(f"resolution must be positive, got {self.resolution_m}")
        self.blocked = np.ascontiguousarray(b, dtype=bool)

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


# ---- loaders ------------------------------------------------------------------


def _parse_small_yaml(text: str) -> dict[str, object]:
    """The flat ``key: value`` YAML of a ROS map file: numbers, strings and
    one-line ``[a, b, c]`` lists. Comments (#) are dropped."""
    out: dict[str, object] = {}
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if ":" not in line:
            raise ValueError(f"map yaml line {lineno}: expected 'key: value', got {raw!r}")
        key, value = (s.strip() for s in line.split(":", 1))
        if value.startswith("[") and value.endswith("]"):
            out[key] = [_scalar(v.strip()) for v in value[1:-1].split(",") if v.strip()]
        else:
            out[key] = _scalar(value)
    return out


def _scalar(v: str) -> object:
    if len(v) >= 2 and v[0] == v[-1] and v[0] in "'\"":
        return v[1:-1]
    for conv in (int, float):
        try:
            return conv(v)
        except ValueError:
            pass
    if v.lower() in ("true", "false"):
        return v.lower() == "true"
    return v


def load_ros_map(yaml_path: str | Path, unknown_blocked: bool = True) -> GridMap:
    """Load a ROS map_server map (YAML + PGM/PNG). Trinary mode: a pixel's
    occupancy p = (255 − v)/255 (v/255 when negate: 1); p > occupied_thresh is
    blocked, p < free_thresh is free, anything between is unknown."""
    yaml_path = Path(yaml_path)
    meta = _parse_small_yaml(yaml_path.read_text(encoding="utf-8"))
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            raise ValueError(f"{yaml_path}: missing '{key}'")
    img_path = Path(str(meta["image"]))
    if not img_path.is_absolute():
        img_path = yaml_path.parent / img_path
    img = cv2.imread(str(img_path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ValueError(f"{yaml_path}: cannot read image {img_path}")
    if img.ndim == 3:
        img = cv2.cvtColor(img[:, :, :3], cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        img = (img.astype(np.float64) * 255.0 / float(np.iinfo(img.dtype).max)).astype(np.uint8)
    v = img.astype(np.float64) / 255.0
    p = v if int(meta.get("negate", 0)) else 1.0 - v
    occ_t = float(meta.get("occupied_thresh", 0.65))
    free_t = float(meta.get("free_thresh", 0.196))
    blocked = p > occ_t
    unknown = (p >= free_t) & ~blocked
    if unknown_blocked:
        blocked |= unknown
    origin = meta["origin"]
    if not isinstance(origin, list) or len(origin) < 2:
        raise ValueError(f"{yaml_path}: origin must be [x, y, yaw]")
    if len(origin) > 2 and float(origin[2]) != 0.0:
        log.warning("%s: map yaw %.3f rad is ignored", yaml_path, float(origin[2]))
    res = float(meta["resolution"])  # type: ignore[arg-type]
    return GridMap(np.flipud(blocked), res, (float(origin[0]), float(origin[1])))


def save_ros_map(grid: GridMap, yaml_path: str | Path) -> None:
    """Write grid as a PGM + YAML pair that load_ros_map reads back."""
    yaml_path = Path(yaml_path)
    pgm = yaml_path.with_suffix(".pgm")
    img = np.where(np.flipud(grid.blocked), 0, 254).astype(np.uint8)
    cv2.imwrite(str(pgm), img)
    ox, oy = grid.origin_xy
    yaml_path.write_text(
        f"image: {pgm.name}\nresolution: {grid.resolution_m}\norigin: [{ox}, {oy}, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        encoding="utf-8",
    )


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
