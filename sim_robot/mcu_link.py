"""The MCU serial protocol: small binary frames between the Pi (relay) and the STM32.

Frame layout (little-endian, see docs/mcu-serial.md)::

    0xAA 0x55 | type u8 | seq u8 | len u8 | payload (len bytes) | crc16 u16

``crc16`` is CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) over type, seq, len
and payload. :class:`McuDecoder` takes bytes in any chunking, resynchronises on
the sync word after garbage, and counts what it drops. Every type has a fixed
payload length, so a header whose length does not match its type is rejected
at once (a false sync word inside garbage cannot stall the decoder).
"""

from __future__ import annotations

import binascii
import enum
import math
import struct
from dataclasses import dataclass

SYNC = b"\xaa\x55"
MAX_LEN = 255
_HEAD = struct.Struct("<2sBBB")
_CRC = struct.Struct("<H")
OVERHEAD = _HEAD.size + _CRC.size  # 7 bytes


class McuType(enum.IntEnum):
    SENSOR_REPORT = 0x01  # MCU -> Pi, 20 Hz
    ACK = 0x02  # MCU -> Pi, answers MOTOR_CMD / CONFIG / ESTOP
    MOTOR_CMD = 0x10  # Pi -> MCU
    KEEPALIVE = 0x11  # Pi -> MCU, every 100 ms
    CONFIG = 0x12  # Pi -> MCU, warning limits
    ESTOP = 0x13  # Pi -> MCU, engage (1) / release (0)
    PROBE_REPORT = 0x03  # MCU -> Pi, the wall climber's thickness probe, each sample
    WHEEL_REPORT = 0x04  # MCU -> Pi, the 4WS base's four wheels, each sample
    BODY_CMD = 0x14  # Pi -> MCU, the 4WS base's body twist (vx, vy, ω): crab driving


def crc16(data: bytes) -> int:
    return binascii.crc_hqx(data, 0xFFFF)


def encode_frame(msg_type: int, seq: int, payload: bytes = b"") -> bytes:
    if len(payload) > MAX_LEN:
        raise ValueError(f"MCU payload of {len(payload)} bytes exceeds {MAX_LEN}")
    body = _HEAD.pack(SYNC, msg_type, seq & 0xFF, len(payload)) + payload
    return body + _CRC.pack(crc16(body[2:]))


# --------------------------------------------------------------------------- payloads


@dataclass
class SensorReport:
    """One MCU sample. Scaled integers on the wire, SI floats here."""

    _S = struct.Struct("<IhhHHHHHhhhiihhHBh")
    mcu_time_ms: int = 0
    gas_lel_pct: float = 0.0  # wire: 0.01 %LEL, signed (a faulty sensor reads below zero)
    temp_c: float = 0.0  # wire: 0.1 degC
    humidity_pct: float = 0.0  # wire: 0.1 %RH
    obstacle_left_m: float = 0.0  # wire: mm
    obstacle_front_m: float = 0.0
    obstacle_right_m: float = 0.0
    battery_v: float = 0.0  # wire: mV
    wheel_left_mps: float = 0.0  # wire: mm/s
    wheel_right_mps: float = 0.0
    yaw_rate_rps: float = 0.0  # wire: mrad/s
    enc_left_ticks: int = 0  # cumulative, wraps at 2**31
    enc_right_ticks: int = 0
    cmd_linear_mps: float = 0.0  # what the MCU is executing, mm/s
    cmd_angular_rps: float = 0.0  # mrad/s
    alarm_flags: int = 0  # app.comm.protocol.AlarmFlag bits
    mode: int = 0  # app.comm.protocol.RobotMode
    imu_yaw_rad: float = 0.0  # gyro integrated on the MCU, wraps at +-pi; wire: 1e-4 rad

    def pack(self) -> bytes:
        return self._S.pack(
            self.mcu_time_ms & 0xFFFFFFFF, _i16(self.gas_lel_pct * 100),
            _i16(self.temp_c * 10), _u16(self.humidity_pct * 10),
            _u16(self.obstacle_left_m * 1000), _u16(self.obstacle_front_m * 1000),
            _u16(self.obstacle_right_m * 1000), _u16(self.battery_v * 1000),
            _i16(self.wheel_left_mps * 1000), _i16(self.wheel_right_mps * 1000),
            _i16(self.yaw_rate_rps * 1000), _i32(self.enc_left_ticks),
            _i32(self.enc_right_ticks), _i16(self.cmd_linear_mps * 1000),
            _i16(self.cmd_angular_rps * 1000), self.alarm_flags & 0xFFFF, self.mode & 0xFF,
            _i16(_wrap_pi(self.imu_yaw_rad) * 10000))

    @classmethod
    def unpack(cls, b: bytes) -> SensorReport:
        (t, gas, temp, hum, ol, of, orr, bat, wl, wr, yaw, el, er, cv, cw, flags,
         mode, heading) = cls._S.unpack(b)
        return cls(t, gas / 100, temp / 10, hum / 10, ol / 1000, of / 1000, orr / 1000,
                   bat / 1000, wl / 1000, wr / 1000, yaw / 1000, el, er, cv / 1000,
                   cw / 1000, flags, mode, heading / 10000)


