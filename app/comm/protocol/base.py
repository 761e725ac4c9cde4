"""What every part of the wire codec shares: the frame's constants, the message
type numbers, the payload error, and the small helpers the messages use."""

from __future__ import annotations

import enum
import json
import struct
import time
from typing import ClassVar

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



def _unpack_exact(s: struct.Struct, b: bytes) -> tuple:
    if len(b) != s.size:
        raise ProtocolError(f"payload is {len(b)} bytes, expected {s.size}")
    vals = s.unpack(b)
    return vals
