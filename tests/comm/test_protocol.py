"""The wire codec: round trips, any chunking, resynchronisation, and what it drops."""

import os
import random
import struct

import numpy as np
import pytest

from app.comm import protocol as P


def all_messages():
    return [
        P.Heartbeat(P.Heartbeat.ROLE_ROBOT, 123456789, 4567, 42),
        P.Telemetry(mcu_time_ms=1000, gas_lel_pct=3.25, temp_c=21.5, humidity_pct=55.0,
                    obstacle_left_m=1.0, obstacle_front_m=2.5, obstacle_right_m=3.0,
                    battery_v=24.1, wheel_left_mps=0.5, wheel_right_mps=0.25,
                    yaw_rate_rps=-0.1, cmd_linear_mps=0.5, cmd_angular_rps=0.0,
                    alarm_flags=int(P.AlarmFlag.GAS_HIGH | P.AlarmFlag.BATTERY_LOW),
                    mode=P.RobotMode.TELEOP),
        P.VideoFrame(7, 1_700_000_000_000_000, 640, 480, 0.25, b"\xff\xd8" + os.urandom(5000)),
        P.LidarScan(99, -3.14159, 0.0174533, 12.0,
                    np.linspace(0.5, 12.0, 360).astype(np.float32)),
        P.Pose(12.5, -3.25, 1.5, 0.4, -0.2),
        P.Event("warning", "failsafe_stop", "motors stopped", {"reason": "link"}),
        P.Command("drive", {"linear_mps": 0.3, "angular_rps": -0.2}),
        P.CommandAck(17, False, "e-stop latched"),
        P.MapImage(0.1, -2.5, -1.0, 800, 600, b"\x89PNG\r\n\x1a\n" + os.urandom(300)),
        P.Path(P.Path.GLOBAL, np.array([[0, 0], [1.5, 2.0], [3.0, 2.5]], np.float32)),
        P.PatrolStatus("driving", "east tanks", 1,
                       [{"name": "PT-101", "kind": "meter", "x_m": 3.0, "y_m": 4.0,
                         "state": "done"}], "", 0.25, "apf"),
        P.Obstacles(np.array([[1, 2, 0.5, 0, 0.3], [4, 5, 0, -0.2, 0.4]], np.float32)),
        *wall_messages(),
        *fws_messages(),
    ]


def fws_messages():
    from app.comm import fws_protocol as F

    return [F.WheelState(1234, 2, (0.25, 0.125, -0.25, -0.125), (0.5, 0.75, 0.5, 0.75)),
            F.TebPlan(False, np.array([[0, 0, 0], [0.5, 0.25, 0.5], [1, 0.5, 0.5]],
                                      np.float32), np.array([0.25, 0.5], np.float32))]


def wall_messages():
    from app.comm import wall_protocol as W

    blocked = np.zeros((4, 6), bool)
    blocked[1, 2] = True
    return [W.WallInfo.build("t", 0.1, blocked, np.where(blocked, -1, 0), [0],
                             [(0, 0), (0, 1), (1, 1)], 10.0, 8.0, [[0.0, 0.2, 0.6, 0.2]]),
            W.CoverageProgress.build(~blocked, 23, 25, 3, 30, W.CoverageState.RUNNING),
            W.ProbeReadings(np.array([[0.15, 0.05, 9.5]], np.float32)),
            W.WallPose(1.25, 0.5, 0.25, 0.1, -0.05, 0.02)]


def same(a, b):
    assert type(a) is type(b)
    for k, v in a.__dict__.items():
        if k == "body":  # a decoded command keeps the JSON bytes it arrived as
            continue
        w = getattr(b, k)
        if isinstance(v, np.ndarray):
            np.testing.assert_array_equal(v, w)
        elif isinstance(v, float):
            assert w == pytest.approx(v, rel=1e-6)
        else:
            assert v == w, k


def test_every_message_type_round_trips_with_header_fields():
    enc = P.FrameEncoder(first_seq=5)
    dec = P.FrameDecoder()
    msgs = all_messages()
    assert {m.TYPE for m in msgs} == set(P.MsgType)
    data = b"".join(enc.encode(m, timestamp_us=1000 + i) for i, m in enumerate(msgs))
    frames = dec.feed(data)
    assert [f.msg_type for f in frames] == [m.TYPE for m in msgs]
    assert [f.seq for f in frames] == list(range(5, 5 + len(msgs)))
    assert [f.timestamp_us for f in frames] == [1000 + i for i in range(len(msgs))]
    for m, f in zip(msgs, frames, strict=True):
        same(m, f.message)
    assert dec.stats.dropped == 0 and dec.stats.garbage_bytes == 0
    assert dec.buffered == 0


