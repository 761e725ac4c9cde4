"""The robot link's wire codec, shared by the desk and the robot (no Qt).

Every frame (little-endian, byte layout in docs/protocol.md)::

    offset size field
    0      2    magic        0xA5 0x5A
    2      1    version      PROTOCOL_VERSION
    3      1    msg_type     MsgType
    4      4    length       payload bytes, <= MAX_PAYLOAD
    8      4    seq          sender's sequence number (wraps at 2**32)
    12     8    timestamp_us sender's UTC clock, microseconds since the epoch
    20     2    header_crc   CRC-16/CCITT of bytes 2..19
    22     n    payload
    22+n   4    crc32        CRC-32 of bytes 2..22+n-1

The header has its own CRC so a corrupt length is rejected at once instead of
stalling the decoder while it waits for a megabyte that never comes.
:class:`FrameDecoder` accepts the byte stream in any chunking, resynchronises
on the magic after garbage, and counts every frame it drops and why.
"""

from __future__ import annotations

import binascii
import enum
import json
import struct
import time
import zlib
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

MAGIC = b"\xa5\x5a"
PROTOCOL_VERSION = 1
MAX_PAYLOAD = 1 << 20  # 1 MiB: a 640x480 JPEG is far smaller
_HEADER = struct.Struct("<2sBBIIQ")  # magic, version, type, length, seq, timestamp_us
_HCRC = struct.Struct("<H")
_CRC = struct.Struct("<I")
HEADER_SIZE = _HEADER.size + _HCRC.size  # 22
TRAILER_SIZE = _CRC.size
MIN_FRAME = HEADER_SIZE + TRAILER_SIZE


class MsgType(enum.IntEnum):
    HEARTBEAT = 1
    TELEMETRY = 2
    VIDEO_FRAME = 3
    LIDAR_SCAN = 4
    POSE = 5
    EVENT = 6
    COMMAND = 7
    COMMAND_ACK = 8
    MAP = 9
    PATH = 10
    PATROL_STATUS = 11
    OBSTACLES = 12
    # the wall climber (app/comm/wall_protocol.py)
    WALL_INFO = 20
    COVERAGE = 21
    PROBE = 22
    WALL_POSE = 23
    # the four-wheel-steer patrol robot (app/comm/fws_protocol.py)
    WHEEL_STATE = 24
    TEB_PLAN = 25


class ProtocolError(ValueError):
    """A payload that does not decode as its message type."""


def parse_hostport(text: str, *, allow_port_zero: bool = False) -> tuple[str, int]:
    """``"HOST:PORT"`` (``[::1]:PORT`` for IPv6) as ``(host, port)``; ValueError with
    a message an operator can act on. Port 0 (pick a free one) only for listening."""
    host, sep, port = text.rpartition(":")
    lo = 0 if allow_port_zero else 1
    if not sep or not host or not port.isdigit() or not lo <= int(port) <= 65535:
        raise ValueError(f"expected HOST:PORT with a port {lo}-65535, got {text!r}")
    return host.strip("[]"), int(port)


def now_us() -> int:
    """UTC wall clock in microseconds (frame timestamps, latency on one host)."""
    return time.time_ns() // 1000


# --------------------------------------------------------------------------- messages


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


