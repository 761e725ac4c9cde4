"""The climber's relay-side estimate with a gyro whose bias it never saw at rest:
the heading it believes stays within its own σθ of the truth (docs/climber.md,
"The lean of the first lanes: the gyro's bias")."""

import math

import numpy as np

from sim_robot.climber import ClimberBody, ClimberParams, ClimberState
from sim_robot.climber.accelerometer import WallAccelerometer
from sim_robot.climber.odometry import ClimberOdometry


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def test_a_gyro_bias_never_seen_at_rest_leaves_an_honest_heading():
    params = ClimberParams()
    body = ClimberBody(params, ClimberState(3.0, 0.3, math.pi / 2), seed=4)
    rng = np.random.default_rng(7)
    acc = WallAccelerometer(rng)
    odom = ClimberOdometry(params, 3.0, 0.3, math.pi / 2)
    ticks_per_m = odom.ticks_per_m
    gyro_bias = 0.01  # rad/s: the board's gyro, never standing still before the first move
    dt, el, er = 0.05, 0.0, 0.0
    # up a lane, a half turn in place, down the lane, a half turn, up again
    legs = [(0.08, 0.0, 30.0), (0.0, 0.4, math.pi / 0.4), (0.08, 0.0, 30.0),
            (0.0, -0.4, math.pi / 0.4), (0.08, 0.0, 30.0)]
    worst, t = 0.0, 0.0
    for v, w, dur in legs:
        for _ in range(int(round(dur / dt))):
            vl, vr, w_true = body.step(v, w, dt)
            el, er = el + vl * dt, er + vr * dt
            fx, fy = acc.sample(dt, body.s.theta_rad, body.v_true_mps, w_true)
            gyro = w_true + gyro_bias + 0.004 * rng.standard_normal()
            head = acc.heading(dt, fx, fy, (vl + vr) / 2, gyro)
            t += dt
            odom.update(int(round(t * 1000)), int(el * ticks_per_m), int(er * ticks_per_m),
                        gyro, head)
            if t > 5.0:
                err = abs(_wrap(odom.theta - body.s.theta_rad))
                sth = math.sqrt(odom.ekf.covariance[2, 2])
                worst = max(worst, err / max(sth, 1e-6))
    assert worst < 4.0  # never further off than the filter's own σθ allows
    assert abs(_wrap(odom.theta - body.s.theta_rad)) < 0.005
