import random

import pytest

from sim_robot.mcu_link import (
    Ack,
    ConfigLimits,
    Estop,
    Keepalive,
    McuDecoder,
    McuEncoder,
    McuType,
    MotorCmd,
    SensorReport,
    encode_frame,
)

REPORT = SensorReport(123456, 12.34, -5.2, 67.8, 0.25, 1.5, 4.0, 11.95, 0.31, -0.2, 0.123,
                      -42, 2**31 - 5, 0.3, -0.5, 0b101, 1, -3.1)
MESSAGES = [REPORT, MotorCmd(0.3, -0.25), Keepalive(), ConfigLimits(10, 45, 90, 0.35, 22.0),
            Estop(True), Estop(False), Ack(McuType.MOTOR_CMD, 7, 1)]


def _approx_equal(a, b):
    for k, v in a.__dict__.items():
        w = getattr(b, k)
        if isinstance(v, float):
            assert w == pytest.approx(v, abs=2e-3), k
        else:
            assert w == v, k


def test_round_trip_every_type():
    enc, dec = McuEncoder(), McuDecoder()
    data = b"".join(enc.encode(m) for m in MESSAGES)
    frames = dec.feed(data)
    assert [type(f.message) for f in frames] == [type(m) for m in MESSAGES]
    assert [f.seq for f in frames] == list(range(len(MESSAGES)))
    for f, m in zip(frames, MESSAGES, strict=True):
        _approx_equal(m, f.message)
    assert dec.stats.dropped == 0 and dec.stats.garbage_bytes == 0


def test_one_byte_chunks():
    enc, dec = McuEncoder(), McuDecoder()
    data = b"".join(enc.encode(m) for m in MESSAGES * 3)
    out = []
    for i in range(len(data)):
        out += dec.feed(data[i:i + 1])
    assert len(out) == len(MESSAGES) * 3


def test_garbage_is_skipped_and_counted():
    enc, dec = McuEncoder(), McuDecoder()
    rnd = random.Random(5)
    junk = bytes(rnd.randrange(256) for _ in range(300)).replace(b"\xaa", b"\x00")
    data = junk + enc.encode(REPORT) + b"\xaa\xaa\x55" + enc.encode(MotorCmd(0.1, 0))
    frames = dec.feed(data)
    assert [type(f.message) for f in frames] == [SensorReport, MotorCmd]
    assert dec.stats.garbage_bytes >= 300


def test_bad_checksum_dropped_then_resync():
    enc, dec = McuEncoder(), McuDecoder()
    bad = bytearray(enc.encode(REPORT))
    bad[10] ^= 0x40
    good = enc.encode(MotorCmd(0.2, 0.1))
    frames = dec.feed(bytes(bad) + good)
    assert [type(f.message) for f in frames] == [MotorCmd]
    assert dec.stats.bad_crc == 1 and dec.stats.dropped == 1


def test_unknown_type_and_wrong_length_counted():
    dec = McuDecoder()
    frames = dec.feed(encode_frame(0x7E, 0, b"xy") + encode_frame(McuType.MOTOR_CMD, 1, b"\x01")
                      + encode_frame(McuType.KEEPALIVE, 2))
    assert [type(f.message) for f in frames] == [Keepalive]
    assert dec.stats.unknown_type >= 1 and dec.stats.bad_length >= 1


def test_values_saturate_instead_of_overflowing():
    b = MotorCmd(100.0, -100.0).pack()
    m = MotorCmd.unpack(b)
    assert m.linear_mps == pytest.approx(32.767) and m.angular_rps == pytest.approx(-32.768)


def test_gas_is_signed_on_the_wire_and_old_reports_read_the_same():
    """A faulty sensor's negative reading crosses the serial link (i16, 0.01 %LEL); a
    report from a board that sent the field unsigned (u16) decodes to the same value
    over the sensor's whole range (0..110 %LEL), so the change needs no new version."""
    import struct
    enc, dec = McuEncoder(), McuDecoder()
    for gas in (-8.25, -25.0, 0.0, 55.5, 110.0):
        (f,) = dec.feed(enc.encode(SensorReport(1, gas_lel_pct=gas)))
        assert f.message.gas_lel_pct == pytest.approx(gas, abs=0.006)
    old = struct.Struct("<IHhHHHHHhhhiihhHBh")  # the unsigned layout, same length
    payload = old.pack(7, 11000, *([0] * 16))
    assert SensorReport.unpack(payload).gas_lel_pct == pytest.approx(110.0)
