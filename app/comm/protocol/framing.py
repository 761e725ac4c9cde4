"""Framing: the table of message classes, the encoder that numbers and checks
frames, and the incremental decoder that resynchronises on garbage and counts
what it drops (frame layout in the package docstring and docs/protocol.md)."""

from __future__ import annotations

import binascii
import struct
import zlib
from dataclasses import dataclass
from typing import Any

from .base import (
    _CRC,
    _HCRC,
    _HEADER,
    HEADER_SIZE,
    MAGIC,
    MAX_PAYLOAD,
    PROTOCOL_VERSION,
    TRAILER_SIZE,
    MsgType,
    ProtocolError,
    now_us,
)
from .control import Command, CommandAck, Event, PatrolStatus
from .maps import MapImage, Obstacles, Path
from .telemetry import Heartbeat, LidarScan, Pose, Telemetry, VideoFrame

MESSAGE_CLASSES: dict[int, type] = {
    c.TYPE: c for c in (Heartbeat, Telemetry, VideoFrame, LidarScan, Pose, Event, Command,
                        CommandAck, MapImage, Path, PatrolStatus, Obstacles)
}





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
