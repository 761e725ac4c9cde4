"""Control and mission messages: the robot's events, the operator's commands
(signed or not) and their acknowledgements, and the patrol's status."""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from typing import Any, ClassVar

from .base import PROTOCOL_VERSION, MsgType, ProtocolError, _JsonMessage


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