class _JsonMessage:
    """Messages whose payload is a small UTF-8 JSON object."""

    _FIELDS: ClassVar[tuple[str, ...]] = ()

    def pack(self) -> bytes:
        return json.dumps({k: getattr(self, k) for k in self._FIELDS},
                          separators=(",", ":")).encode()

    @classmethod
    def unpack(cls, b: bytes):
        try:
            obj = json.loads(bytes(b).decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ProtocolError(f"{cls.__name__} payload is not JSON: {e}") from None
        if not isinstance(obj, dict):
            raise ProtocolError(f"{cls.__name__} payload is not a JSON object")
        try:
            return cls(**{k: obj[k] for k in cls._FIELDS if k in obj})
        except TypeError as e:
            raise ProtocolError(f"{cls.__name__}: {e}") from None


@dataclass
class Event(_JsonMessage):
    """Something that happened on the robot worth a line in the operator's log."""

    TYPE: ClassVar[MsgType] = MsgType.EVENT
    _FIELDS: ClassVar[tuple[str, ...]] = ("level", "code", "text", "data")
    level: str = "info"  # info | warning | alarm
    code: str = ""
    text: str = ""
    data: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def unpack(cls, b: bytes) -> Event:
        ev = super().unpack(b)
        if not (isinstance(ev.level, str) and isinstance(ev.code, str)
                and isinstance(ev.text, str) and isinstance(ev.data, dict)):
            raise ProtocolError("event fields have the wrong types")
        return ev


@dataclass
class Command(_JsonMessage):
    """An operator intent. ``name`` e.g. ``drive`` (args linear_mps, angular_rps),
    ``stop``, ``estop``, ``reset_estop``, ``set_speed``, ``request_control``. The robot
    answers with a :class:`CommandAck` naming this frame's sequence number.

    A signed command (see :mod:`app.comm.auth` and docs/security.md) carries
    ``auth`` = ``{"desk", "session", "ctr"}`` in its JSON and, after the JSON, a NUL
    byte and a 32-byte HMAC-SHA256 tag (``mac``). JSON text never holds a raw NUL,
    so an unsigned command is told apart without doubt. ``body`` keeps the JSON bytes
    as received, the bytes the tag covers."""

    TYPE: ClassVar[MsgType] = MsgType.COMMAND
    _FIELDS: ClassVar[tuple[str, ...]] = ("name", "args", "auth")
    name: str = ""
    args: dict[str, Any] = field(default_factory=dict)
    auth: dict[str, Any] | None = None
    mac: bytes = b""
    body: bytes = b""

    def json_bytes(self) -> bytes:
        obj: dict[str, Any] = {"name": self.name, "args": self.args}
        if self.auth is not None:
            obj["auth"] = self.auth
        return json.dumps(obj, separators=(",", ":")).encode()

    def pack(self) -> bytes:
        body = self.json_bytes()
        return body + b"\0" + bytes(self.mac) if self.mac else body

    @classmethod
    def unpack(cls, b: bytes) -> Command:
        b = bytes(b)
        mac = b""
        if len(b) > MAC_SIZE and b[-MAC_SIZE - 1] == 0:
            b, mac = b[:-MAC_SIZE - 1], b[-MAC_SIZE:]
        cmd = super().unpack(b)
        if not isinstance(cmd.name, str):
            raise ProtocolError("command name is not a string")
        if not isinstance(cmd.args, dict):
            raise ProtocolError("command args are not a JSON object")
        if cmd.auth is not None and not isinstance(cmd.auth, dict):
            raise ProtocolError("command auth is not a JSON object")
        cmd.mac, cmd.body = mac, b
        return cmd


MAC_SIZE = 32  # HMAC-SHA256
_MAC_HEAD = struct.Struct("<BBIIQ")  # version, type, length, seq, timestamp_us


def mac_header(msg_type: int, length: int, seq: int, timestamp_us: int) -> bytes:
    """The header fields a command's tag covers (besides its JSON body): a tag
    copied onto another frame, type, length, sequence number or time fails."""
    return _MAC_HEAD.pack(PROTOCOL_VERSION, msg_type, length, seq & 0xFFFFFFFF,
                          timestamp_us)


@dataclass
class CommandAck:
    TYPE: ClassVar[MsgType] = MsgType.COMMAND_ACK
    _S: ClassVar[struct.Struct] = struct.Struct("<IB")
    cmd_seq: int = 0
    ok: bool = True
    reason: str = ""

    def pack(self) -> bytes:
        return self._S.pack(self.cmd_seq & 0xFFFFFFFF, 1 if self.ok else 0) + \
            self.reason.encode("utf-8")

    @classmethod
    def unpack(cls, b: bytes) -> CommandAck:
        if len(b) < cls._S.size:
            raise ProtocolError("command ack payload too short")
        seq, ok = cls._S.unpack_from(b)
        try:
            reason = bytes(b[cls._S.size:]).decode("utf-8")
        except UnicodeDecodeError:
            raise ProtocolError("command ack reason is not UTF-8") from None
        return cls(seq, bool(ok), reason)


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


@dataclass
class PatrolStatus(_JsonMessage):
    """Where the patrol stands. ``state``: idle | planning | driving | avoiding |
    inspecting | paused | docking | done | aborted | failed. ``points``: the route,
    each ``{"name", "kind", "x_m", "y_m", "state"}`` with state pending | current |
    done | skipped. ``reason`` says why it stopped or failed."""

    TYPE: ClassVar[MsgType] = MsgType.PATROL_STATUS
    _FIELDS: ClassVar[tuple[str, ...]] = ("state", "route", "index", "points", "reason",
                                          "progress", "local_planner")
    state: str = "idle"
    route: str = ""
    index: int = -1
    points: list[dict[str, Any]] = field(default_factory=list)
    reason: str = ""
    progress: float = 0.0
    local_planner: str = ""

    @classmethod
    def unpack(cls, b: bytes) -> PatrolStatus:
        st = super().unpack(b)
        if not (isinstance(st.state, str) and isinstance(st.route, str)
                and type(st.index) is int and isinstance(st.reason, str)
                and isinstance(st.progress, (int, float)) and isinstance(st.local_planner, str)
                and isinstance(st.points, list)
                and all(isinstance(p, dict) for p in st.points)):
            raise ProtocolError("patrol status fields have the wrong types")
        return st


MESSAGE_CLASSES: dict[int, type] = {
    c.TYPE: c for c in (Heartbeat, Telemetry, VideoFrame, LidarScan, Pose, Event, Command,
                        CommandAck, MapImage, Path, PatrolStatus, Obstacles)
}


def _unpack_exact(s: struct.Struct, b: bytes) -> tuple:
    if len(b) != s.size:
        raise ProtocolError(f"payload is {len(b)} bytes, expected {s.size}")
    vals = s.unpack(b)
    return vals


# --------------------------------------------------------------------------- framing


@dataclass
class Frame:
    msg_type: MsgType
    seq: int
    timestamp_us: int
    message: Any
    size: int  # bytes on the wire


class FrameEncoder:
    """Turns messages into frames, numbering them. With a ``signer`` (an
    :class:`app.comm.auth.CommandSigner`) every :class:`Command` is signed."""

    def __init__(self, first_seq: int = 0, signer=None) -> None:
        self.seq = first_seq & 0xFFFFFFFF
        self.signer = signer

    def encode(self, message, timestamp_us: int | None = None) -> bytes:
        if self.signer is not None and isinstance(message, Command):
            seq = self.seq
            self.seq = (self.seq + 1) & 0xFFFFFFFF
            ts = now_us() if timestamp_us is None else timestamp_us
            payload = self.signer.seal(message, seq, ts)
            return self.encode_raw(int(message.TYPE), payload, ts, seq=seq)
        payload = message.pack()
        return self.encode_raw(int(message.TYPE), payload, timestamp_us)

    def encode_raw(self, msg_type: int, payload: bytes, timestamp_us: int | None = None,
                   seq: int | None = None) -> bytes:
        if len(payload) > MAX_PAYLOAD:
            raise ValueError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}")
        if seq is None:
            seq = self.seq
            self.seq = (self.seq + 1) & 0xFFFFFFFF
        ts = now_us() if timestamp_us is None else timestamp_us
        head = _HEADER.pack(MAGIC, PROTOCOL_VERSION, msg_type, len(payload), seq, ts)
        head += _HCRC.pack(binascii.crc_hqx(head[2:], 0xFFFF))
        crc = zlib.crc32(payload, zlib.crc32(head[2:]))
        return b"".join((head, payload, _CRC.pack(crc)))