@dataclass
class MotorCmd:
    _S = struct.Struct("<hh")
    linear_mps: float = 0.0  # wire: mm/s
    angular_rps: float = 0.0  # wire: mrad/s

    def pack(self) -> bytes:
        return self._S.pack(_i16(self.linear_mps * 1000), _i16(self.angular_rps * 1000))

    @classmethod
    def unpack(cls, b: bytes) -> MotorCmd:
        v, w = cls._S.unpack(b)
        return cls(v / 1000, w / 1000)


@dataclass
class BodyCmd:
    """The 4WS base's full body twist: forward and sideways speed and yaw rate
    (body frame, Y to the left). A ``MOTOR_CMD`` is this with ``lateral_mps`` 0."""

    _S = struct.Struct("<hhh")
    linear_mps: float = 0.0  # wire: mm/s
    lateral_mps: float = 0.0  # wire: mm/s
    angular_rps: float = 0.0  # wire: mrad/s

    def pack(self) -> bytes:
        return self._S.pack(_i16(self.linear_mps * 1000), _i16(self.lateral_mps * 1000),
                            _i16(self.angular_rps * 1000))

    @classmethod
    def unpack(cls, b: bytes) -> BodyCmd:
        v, vy, w = cls._S.unpack(b)
        return cls(v / 1000, vy / 1000, w / 1000)


@dataclass
class ConfigLimits:
    _S = struct.Struct("<HhHHH")
    gas_lel_pct: float = 10.0  # 0.01 %LEL
    temp_c: float = 45.0  # 0.1 degC
    humidity_pct: float = 90.0  # 0.1 %RH
    obstacle_m: float = 0.35  # mm
    battery_low_v: float = 22.0  # mV

    def pack(self) -> bytes:
        return self._S.pack(_u16(self.gas_lel_pct * 100), _i16(self.temp_c * 10),
                            _u16(self.humidity_pct * 10), _u16(self.obstacle_m * 1000),
                            _u16(self.battery_low_v * 1000))

    @classmethod
    def unpack(cls, b: bytes) -> ConfigLimits:
        g, t, h, o, bv = cls._S.unpack(b)
        return cls(g / 100, t / 10, h / 10, o / 1000, bv / 1000)


@dataclass
class Ack:
    _S = struct.Struct("<BBB")
    acked_type: int = 0
    acked_seq: int = 0
    status: int = 0  # 0 ok, 1 rejected (e.g. motion while e-stopped), 2 bad payload

    def pack(self) -> bytes:
        return self._S.pack(self.acked_type, self.acked_seq, self.status)

    @classmethod
    def unpack(cls, b: bytes) -> Ack:
        return cls(*cls._S.unpack(b))


@dataclass
class Estop:
    _S = struct.Struct("<B")
    engage: bool = True

    def pack(self) -> bytes:
        return self._S.pack(1 if self.engage else 0)

    @classmethod
    def unpack(cls, b: bytes) -> Estop:
        return cls(bool(cls._S.unpack(b)[0]))


@dataclass
class Keepalive:
    def pack(self) -> bytes:
        return b""

    @classmethod
    def unpack(cls, b: bytes) -> Keepalive:
        if b:
            raise struct.error("keepalive carries no payload")
        return cls()


@dataclass
class ProbeReport:
    """One ultrasonic thickness sample of the wall climber's probe (the MCU's time
    and the thickness in µm; ``NO_ECHO`` when the probe has no coupling)."""

    _S = struct.Struct("<IH")
    NO_ECHO = 0xFFFF
    mcu_time_ms: int = 0
    thickness_um: int = NO_ECHO

    @property
    def thickness_mm(self) -> float | None:
        return None if self.thickness_um == self.NO_ECHO else self.thickness_um / 1000

    def pack(self) -> bytes:
        return self._S.pack(self.mcu_time_ms & 0xFFFFFFFF, self.thickness_um & 0xFFFF)

    @classmethod
    def unpack(cls, b: bytes) -> ProbeReport:
        return cls(*cls._S.unpack(b))


@dataclass
class WheelReport:
    """The four-wheel-steer base's wheels (FL, FR, RL, RR): steering angles (wire:
    1e-4 rad), rolling speeds (mm/s), drive encoder counts, and the steering mode
    the board runs (``MODES``)."""

    _S = struct.Struct("<IB4h4h4i")
    MODES = ("stopped", "front", "counter", "crab", "pivot")
    mcu_time_ms: int = 0
    mode: int = 0
    angles_rad: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
    speeds_mps: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
    ticks: tuple[int, ...] = (0, 0, 0, 0)

    def pack(self) -> bytes:
        return self._S.pack(self.mcu_time_ms & 0xFFFFFFFF, self.mode & 0xFF,
                            *(_i16(a * 10000) for a in self.angles_rad),
                            *(_i16(v * 1000) for v in self.speeds_mps),
                            *(_i32(t) for t in self.ticks))

    @classmethod
    def unpack(cls, b: bytes) -> WheelReport:
        v = cls._S.unpack(b)
        return cls(v[0], v[1], tuple(a / 10000 for a in v[2:6]),
                   tuple(s / 1000 for s in v[6:10]), tuple(v[10:14]))