def golden_messages():
    """One message of each of the codec's own types, with exact values (no random bytes)."""
    return [
        P.Heartbeat(P.Heartbeat.ROLE_ROBOT, 123456789, 4567, 42),
        P.Telemetry(1000, 3.25, 21.5, 55.0, 1.0, 2.5, 3.0, 24.125, 0.5, 0.25, -0.125, 0.5, 0.0,
                    int(P.AlarmFlag.GAS_HIGH | P.AlarmFlag.BATTERY_LOW), P.RobotMode.TELEOP, 77),
        P.VideoFrame(7, 1_700_000_000_000_000, 640, 480, 0.25, b"\xff\xd8jpeg"),
        P.LidarScan(99, -1.5, 0.5, 12.0, np.array([0.5, 1.0, np.inf], np.float32)),
        P.Pose(12.5, -3.25, 1.5, 0.375, -0.25),
        P.Pose(1.0, 2.0, 0.5, 0.0, 0.0, 0.01, 0.0, 0.02, 0.001, 0.875, 0.05,
               P.Pose.STATUS_TRACKING),
        P.Event("warning", "failsafe_stop", "motors stopped", {"reason": "link"}),
        P.Command("drive", {"linear_mps": 0.25, "angular_rps": -0.5}),
        P.CommandAck(17, False, "e-stop latched"),
        P.MapImage(0.125, -2.5, -1.0, 4, 3, b"\x89PNG"),
        P.Path(P.Path.GLOBAL, np.array([[0, 0], [1.5, 2.0]], np.float32)),
        P.PatrolStatus("driving", "east", 1, [{"name": "PT-101", "state": "done"}], "", 0.25,
                       "apf"),
        P.Obstacles(np.array([[1, 2, 0.5, 0, 0.25]], np.float32)),
    ]


# The frames golden_messages() encodes to (FrameEncoder(first_seq=0xFFFFFFFE), timestamps
# 1_700_000_000_000_000 + i): the wire format robots and desks in the field speak. A
# change here is a change of the protocol, which needs a new PROTOCOL_VERSION.
GOLDEN_FRAMES = [
    ("Heartbeat",
     "a55a010115000000feffffff00401e18240a060055190115cd5b0700000000d711000000"
     "0000002a000000f5fa6e20"),
    ("Telemetry",
     "a55a01023b000000ffffffff01401e18240a0600fffbe8030000000050400000ac410000"
     "5c420000803f00002040000040400000c1410000003f0000803e000000be0000003f0000"
     "00001100014d000000b5f171bc"),
    ("VideoFrame",
     "a55a01031a0000000000000002401e18240a060098a80700000000401e18240a06008002"
     "e0010000803effd86a706567be9ca2d8"),
    ("LidarScan",
     "a55a0104220000000100000003401e18240a06000bea63000000000000000000c0bf0000"
     "003f0000404103000000003f0000803f0000807f18b835c3"),
    ("Pose",
     "a55a0105200000000200000004401e18240a060007780000000000002940000000000000"
     "0ac0000000000000f83f0000c03e000080be0c3aa2b4"),
    ("Pose",
     "a55a0105390000000300000005401e18240a06000aa6000000000000f03f000000000000"
     "0040000000000000e03f00000000000000000ad7233c000000000ad7a33c6f12833a0000"
     "603fcdcc4c3d01e236b3af"),
    ("Event",
     "a55a01065b0000000400000006401e18240a060047dd7b226c6576656c223a227761726e"
     "696e67222c22636f6465223a226661696c736166655f73746f70222c2274657874223a22"
     "6d6f746f72732073746f70706564222c2264617461223a7b22726561736f6e223a226c69"
     "6e6b227d7d6c31e9ab"),
    ("Command",
     "a55a01073e0000000500000007401e18240a0600c96b7b226e616d65223a226472697665"
     "222c2261726773223a7b226c696e6561725f6d7073223a302e32352c22616e67756c6172"
     "5f727073223a2d302e357d7db38c8a7a"),
    ("CommandAck",
     "a55a0108130000000600000008401e18240a06004d3d1100000000652d73746f70206c61"
     "74636865643ad15fe4"),
    ("MapImage",
     "a55a0109200000000700000009401e18240a06005ae40000003e00000000000004c00000"
     "00000000f0bf040000000300000089504e4744ca3349"),
    ("Path",
     "a55a010a15000000080000000a401e18240a060002430002000000000000000000000000"
     "00c03f000000400a32b194"),
    ("PatrolStatus",
     "a55a010b8a000000090000000b401e18240a060027457b227374617465223a2264726976"
     "696e67222c22726f757465223a2265617374222c22696e646578223a312c22706f696e74"
     "73223a5b7b226e616d65223a2250542d313031222c227374617465223a22646f6e65227d"
     "5d2c22726561736f6e223a22222c2270726f6772657373223a302e32352c226c6f63616c"
     "5f706c616e6e6572223a22617066227d54bd97f5"),
    ("Obstacles",
     "a55a010c180000000a0000000c401e18240a06001c9e010000000000803f000000400000"
     "003f000000000000803e91af9ab8"),
]