@dataclass
class DecoderStats:
    frames: int = 0
    bytes_in: int = 0
    garbage_bytes: int = 0
    bad_header: int = 0  # header CRC mismatch
    bad_version: int = 0
    bad_length: int = 0  # length beyond MAX_PAYLOAD
    bad_checksum: int = 0  # frame CRC mismatch
    unknown_type: int = 0
    bad_payload: int = 0  # checksum right, payload does not decode

    @property
    def dropped(self) -> int:
        return (self.bad_header + self.bad_version + self.bad_length + self.bad_checksum
                + self.unknown_type + self.bad_payload)

    def as_dict(self) -> dict[str, int]:
        d = dict(self.__dict__)
        d["dropped"] = self.dropped
        return d


class FrameDecoder:
    """Incremental decoder: ``feed(bytes)`` returns the whole frames completed so far.

    Garbage before a magic is skipped and counted; a frame whose header or body
    fails its check is dropped, counted, and the search resumes one byte later,
    so a real frame hidden inside garbage is still found.
    """

    def __init__(self, max_payload: int = MAX_PAYLOAD) -> None:
        self.max_payload = max_payload
        self.stats = DecoderStats()
        self._buf = bytearray()
        self.last_error = ""

    def _drop(self, kind: str, why: str, skip: int) -> None:
        setattr(self.stats, kind, getattr(self.stats, kind) + 1)
        self.last_error = why
        del self._buf[:skip]

    def feed(self, data: bytes) -> list[Frame]:
        self.stats.bytes_in += len(data)
        buf = self._buf
        buf += data
        out: list[Frame] = []
        while True:
            i = buf.find(MAGIC)
            if i < 0:
                # keep a trailing first byte of the magic: it may complete next time
                keep = 1 if buf[-1:] == MAGIC[:1] else 0
                self.stats.garbage_bytes += len(buf) - keep
                del buf[:len(buf) - keep]
                return out
            if i:
                self.stats.garbage_bytes += i
                del buf[:i]
            if len(buf) < HEADER_SIZE:
                return out
            _magic, ver, mtype, length, seq, ts = _HEADER.unpack_from(buf)
            (hcrc,) = _HCRC.unpack_from(buf, _HEADER.size)
            if binascii.crc_hqx(bytes(buf[2:_HEADER.size]), 0xFFFF) != hcrc:
                self._drop("bad_header", "header checksum mismatch", 1)
                continue
            if ver != PROTOCOL_VERSION:
                self._drop("bad_version", f"protocol version {ver}", 1)
                continue
            if length > self.max_payload:
                self._drop("bad_length", f"length {length} > {self.max_payload}", 1)
                continue
            total = HEADER_SIZE + length + TRAILER_SIZE
            if len(buf) < total:
                return out
            (crc,) = _CRC.unpack_from(buf, HEADER_SIZE + length)
            if zlib.crc32(memoryview(buf)[2:HEADER_SIZE + length]) != crc:
                self._drop("bad_checksum", "frame checksum mismatch", 1)
                continue
            payload = bytes(buf[HEADER_SIZE:HEADER_SIZE + length])
            del buf[:total]
            cls = MESSAGE_CLASSES.get(mtype)
            if cls is None:
                self.stats.unknown_type += 1
                self.last_error = f"unknown message type {mtype}"
                continue
            try:
                msg = cls.unpack(payload)
            except (ProtocolError, struct.error, ValueError) as e:
                self.stats.bad_payload += 1
                self.last_error = f"{cls.__name__}: {e}"
                continue
            self.stats.frames += 1
            out.append(Frame(MsgType(mtype), seq, ts, msg, total))

    @property
    def buffered(self) -> int:
        return len(self._buf)

    @property
    def pending_bytes(self) -> int:
        """Bytes still to come for the frame whose header sits at the buffer's
        start (0 when no checked header is waiting)."""
        buf = self._buf
        if len(buf) < HEADER_SIZE or buf[:2] != MAGIC:
            return 0
        _m, ver, _t, length, _s, _ts = _HEADER.unpack_from(buf)
        (hcrc,) = _HCRC.unpack_from(buf, _HEADER.size)
        if (binascii.crc_hqx(bytes(buf[2:_HEADER.size]), 0xFFFF) != hcrc
                or ver != PROTOCOL_VERSION or length > self.max_payload):
            return 0
        return max(0, HEADER_SIZE + length + TRAILER_SIZE - len(buf))


def encode(message, seq: int = 0, timestamp_us: int | None = None) -> bytes:
    """One-off encoding of a message with a given sequence number."""
    return FrameEncoder().encode_raw(int(message.TYPE), message.pack(), timestamp_us, seq=seq)


# the wall climber's messages live in their own module, which registers them in
# MESSAGE_CLASSES when imported (by this line, whichever module is imported first)
WALL_TYPES = frozenset({MsgType.WALL_INFO, MsgType.COVERAGE, MsgType.PROBE, MsgType.WALL_POSE})
import app.comm.wall_protocol  # noqa: E402,F401

# the 4WS patrol robot's messages, registered the same way
FWS_TYPES = frozenset({MsgType.WHEEL_STATE, MsgType.TEB_PLAN})
import app.comm.fws_protocol  # noqa: E402,F401
