"""The 4WS base's actuators: servos settle, then the body follows the
commanded arc; motors wait for their servos; encoders count distance; bad
commands are refused and counted."""

import math

import numpy as np
import pytest

from app.core.kinematics import Mode, WheelCommand, integrate_pose, mode_twist, wheel_commands
from sim_robot.fws_base import FwsBase


def test_after_the_servos_settle_the_body_follows_the_arc():
    base = FwsBase()
    tw = mode_twist(base.geom, Mode.COUNTER, 0.6, math.radians(20))
    assert base.command(wheel_commands(base.geom, tw))
    for _ in range(200):  # 2 s: servos and motors settle
        base.step(0.01)
    assert np.allclose(base.angles, base.target_angles)
    assert np.allclose(base.speeds, base.target_speeds)
    assert base.slip_mps < 1e-9
    start = base.pose
    for _ in range(100):
        base.step(0.01)
    want = integrate_pose(start, tw, 1.0)
    assert base.pose == pytest.approx(want, abs=1e-9)


def test_motors_wait_for_the_servos_before_a_pivot():
    base = FwsBase()
    base.command(wheel_commands(base.geom, mode_twist(base.geom, Mode.PIVOT, 0.8)))
    base.step(0.05)  # servos 0.15 rad into a 0.88 rad swing: far from aligned
    assert np.all(base.speeds == 0.0)
    assert base.pose == pytest.approx((0.0, 0.0, 0.0))
    for _ in range(300):
        base.step(0.01)
    assert np.all(np.abs(base.speeds) > 0.3)
    assert base.pose[0] == pytest.approx(0.0, abs=1e-6)  # turned on the spot
    assert base.pose[1] == pytest.approx(0.0, abs=1e-6)
    assert abs(base.pose[2]) > 0.5


def test_encoders_count_the_distance():
    base = FwsBase()
    base.command(WheelCommand((0.0,) * 4, (0.5,) * 4))
    for _ in range(400):
        base.step(0.01)
    dist = base.pose[0]
    revs = base.ticks / base.act.ticks_per_rev
    assert np.allclose(revs * 2 * math.pi * base.act.wheel_radius_m, dist)
    assert dist > 1.5


def test_bad_commands_are_refused_and_counted():
    base = FwsBase()
    assert not base.command(WheelCommand((0.0, 0.0, 0.0, float("nan")), (0.1,) * 4))
    assert not base.command(WheelCommand((0.0,) * 3, (0.1,) * 3))
    assert base.rejected == 2
    assert np.all(base.target_speeds == 0.0)
    state = base.wheel_state()
    assert set(state) == {"front_left", "front_right", "rear_left", "rear_right"}
