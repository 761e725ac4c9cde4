"""The four-wheel-steer patrol robot's link messages (docs/protocol.md, "4WS
patrol robot"): the four wheels' state and the TEB local plan. Qt-free;
registered with the frame codec on import (:mod:`app.comm.protocol` imports this
module; message types 24–25, after the wall climber's 20–23).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from app.comm.protocol import MESSAGE_CLASSES, MsgType, ProtocolError, _unpack_exact

WHEELS = ("front_left", "front_right", "rear_left", "rear_right")
MODES = ("stopped", "front", "counter", "crab", "pivot")  # as the MCU reports them
MAX_TEB_POSES = 1000


@dataclass
class WheelState:
    """The four wheels (FL, FR, RL, RR): steering angle (rad, anticlockwise
    positive, 0 = straight ahead) and signed rolling speed (m/s), and the
    steering ``mode`` (an index into ``MODES``), as the MCU last reported them."""

    TYPE: ClassVar[MsgType] = MsgType.WHEEL_STATE
    _S: ClassVar[struct.Struct] = struct.Struct("<IB4f4f")
    mcu_time_ms: int = 0
    mode: int = 0
    angles_rad: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
    speeds_mps: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)

    @property
    def mode_name(self) -> str:
        return MODES[self.mode] if 0 <= self.mode < len(MODES) else f"mode {self.mode}"

    def pack(self) -> bytes:
        return self._S.pack(self.mcu_time_ms & 0xFFFFFFFF, self.mode & 0xFF,
                            *map(float, self.angles_rad), *map(float, self.speeds_mps))

    @classmethod
    def unpack(cls, b: bytes) -> WheelState:
        v = _unpack_exact(cls._S, b)
        angles, speeds = tuple(v[2:6]), tuple(v[6:10])
        if not all(math.isfinite(x) for x in angles + speeds):
            raise ProtocolError("wheel state has a value that is not finite")
        if v[1] >= len(MODES):
            raise ProtocolError(f"wheel state mode {v[1]} is unknown")
        return cls(v[0], v[1], angles, speeds)


@dataclass
class TebPlan:
    """The TEB local plan (map frame): ``poses`` n × 3 (x_m, y_m, theta_rad),
    ``dts_s`` the n − 1 time intervals between them, and whether the base is
    turning in place (the optimised TEB's step ②)."""

    TYPE: ClassVar[MsgType] = MsgType.TEB_PLAN
    _S: ClassVar[struct.Struct] = struct.Struct("<BI")
    turning_in_place: bool = False
    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.float32))
    dts_s: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))

    def pack(self) -> bytes:
        p = np.asarray(self.poses, dtype="<f4").reshape(-1, 3)
        d = np.asarray(self.dts_s, dtype="<f4").reshape(-1)
        if len(p) and len(d) != len(p) - 1:
            raise ValueError(f"{len(p)} poses need {len(p) - 1} intervals, not {len(d)}")
        return self._S.pack(1 if self.turning_in_place else 0, len(p)) + p.tobytes() + \
            d.tobytes()

    @classmethod
    def unpack(cls, b: bytes) -> TebPlan:
        if len(b) < cls._S.size:
            raise ProtocolError("TEB plan payload too short")
        turning, n = cls._S.unpack_from(b)
        if n > MAX_TEB_POSES:
            raise ProtocolError(f"TEB plan of {n} poses exceeds {MAX_TEB_POSES}")
        nd = max(n - 1, 0)
        if len(b) != cls._S.size + 12 * n + 4 * nd:
            raise ProtocolError(f"TEB plan of {n} poses has {len(b)} bytes")
        p = np.frombuffer(b, dtype="<f4", count=3 * n, offset=cls._S.size).reshape(n, 3)
        d = np.frombuffer(b, dtype="<f4", count=nd, offset=cls._S.size + 12 * n)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(d))):
            raise ProtocolError("TEB plan has a value that is not finite")
        return cls(bool(turning), p.astype(np.float32), d.astype(np.float32))


for _cls in (WheelState, TebPlan):
    MESSAGE_CLASSES[_cls.TYPE] = _cls
