"""4WS kinematics (seed 004 §2.1): round trips, ICR, limits, modes, pose update."""

import math

import numpy as np
import pytest

from app.core.kinematics import (
    FwsGeometry,
    Mode,
    Twist,
    WheelCommand,
    bicycle_to_twist,
    body_twist,
    icr,
    integrate_pose,
    min_turn_radius,
    mode_twist,
    realise,
    select_mode,
    twist_to_bicycle,
    wheel_commands,
)
from app.core.kinematics.fws import limit_twist

G = FwsGeometry()


def test_wheels_to_twist_to_wheels_round_trip():
    rng = np.random.default_rng(3)
    lim = G.max_steer_rad
    twists = [bicycle_to_twist(G, rng.choice([-1, 1]) * rng.uniform(0.05, 1.0),
                               *rng.uniform(-lim, lim, 2)) for _ in range(200)]
    twists += [Twist(0.0, 0.0, w) for w in rng.uniform(-2, 2, 20)]
    for t in twists:
        cmd = wheel_commands(G, t)
        back, slip = body_twist(G, cmd)
        assert slip < 1e-9
        assert np.allclose(back.as_array(), t.as_array(), atol=1e-9)
        again = wheel_commands(G, back)
        assert np.allclose(again.angles_rad, cmd.angles_rad, atol=1e-9)
        assert np.allclose(again.speeds_mps, cmd.speeds_mps, atol=1e-9)


def test_inconsistent_wheels_show_slip():
    cmd = wheel_commands(G, Twist(0.5, 0.0, 0.4))
    bad = WheelCommand(cmd.angles_rad, (cmd.speeds_mps[0] + 0.2, *cmd.speeds_mps[1:]))
    _, slip = body_twist(G, bad)
    assert slip > 0.01
    with pytest.raises(ValueError):
        body_twist(G, WheelCommand((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)))


def test_each_wheel_rolls_about_the_icr():
    t = mode_twist(G, Mode.FRONT, 0.8, math.radians(20))
    cx, cy = icr(t)
    assert cx == pytest.approx(-G.wheelbase_m / 2)  # on the rear axle line
    cmd = wheel_commands(G, t)
    for (x, y), a, s in zip(G.wheel_xy, cmd.angles_rad, cmd.speeds_mps, strict=True):
        r = math.hypot(x - cx, y - cy)
        assert abs(s) == pytest.approx(abs(t.omega) * r)
        # wheel direction is perpendicular to the radius from the ICR
        assert math.cos(a) * (x - cx) + math.sin(a) * (y - cy) == pytest.approx(0, abs=1e-9)
    fl, fr, rl, rr = cmd.angles_rad
    assert fl > fr > 0  # left turn: inner (left) front steers more than the outer
    assert cmd.speeds_mps[0] < cmd.speeds_mps[1]  # inner wheel slower
    assert rl == pytest.approx(0) and rr == pytest.approx(0)


def test_bicycle_round_trip_and_modes():
    for df, dr in [(0.3, 0.0), (0.3, -0.3), (0.2, 0.2), (-0.1, 0.25)]:
        t = bicycle_to_twist(G, 0.7, df, dr)
        assert twist_to_bicycle(G, t) == pytest.approx((df, dr))
    counter = mode_twist(G, Mode.COUNTER, 1.0, 0.3)
    assert counter.vy == pytest.approx(0) and icr(counter)[0] == pytest.approx(0)
    crab = mode_twist(G, Mode.CRAB, 1.0, 0.3)
    assert crab.omega == pytest.approx(0) and icr(crab) is None
    cmd = wheel_commands(G, crab)
    assert np.allclose(cmd.angles_rad, 0.3) and np.allclose(cmd.speeds_mps, cmd.speeds_mps[0])
    pivot = wheel_commands(G, mode_twist(G, Mode.PIVOT, 1.0))
    assert np.allclose(np.abs(pivot.angles_rad), G.pivot_steer_rad)
    assert np.allclose(np.abs(pivot.speeds_mps), math.hypot(G.wheelbase_m, G.track_m) / 2)
    back, _ = body_twist(G, pivot)
    assert back.vx == pytest.approx(0, abs=1e-12) and back.omega == pytest.approx(1.0)


