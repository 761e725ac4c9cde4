"""The robot's state on the wire: the heartbeat (both ways), MCU telemetry with
its alarm flags and modes, camera frames, lidar scans and the estimated pose."""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .base import MsgType, ProtocolError, _unpack_exact


@dataclass
class Heartbeat:
    """1 Hz both ways. ``echo_ts_us`` returns the timestamp of the last heartbeat
    received from the peer and ``echo_hold_us`` how long ago that was, so the
    peer computes round-trip time as ``now - echo_ts_us - echo_hold_us``."""

    TYPE: ClassVar[MsgType] = MsgType.HEARTBEAT
    _S: ClassVar[struct.Struct] = struct.Struct("<BQQI")
    role: int = 0  # 0 desk, 1 robot
    echo_ts_us: int = 0
    echo_hold_us: int = 0
    rx_frames: int = 0  # frames this side has accepted from the peer (wraps)

    ROLE_DESK: ClassVar[int] = 0
    ROLE_ROBOT: ClassVar[int] = 1

    def pack(self) -> bytes:
        return self._S.pack(self.role, self.echo_ts_us, self.echo_hold_us,
                            self.rx_frames & 0xFFFFFFFF)

    @classmethod
    def unpack(cls, b: bytes) -> Heartbeat:
        return cls(*_unpack_exact(cls._S, b))


# MCU local alarm flags (bit numbers), mirrored from docs/mcu-serial.md
class AlarmFlag(enum.IntFlag):
    GAS_HIGH = 1 << 0
    TEMP_HIGH = 1 << 1
    HUMIDITY_HIGH = 1 << 2
    OBSTACLE_NEAR = 1 << 3
    BATTERY_LOW = 1 << 4
    FAILSAFE_STOP = 1 << 5
    ESTOP = 1 << 6
    SENSOR_FAULT = 1 << 7


class RobotMode(enum.IntEnum):
    IDLE = 0
    TELEOP = 1
    PATROL = 2
    ESTOP = 3
    FAILSAFE = 4
    DOCKED = 5


@dataclass
class Telemetry:
    """One MCU sample relayed to the desk, SI units named in the fields."""

    TYPE: ClassVar[MsgType] = MsgType.TELEMETRY
    _S: ClassVar[struct.Struct] = struct.Struct("<I12fHBI")
    mcu_time_ms: int = 0
    gas_lel_pct: float = 0.0
    temp_c: float = 0.0
    humidity_pct: float = 0.0
    obstacle_left_m: float = 0.0
    obstacle_front_m: float = 0.0
    obstacle_right_m: float = 0.0
    battery_v: float = 0.0
    wheel_left_mps: float = 0.0
    wheel_right_mps: float = 0.0
    yaw_rate_rps: float = 0.0
    cmd_linear_mps: float = 0.0
    cmd_angular_rps: float = 0.0
    alarm_flags: int = 0
    mode: int = RobotMode.IDLE
    # the robot's telemetry counter, the same for every desk (wraps at 2**32): a gap
    # means a lost sample, a step back a reordered or repeated one
    tel_seq: int = 0

    def pack(self) -> bytes:
        return self._S.pack(
            self.mcu_time_ms & 0xFFFFFFFF, self.gas_lel_pct, self.temp_c, self.humidity_pct,
            self.obstacle_left_m, self.obstacle_front_m, self.obstacle_right_m,
            self.battery_v, self.wheel_left_mps, self.wheel_right_mps, self.yaw_rate_rps,
            self.cmd_linear_mps, self.cmd_angular_rps, self.alarm_flags, self.mode,
            self.tel_seq & 0xFFFFFFFF)

    @classmethod
    def unpack(cls, b: bytes) -> Telemetry:
        return cls(*_unpack_exact(cls._S, b))


