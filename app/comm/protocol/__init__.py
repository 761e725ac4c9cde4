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

The codec is split by concern: ``base`` (constants, type numbers, errors),
``telemetry`` (heartbeat, telemetry, video, lidar, pose), ``control`` (events,
commands, acks, patrol status), ``maps`` (map image, paths, obstacles) and
``framing`` (encoder, decoder, the table of message classes); every name is
importable from here.
"""

from __future__ import annotations

from .base import _CRC as _CRC
from .base import _HCRC as _HCRC
from .base import _HEADER as _HEADER
from .base import (
    HEADER_SIZE,
    MAGIC,
    MAX_PAYLOAD,
    MIN_FRAME,
    PROTOCOL_VERSION,
    TRAILER_SIZE,
    MsgType,
    ProtocolError,
    now_us,
    parse_hostport,
)
from .base import _JsonMessage as _JsonMessage
from .base import _unpack_exact as _unpack_exact
from .control import _MAC_HEAD as _MAC_HEAD
from .control import MAC_SIZE, Command, CommandAck, Event, PatrolStatus, mac_header
from .framing import (
    MESSAGE_CLASSES,
    DecoderStats,
    Frame,
    FrameDecoder,
    FrameEncoder,
    encode,
)
from .maps import MapImage, Obstacles, Path
from .telemetry import AlarmFlag, Heartbeat, LidarScan, Pose, RobotMode, Telemetry, VideoFrame

__all__ = [
    "FWS_TYPES", "HEADER_SIZE", "MAC_SIZE", "MAGIC", "MAX_PAYLOAD", "MESSAGE_CLASSES",
    "MIN_FRAME", "PROTOCOL_VERSION", "TRAILER_SIZE", "WALL_TYPES", "AlarmFlag", "Command",
    "CommandAck", "DecoderStats", "Event", "Frame", "FrameDecoder", "FrameEncoder",
    "Heartbeat", "LidarScan", "MapImage", "MsgType", "Obstacles", "Path", "PatrolStatus",
    "Pose", "ProtocolError", "RobotMode", "Telemetry", "VideoFrame", "encode", "mac_header",
    "now_us", "parse_hostport",
]

# the wall climber's messages live in their own module, which registers them in
# MESSAGE_CLASSES when imported (by this line, whichever module is imported first)
WALL_TYPES = frozenset({MsgType.WALL_INFO, MsgType.COVERAGE, MsgType.PROBE, MsgType.WALL_POSE})
import app.comm.wall_protocol  # noqa: E402,F401

# the 4WS patrol robot's messages, registered the same way
FWS_TYPES = frozenset({MsgType.WHEEL_STATE, MsgType.TEB_PLAN})
import app.comm.fws_protocol  # noqa: E402,F401
