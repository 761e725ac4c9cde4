"""Occupancy maps and map-frame geometry (no Qt).

The robot sends its map as a grey PNG (0 blocked, 255 free, 205 unknown) in the
ROS map_server convention: row 0 is the *top* row of the image, and the map's
origin ``(origin_x_m, origin_y_m)`` is the world position of the *lower-left*
corner of the lower-left cell. Cell ``(row, col)`` is centred at::

    x = origin_x_m + (col + 0.5) * res
    y = origin_y_m + (height - row - 0.5) * res

:func:`decode_map` turns the message into a :class:`MapGrid`; the transforms are
vectorised and work on scalars or arrays. :func:`scan_to_map` puts a planar
lidar scan (robot frame, x forward, counter-clockwise positive) into the map
frame with the robot's pose: ``p = (x, y) + R(theta) · r (cos a, sin a)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

__all__ = ["BLOCKED", "FREE", "UNKNOWN", "MapGrid", "cell_to_world", "decode_map",
           "scan_to_map", "world_to_cell"]

BLOCKED, UNKNOWN, FREE = 0, 205, 255


@dataclass
class MapGrid:
    """A decoded occupancy map: ``image`` (height x width uint8 grey, row 0 on top)."""

    image: np.ndarray
    resolution_m: float
    origin_x_m: float
    origin_y_m: float

    @property
    def height(self) -> int:
        return int(self.image.shape[0])

    @property
    def width(self) -> int:
        return int(self.image.shape[1])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) of the whole map in metres."""
        return (self.origin_x_m, self.origin_y_m,
                self.origin_x_m + self.width * self.resolution_m,
                self.origin_y_m + self.height * self.resolution_m)

    def blocked(self) -> np.ndarray:
        """Bool grid, True where a cell is occupied (grey below 50)."""
        return self.image < 50

    def world_to_cell(self, x: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        return world_to_cell(x, y, self.resolution_m, self.origin_x_m, self.origin_y_m,
                             self.height)

    def cell_to_world(self, row: Any, col: Any) -> tuple[np.ndarray, np.ndarray]:
        return cell_to_world(row, col, self.resolution_m, self.origin_x_m, self.origin_y_m,
                             self.height)


def decode_map(msg: Any) -> MapGrid:
    """Decode a ``protocol.MapImage`` (``png``, ``width``, ``height``,
    ``resolution_m``, ``origin_x_m``, ``origin_y_m``). ValueError when the PNG
    does not decode or its size disagrees with the header."""
    res = float(msg.resolution_m)
    if not (res > 0 and np.isfinite(res)):
        raise ValueError(f"map resolution {res} m is not valid")
    buf = np.frombuffer(bytes(msg.png), np.uint8)
    img = cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE) if buf.size else None
    if img is None:
        raise ValueError("map PNG does not decode")
    h, w = img.shape[:2]
    if (w, h) != (int(msg.width), int(msg.height)):
        raise ValueError(f"map PNG is {w}x{h}, header says {msg.width}x{msg.height}")
    return MapGrid(np.ascontiguousarray(img), res, float(msg.origin_x_m),
                   float(msg.origin_y_m))


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of a grey uint8 image (for tests and tools)."""
    ok, buf = cv2.imencode(".png", np.asarray(image, np.uint8))
    if not ok:
        raise ValueError("PNG encoding failed")
    return buf.tobytes()


def world_to_cell(x: Any, y: Any, res: float, origin_x: float, origin_y: float,
                  height: int) -> tuple[np.ndarray, np.ndarray]:
    """(row, col) integer indices of the cell holding world point (x, y); may be
    outside the map (negative or >= size) — the caller checks."""
    col = np.floor((np.asarray(x, float) - origin_x) / res).astype(np.int64)
    row = (height - 1) - np.floor((np.asarray(y, float) - origin_y) / res).astype(np.int64)
    return row, col


def cell_to_world(row: Any, col: Any, res: float, origin_x: float, origin_y: float,
                  height: int) -> tuple[np.ndarray, np.ndarray]:
    """World (x, y) of the centre of cell (row, col)."""
    x = origin_x + (np.asarray(col, float) + 0.5) * res
    y = origin_y + (height - np.asarray(row, float) - 0.5) * res
    return x, y


def scan_to_map(ranges_m: Any, angle_min_rad: float, angle_increment_rad: float,
                range_max_m: float, x_m: float, y_m: float, theta_rad: float) -> np.ndarray:
    """(N, 2) float32 map-frame points of the valid returns of a scan taken at pose
    (x_m, y_m, theta_rad). Returns that are inf, nan, <= 0 or beyond
    ``range_max_m`` (when it is > 0) are dropped."""
    r = np.asarray(ranges_m, np.float64).ravel()
    a = angle_min_rad + angle_increment_rad * np.arange(r.size) + theta_rad
    ok = np.isfinite(r) & (r > 0)
    if range_max_m > 0:
        ok &= r <= range_max_m
    r, a = r[ok], a[ok]
    out = np.empty((r.size, 2), np.float32)
    out[:, 0] = x_m + r * np.cos(a)
    out[:, 1] = y_m + r * np.sin(a)
    return out