@dataclass
class VideoFrame:
    """A JPEG camera frame with its capture time (robot's UTC clock)."""

    TYPE: ClassVar[MsgType] = MsgType.VIDEO_FRAME
    _S: ClassVar[struct.Struct] = struct.Struct("<IQHHf")
    frame_id: int = 0
    capture_ts_us: int = 0
    width: int = 0
    height: int = 0
    camera_pan_rad: float = 0.0
    jpeg: bytes = b""

    def pack(self) -> bytes:
        return self._S.pack(self.frame_id & 0xFFFFFFFF, self.capture_ts_us, self.width,
                            self.height, self.camera_pan_rad) + bytes(self.jpeg)

    @classmethod
    def unpack(cls, b: bytes) -> VideoFrame:
        if len(b) < cls._S.size:
            raise ProtocolError(f"video frame payload too short ({len(b)} bytes)")
        fid, ts, w, h, pan = cls._S.unpack_from(b)
        jpeg = bytes(b[cls._S.size:])
        if not jpeg.startswith(b"\xff\xd8"):
            raise ProtocolError("video frame payload is not a JPEG")
        return cls(fid, ts, w, h, pan, jpeg)


@dataclass
class LidarScan:
    """A planar scan: ``ranges_m[i]`` at ``angle_min_rad + i * angle_increment_rad``
    in the robot frame (x forward, counter-clockwise positive); inf = no return."""

    TYPE: ClassVar[MsgType] = MsgType.LIDAR_SCAN
    _S: ClassVar[struct.Struct] = struct.Struct("<QfffH")
    scan_ts_us: int = 0
    angle_min_rad: float = 0.0
    angle_increment_rad: float = 0.0
    range_max_m: float = 0.0
    ranges_m: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))

    def pack(self) -> bytes:
        r = np.asarray(self.ranges_m, dtype="<f4")
        return self._S.pack(self.scan_ts_us, self.angle_min_rad, self.angle_increment_rad,
                            self.range_max_m, r.size) + r.tobytes()

    @classmethod
    def unpack(cls, b: bytes) -> LidarScan:
        if len(b) < cls._S.size:
            raise ProtocolError(f"lidar payload too short ({len(b)} bytes)")
        ts, amin, ainc, rmax, n = cls._S.unpack_from(b)
        if len(b) != cls._S.size + 4 * n:
            raise ProtocolError(f"lidar payload holds {len(b) - cls._S.size} bytes, "
                                f"{n} ranges need {4 * n}")
        r = np.frombuffer(b, dtype="<f4", count=n, offset=cls._S.size).astype(np.float32)
        return cls(ts, amin, ainc, rmax, r)


@dataclass
class Pose:
    """The robot's own estimate of its pose (localised odometry), never ground truth."""

    TYPE: ClassVar[MsgType] = MsgType.POSE
    _S: ClassVar[struct.Struct] = struct.Struct("<dddff")
    # optional localisation quality, appended (an older robot sends only _S)
    _Q: ClassVar[struct.Struct] = struct.Struct("<ffffffB")
    STATUS_ODOMETRY, STATUS_TRACKING, STATUS_LOST = 0, 1, 2
    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = 0.0
    v_mps: float = 0.0
    omega_rps: float = 0.0
    # covariance of (x, y) in m², variance of θ in rad², the last scan's match
    # (fraction of scan points on the map, RMS residual m), and the status
    cov_xx: float | None = None
    cov_xy: float | None = None
    cov_yy: float | None = None
    var_theta: float | None = None
    match_score: float | None = None
    match_rmse_m: float | None = None
    status: int | None = None

    @property
    def has_quality(self) -> bool:
        return self.cov_xx is not None

    @property
    def lost(self) -> bool:
        return self.status == self.STATUS_LOST

    def pack(self) -> bytes:
        base = self._S.pack(self.x_m, self.y_m, self.theta_rad, self.v_mps, self.omega_rps)
        if not self.has_quality:
            return base
        return base + self._Q.pack(self.cov_xx, self.cov_xy or 0.0, self.cov_yy or 0.0,
                                   self.var_theta or 0.0, self.match_score or 0.0,
                                   self.match_rmse_m or 0.0, int(self.status or 0))

    @classmethod
    def unpack(cls, b: bytes) -> Pose:
        if len(b) == cls._S.size + cls._Q.size:
            base = cls._S.unpack(b[:cls._S.size])
            q = cls._Q.unpack(b[cls._S.size:])
            if q[6] > cls.STATUS_LOST:
                raise ProtocolError(f"pose status {q[6]} is not 0, 1 or 2")
            return cls(*base, *q)
        return cls(*_unpack_exact(cls._S, b))
