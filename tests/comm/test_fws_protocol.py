"""The 4WS robot's messages (types 24–25) and its MCU wheel report: round trips,
and bad payloads refused and counted rather than raised."""

import struct

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm.fws_protocol import MAX_TEB_POSES, TebPlan, WheelState
from sim_robot.mcu_link import McuDecoder, McuEncoder, McuType, WheelReport


def test_wheel_state_round_trip_and_mode_names():
    w = WheelState(7, 4, (0.5, -0.5, -0.5, 0.5), (-0.25, 0.25, -0.25, 0.25))
    back = WheelState.unpack(w.pack())
    assert back == w and back.mode_name == "pivot"
    assert WheelState(mode=2).mode_name == "counter"


@pytest.mark.parametrize("payload, why", [
    (WheelState._S.pack(1, 0, float("nan"), 0, 0, 0, 0, 0, 0, 0), "not finite"),
    (WheelState._S.pack(1, 9, 0, 0, 0, 0, 0, 0, 0, 0), "mode 9"),
    (b"\x00" * 5, "bytes"),
])
def test_bad_wheel_state_is_refused(payload, why):
    with pytest.raises(P.ProtocolError, match=why):
        WheelState.unpack(payload)


def test_teb_plan_round_trip_and_limits():
    poses = np.array([[0, 0, 0], [1, 0, 0.5], [2, 1, 1.0]], np.float32)
    t = TebPlan.unpack(TebPlan(True, poses, np.array([0.5, 0.25], np.float32)).pack())
    assert t.turning_in_place and np.array_equal(t.poses, poses)
    assert np.array_equal(t.dts_s, [0.5, 0.25])
    assert len(TebPlan.unpack(TebPlan().pack()).poses) == 0
    with pytest.raises(ValueError, match="intervals"):
        TebPlan(False, poses, np.zeros(1, np.float32)).pack()
    with pytest.raises(P.ProtocolError, match="exceeds"):
        TebPlan.unpack(struct.pack("<BI", 0, MAX_TEB_POSES + 1))
    with pytest.raises(P.ProtocolError, match="bytes"):
        TebPlan.unpack(struct.pack("<BI", 0, 3) + b"\x00" * 10)
    bad = TebPlan(False, poses, np.array([np.inf, 0.25], np.float32)).pack()
    with pytest.raises(P.ProtocolError, match="not finite"):
        TebPlan.unpack(bad)


def test_decoder_counts_a_bad_fws_payload_and_carries_on():
    good = WheelState(1, 2, (0.0,) * 4, (0.5,) * 4)
    bad = P.FrameEncoder().encode_raw(int(P.MsgType.WHEEL_STATE), b"\x01\x02")
    dec = P.FrameDecoder()
    frames = dec.feed(bad + P.encode(good, seq=3))
    assert [f.message for f in frames] == [good]
    assert dec.stats.bad_payload == 1 and "WheelState" in dec.last_error


def test_mcu_wheel_report_round_trip_over_the_serial_framing():
    rep = WheelReport(123456, 4, (0.8761, -0.8761, -0.8761, 0.8761), (-0.469, 0.469, -0.469,
                                                                        0.469),
                      (100, -2**31, 2**31 - 1, 0))
    dec = McuDecoder()
    (fr,) = dec.feed(McuEncoder().encode(rep))
    assert fr.msg_type == McuType.WHEEL_REPORT
    m = fr.message
    assert m.mcu_time_ms == 123456 and m.mode == 4 and m.ticks == rep.ticks
    assert np.allclose(m.angles_rad, rep.angles_rad, atol=1e-4)
    assert np.allclose(m.speeds_mps, rep.speeds_mps, atol=1e-3)