def test_counter_phase_turns_tighter_than_front_steer_and_respects_the_limit():
    rc, rf = min_turn_radius(G, Mode.COUNTER), min_turn_radius(G, Mode.FRONT)
    assert rc < rf
    t = limit_twist(G, Twist(0.5, 0.0, 5.0))  # far too tight: ω is clipped
    cmd = wheel_commands(G, t)
    assert max(abs(a) for a in cmd.angles_rad) == pytest.approx(G.max_steer_rad, abs=1e-6)
    assert 0.5 / t.omega == pytest.approx(rc, rel=1e-6)  # the limit is reached exactly
    # Front steer at the limit: the bicycle angle whose ICR puts the inner
    # front wheel at δmax; the centre then runs on the front-steer radius.
    ry = G.track_m / 2 + G.wheelbase_m / math.tan(G.max_steer_rad)
    t = mode_twist(G, Mode.FRONT, 0.5, math.atan(G.wheelbase_m / ry))
    cmd = wheel_commands(G, t)
    assert max(abs(a) for a in cmd.angles_rad) == pytest.approx(G.max_steer_rad)
    assert math.hypot(t.vx, t.vy) / t.omega == pytest.approx(rf)
    big = limit_twist(G, Twist(3.0, 0.0, 0.0))
    assert max(abs(s) for s in wheel_commands(G, big).speeds_mps) <= G.max_wheel_speed_mps + 1e-9


def test_servo_travel_is_enforced():
    with pytest.raises(ValueError, match="servo travel"):
        wheel_commands(G, Twist(0.0, 1.0, 0.0))  # pure sideways: 90° wheels


def test_pose_update_follows_the_arc():
    t = Twist(0.5, 0.0, 0.5)  # radius 1 about (0, 1)
    pose = (0.0, 0.0, 0.0)
    for _ in range(100):
        pose = integrate_pose(pose, t, math.pi / 100)  # a quarter turn in total
    assert pose == pytest.approx((1.0, 1.0, math.pi / 2))
    one = integrate_pose((0, 0, 0), t, math.pi)
    assert one[:2] == pytest.approx(pose[:2])
    crab = integrate_pose((1.0, 2.0, math.pi / 2), Twist(1.0, 1.0, 0.0), 1.0)
    assert crab == pytest.approx((0.0, 3.0, math.pi / 2))


def test_mode_selection_and_the_twist_each_mode_drives():
    assert select_mode(G, Twist(0.0, 0.0, 0.8)) is Mode.PIVOT
    assert select_mode(G, Twist(0.1, 0.08, 0.0)) is Mode.CRAB
    assert select_mode(G, Twist(0.6, 0.0, 0.1)) is Mode.FRONT  # a 6 m arc at speed
    assert select_mode(G, Twist(0.6, 0.0, 0.6)) is Mode.COUNTER  # 1 m: too tight for front steer
    assert select_mode(G, Twist(0.2, 0.0, 0.02)) is Mode.COUNTER  # gentle but slow
    front = realise(G, Mode.FRONT, Twist(0.6, 0.0, 0.1))
    cmd = wheel_commands(G, front)
    assert cmd.angles_rad[2:] == pytest.approx((0.0, 0.0), abs=1e-12)  # rear wheels straight
    assert front.vx == 0.6 and front.omega == 0.1  # same speed and yaw rate as asked
    crab = wheel_commands(G, realise(G, Mode.CRAB, Twist(0.1, 0.08, 0.3)))
    assert len(set(round(a, 12) for a in crab.angles_rad)) == 1  # all four at one angle
    assert body_twist(G, crab)[0].omega == pytest.approx(0.0, abs=1e-12)
