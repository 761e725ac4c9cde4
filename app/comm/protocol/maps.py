"""Map-frame messages: the occupancy map image, planned paths and the tracked
moving obstacles."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .base import MsgType, ProtocolError


@dataclass
class MapImage:
    """The robot's occupancy map: a PNG (grey: 0 blocked, 255 free, 205 unknown),
    row 0 at the top, cell (row, col) centred at
    ``(origin_x_m + (col + 0.5) * res, origin_y_m + (height - row - 0.5) * res)``
    — the ROS map_server convention."""

    TYPE: ClassVar[MsgType] = MsgType.MAP
    _S: ClassVar[struct.Struct] = struct.Struct("<fddII")
    resolution_m: float = 0.1
    origin_x_m: float = 0.0
    origin_y_m: float = 0.0
    width: int = 0
    height: int = 0
    png: bytes = b""

    def pack(self) -> bytes:
        return self._S.pack(self.resolution_m, self.origin_x_m, self.origin_y_m, self.width,
                            self.height) + bytes(self.png)

    @classmethod
    def unpack(cls, b: bytes) -> MapImage:
        if len(b) < cls._S.size:
            raise ProtocolError(f"map payload too short ({len(b)} bytes)")
        res, ox, oy, w, h = cls._S.unpack_from(b)
        png = bytes(b[cls._S.size:])
        if not png.startswith(b"\x89PNG"):
            raise ProtocolError("map payload is not a PNG")
        if not (res > 0 and w > 0 and h > 0):
            raise ProtocolError(f"map of {w}x{h} cells at {res} m is not valid")
        return cls(res, ox, oy, w, h, png)


@dataclass
class Path:
    """A path in the map frame: ``kind`` 0 = global plan, 1 = local trajectory."""

    TYPE: ClassVar[MsgType] = MsgType.PATH
    _S: ClassVar[struct.Struct] = struct.Struct("<BI")
    GLOBAL: ClassVar[int] = 0
    LOCAL: ClassVar[int] = 1
    kind: int = 0
    points_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.float32))

    def pack(self) -> bytes:
        pts = np.asarray(self.points_xy, dtype="<f4").reshape(-1, 2)
        return self._S.pack(self.kind, len(pts)) + pts.tobytes()

    @classmethod
    def unpack(cls, b: bytes) -> Path:
        if len(b) < cls._S.size:
            raise ProtocolError("path payload too short")
        kind, n = cls._S.unpack_from(b)
        if len(b) != cls._S.size + 8 * n:
            raise ProtocolError(f"path of {n} points needs {8 * n} bytes, "
                                f"has {len(b) - cls._S.size}")
        pts = np.frombuffer(b, dtype="<f4", count=2 * n, offset=cls._S.size)
        return cls(kind, pts.reshape(n, 2).astype(np.float32))


@dataclass
class Obstacles:
    """Moving obstacles as the robot tracks them, map frame: rows of
    (x_m, y_m, vx_mps, vy_mps, radius_m)."""

    TYPE: ClassVar[MsgType] = MsgType.OBSTACLES
    _S: ClassVar[struct.Struct] = struct.Struct("<I")
    rows: np.ndarray = field(default_factory=lambda: np.zeros((0, 5), np.float32))

    def pack(self) -> bytes:
        r = np.asarray(self.rows, dtype="<f4").reshape(-1, 5)
        return self._S.pack(len(r)) + r.tobytes()

    @classmethod
    def unpack(cls, b: bytes) -> Obstacles:
        if len(b) < cls._S.size:
            raise ProtocolError("obstacles payload too short")
        (n,) = cls._S.unpack_from(b)
        if len(b) != cls._S.size + 20 * n:
            raise ProtocolError(f"{n} obstacles need {20 * n} bytes")
        r = np.frombuffer(b, dtype="<f4", count=5 * n, offset=cls._S.size)
        return cls(r.reshape(n, 5).astype(np.float32))