def test_every_message_encodes_to_the_pinned_wire_bytes_and_back():
    enc = P.FrameEncoder(first_seq=0xFFFFFFFE)
    msgs = golden_messages()
    assert len(msgs) == len(GOLDEN_FRAMES)
    assert {m.TYPE for m in msgs} == set(P.MESSAGE_CLASSES) - P.WALL_TYPES - P.FWS_TYPES
    for i, (m, (name, frame_hex)) in enumerate(zip(msgs, GOLDEN_FRAMES, strict=True)):
        assert type(m).__name__ == name
        wire = enc.encode(m, timestamp_us=1_700_000_000_000_000 + i)
        assert wire.hex() == frame_hex, name
        (frame,) = P.FrameDecoder().feed(bytes.fromhex(frame_hex))
        assert frame.seq == (0xFFFFFFFE + i) & 0xFFFFFFFF
        same(m, frame.message)


def test_one_byte_chunking_and_random_chunking():
    enc = P.FrameEncoder()
    msgs = all_messages()
    data = b"".join(enc.encode(m) for m in msgs)
    dec = P.FrameDecoder()
    got = []
    for i in range(len(data)):
        got += dec.feed(data[i:i + 1])
    assert len(got) == len(msgs)
    rng = random.Random(3)
    dec = P.FrameDecoder()
    got, i = [], 0
    while i < len(data):
        n = rng.randint(1, 700)
        got += dec.feed(data[i:i + n])
        i += n
    assert [f.msg_type for f in got] == [m.TYPE for m in msgs]


def test_garbage_between_frames_is_skipped_and_counted():
    enc = P.FrameEncoder()
    rng = random.Random(7)
    parts, garbage = [], 0
    for m in all_messages():
        g = bytes(rng.randrange(256) for _ in range(rng.randint(1, 50))).replace(P.MAGIC, b"")
        garbage += len(g)
        parts += [g, enc.encode(m)]
    frames = P.FrameDecoder().feed(b"".join(parts))
    assert len(frames) == len(all_messages())
    dec = P.FrameDecoder()
    dec.feed(b"".join(parts))
    assert dec.stats.garbage_bytes == garbage


def test_bad_checksum_is_dropped_and_next_frame_still_decodes():
    enc = P.FrameEncoder()
    bad = bytearray(enc.encode(P.Pose(1, 2, 3, 0, 0)))
    bad[P.HEADER_SIZE + 3] ^= 0xFF  # flip a payload byte
    good = enc.encode(P.Pose(4, 5, 6, 0, 0))
    dec = P.FrameDecoder()
    frames = dec.feed(bytes(bad) + good)
    assert len(frames) == 1 and frames[0].message.x_m == 4
    assert dec.stats.bad_checksum == 1


def test_corrupt_header_is_rejected_without_waiting_for_its_length():
    enc = P.FrameEncoder()
    bad = bytearray(enc.encode(P.Pose(1, 2, 3, 0, 0)))
    bad[5] ^= 0x40  # length field: the header CRC no longer matches
    good = enc.encode(P.Pose(4, 5, 6, 0, 0))
    dec = P.FrameDecoder()
    frames = dec.feed(bytes(bad) + good)
    assert [f.message.x_m for f in frames] == [4]
    assert dec.stats.bad_header == 1