PAYLOADS: dict[int, type] = {
    McuType.SENSOR_REPORT: SensorReport, McuType.ACK: Ack, McuType.MOTOR_CMD: MotorCmd,
    McuType.KEEPALIVE: Keepalive, McuType.CONFIG: ConfigLimits, McuType.ESTOP: Estop,
    McuType.PROBE_REPORT: ProbeReport, McuType.WHEEL_REPORT: WheelReport,
    McuType.BODY_CMD: BodyCmd,
}
TYPE_OF: dict[type, int] = {v: k for k, v in PAYLOADS.items()}
# every frame type has a fixed payload size, so a false sync word is rejected at
# once from its header instead of stalling the decoder while it waits for bytes
PAYLOAD_LEN: dict[int, int] = {k: (v._S.size if hasattr(v, "_S") else 0)
                               for k, v in PAYLOADS.items()}


def _wrap_pi(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _clamp(v: float, lo: int, hi: int) -> int:
    return max(lo, min(hi, int(round(v))))


def _u16(v: float) -> int:
    return _clamp(v, 0, 0xFFFF)


def _i16(v: float) -> int:
    return _clamp(v, -0x8000, 0x7FFF)


def _i32(v: int) -> int:
    return ((int(v) + 0x80000000) & 0xFFFFFFFF) - 0x80000000


# --------------------------------------------------------------------------- codec


class McuEncoder:
    """Numbers outgoing frames (seq wraps at 256)."""

    def __init__(self) -> None:
        self.seq = 0

    def encode(self, msg) -> bytes:
        seq = self.seq
        self.seq = (self.seq + 1) & 0xFF
        return encode_frame(TYPE_OF[type(msg)], seq, msg.pack())

    def encode_with_seq(self, msg) -> tuple[int, bytes]:
        seq = self.seq
        return seq, self.encode(msg)


@dataclass
class McuFrame:
    msg_type: int
    seq: int
    message: object


@dataclass
class McuDecoderStats:
    frames: int = 0
    bytes_in: int = 0
    garbage_bytes: int = 0
    bad_crc: int = 0
    unknown_type: int = 0
    bad_length: int = 0
    bad_payload: int = 0

    @property
    def dropped(self) -> int:
        return self.bad_crc + self.unknown_type + self.bad_length + self.bad_payload

    def as_dict(self) -> dict[str, int]:
        d = dict(self.__dict__)
        d["dropped"] = self.dropped
        return d


class McuDecoder:
    """Incremental decoder; a bad frame is counted and the search resumes one byte on."""

    def __init__(self) -> None:
        self.stats = McuDecoderStats()
        self._buf = bytearray()
        self.last_error = ""

    def feed(self, data: bytes) -> list[McuFrame]:
        self.stats.bytes_in += len(data)
        buf = self._buf
        buf += data
        out: list[McuFrame] = []
        while True:
            i = buf.find(SYNC)
            if i < 0:
                keep = 1 if buf[-1:] == SYNC[:1] else 0
                self.stats.garbage_bytes += len(buf) - keep
                del buf[:len(buf) - keep]
                return out
            if i:
                self.stats.garbage_bytes += i
                del buf[:i]
            if len(buf) < _HEAD.size:
                return out
            _sync, mtype, seq, length = _HEAD.unpack_from(buf)
            want = PAYLOAD_LEN.get(mtype)
            if want is None or want != length:
                # a false sync word, a corrupt header, or a type this side does not know
                if want is None:
                    self.stats.unknown_type += 1
                    self.last_error = f"unknown MCU frame type 0x{mtype:02x}"
                else:
                    self.stats.bad_length += 1
                    self.last_error = f"type 0x{mtype:02x} with length {length} (want {want})"
                del buf[:1]
                continue
            total = _HEAD.size + length + _CRC.size
            if len(buf) < total:
                return out
            (crc,) = _CRC.unpack_from(buf, _HEAD.size + length)
            if crc16(bytes(buf[2:_HEAD.size + length])) != crc:
                self.stats.bad_crc += 1
                self.last_error = "crc mismatch"
                del buf[:1]
                continue
            payload = bytes(buf[_HEAD.size:_HEAD.size + length])
            del buf[:total]
            cls = PAYLOADS[mtype]
            try:
                msg = cls.unpack(payload)
            except struct.error as e:
                self.stats.bad_payload += 1
                self.last_error = f"{cls.__name__}: {e}"
                continue
            self.stats.frames += 1
            out.append(McuFrame(mtype, seq, msg))