def test_oversize_length_is_dropped_and_counted():
    enc = P.FrameEncoder()
    frame = enc.encode_raw(int(P.MsgType.EVENT), b"{}")
    dec = P.FrameDecoder(max_payload=1)
    dec.feed(frame + enc.encode_raw(int(P.MsgType.EVENT), b"{ }"))
    assert dec.stats.bad_length == 2
    with pytest.raises(ValueError):
        enc.encode_raw(int(P.MsgType.EVENT), b"x" * (P.MAX_PAYLOAD + 1))


def test_a_well_formed_header_with_huge_length_is_rejected_at_once():
    head = struct.pack("<2sBBIIQ", P.MAGIC, P.PROTOCOL_VERSION, int(P.MsgType.EVENT),
                       P.MAX_PAYLOAD + 10, 0, 0)
    import binascii

    head += struct.pack("<H", binascii.crc_hqx(head[2:], 0xFFFF))
    dec = P.FrameDecoder()
    frames = dec.feed(head + P.FrameEncoder().encode(P.Pose(7, 0, 0, 0, 0)))
    assert [f.message.x_m for f in frames] == [7]
    assert dec.stats.bad_length == 1


def test_truncated_frame_waits_then_completes_or_is_superseded():
    enc = P.FrameEncoder()
    f1 = enc.encode(P.Pose(1, 0, 0, 0, 0))
    dec = P.FrameDecoder()
    assert dec.feed(f1[:-3]) == []
    assert dec.buffered == len(f1) - 3
    assert len(dec.feed(f1[-3:])) == 1
    # a frame cut short and followed by a whole one: the cut one fails its
    # checksum, the next is still found
    f2 = enc.encode(P.Pose(2, 0, 0, 0, 0))
    f3 = enc.encode(P.Pose(3, 0, 0, 0, 0))
    frames = dec.feed(f2[:-6] + f3)
    assert [f.message.x_m for f in frames] == [3]
    assert dec.stats.bad_checksum >= 1


def test_unknown_type_and_bad_payload_are_counted():
    enc = P.FrameEncoder()
    dec = P.FrameDecoder()
    data = (enc.encode_raw(200, b"abc") + enc.encode_raw(int(P.MsgType.POSE), b"short")
            + enc.encode_raw(int(P.MsgType.COMMAND), b"not json")
            + enc.encode_raw(int(P.MsgType.VIDEO_FRAME), b"\x00" * 30)
            + enc.encode(P.Heartbeat()))
    frames = dec.feed(data)
    assert [f.msg_type for f in frames] == [P.MsgType.HEARTBEAT]
    assert dec.stats.unknown_type == 1
    assert dec.stats.bad_payload == 3
    assert dec.stats.dropped == 4


def test_bad_version_is_counted():
    enc = P.FrameEncoder()
    f = bytearray(enc.encode(P.Heartbeat()))
    f[2] = 99
    import binascii

    f[20:22] = struct.pack("<H", binascii.crc_hqx(bytes(f[2:20]), 0xFFFF))
    dec = P.FrameDecoder()
    assert dec.feed(bytes(f)) == []
    assert dec.stats.bad_version == 1


def test_sequence_wraps():
    enc = P.FrameEncoder(first_seq=2**32 - 1)
    frames = P.FrameDecoder().feed(enc.encode(P.Heartbeat()) + enc.encode(P.Heartbeat()))
    assert [f.seq for f in frames] == [2**32 - 1, 0]


def test_random_bytes_never_raise():
    rng = random.Random(11)
    dec = P.FrameDecoder()
    good = P.FrameEncoder().encode(P.Pose(9, 0, 0, 0, 0))
    found = 0
    for _ in range(300):
        blob = bytes(rng.randrange(256) for _ in range(rng.randint(0, 200)))
        if rng.random() < 0.3:
            blob = P.MAGIC + blob  # provoke header parsing
        found += len(dec.feed(blob))
        found += len(dec.feed(good))
    assert found == 300


def test_parse_hostport():
    assert P.parse_hostport("127.0.0.1:5600") == ("127.0.0.1", 5600)
    assert P.parse_hostport("[::1]:80") == ("::1", 80)
    assert P.parse_hostport("robot.local:0", allow_port_zero=True) == ("robot.local", 0)
    for bad in ("nohost", ":80", "h:0", "h:70000", "h:x"):
        with pytest.raises(ValueError, match="HOST:PORT"):
            P.parse_hostport(bad)
