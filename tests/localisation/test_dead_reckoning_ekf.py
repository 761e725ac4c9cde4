import math

import numpy as np
import pytest

from app.core.localisation.dead_reckoning import (
    DeadReckoning,
    arcs_to_motion,
    integrate,
    pulse_to_arc_m,
)
from app.core.localisation.ekf import EkfNoise, OdometryEkf


def test_pulse_to_arc_is_pi_d_over_n_m():
    # 0.2 m wheel, 30:1 gearbox, 500 pulses per motor turn
    assert pulse_to_arc_m(0.2, 30, 500) == pytest.approx(math.pi * 0.2 / 15000)
    with pytest.raises(ValueError):
        pulse_to_arc_m(0.2, 0, 500)


def test_arcs_and_mid_angle_integration():
    ds, dth = arcs_to_motion(0.9, 1.1, 0.5)
    assert (ds, dth) == pytest.approx((1.0, 0.4))
    x, y, th = integrate((1.0, 2.0, 0.1), ds, dth)
    assert (x, y, th) == pytest.approx((1.0 + math.cos(0.3), 2.0 + math.sin(0.3), 0.5))


def test_dead_reckoning_counts_through_a_counter_wrap():
    dr = DeadReckoning(arc_per_pulse_m=0.001, track_m=0.5, counter_bits=16)
    dr.update(65000, 65000)
    dr.update(65000 + 1000 - 65536, 65000 + 1000 - 65536)  # both wrapped past 65535
    assert dr.pose == pytest.approx((1.0, 0.0, 0.0))


def test_ekf_predict_matches_a_hand_computed_step():
    ekf = OdometryEkf(x=1.0, y=2.0, theta=math.pi / 2)
    ekf._x[3:] = [0.5, 0.1, 0.2]  # v_x, v_y, ω_z
    p0 = ekf.covariance
    ekf.predict(0.1)
    # x += Δt(cosθ vx − sinθ vy) = 0.1·(0 − 0.1); y += Δt(sinθ vx + cosθ vy) = 0.1·0.5
    assert ekf.state[:3] == pytest.approx([0.99, 2.05, math.pi / 2 + 0.02])
    a = np.eye(6)
    a[0, 2], a[0, 3], a[0, 4] = -0.1 * (1 * 0.5 + 0 * 0.1), 0.0, -0.1
    a[1, 2], a[1, 3], a[1, 4] = 0.1 * (0 * 0.5 - 1 * 0.1), 0.1, 0.0
    a[2, 5] = 0.1
    assert OdometryEkf.jacobian(np.array([1, 2, math.pi / 2, 0.5, 0.1, 0.2]), 0.1) == \
        pytest.approx(a, abs=1e-12)
    assert ekf.covariance == pytest.approx(a @ p0 @ a.T + ekf.process_noise(0.1))


def test_ekf_gyro_update_matches_a_hand_computed_gain():
    ekf = OdometryEkf(noise=EkfNoise(gyro_yaw_rate_rps=0.1))
    ekf._p = np.eye(6) * 0.04  # σ² of ω_z = 0.04
    ekf.update_imu_yaw_rate(0.5)
    k = 0.04 / (0.04 + 0.01)  # K = P Hᵀ (H P Hᵀ + R)⁻¹ on the ω_z entry
    assert ekf.state[5] == pytest.approx(k * 0.5)
    assert ekf.covariance[5, 5] == pytest.approx((1 - k) * 0.04)
    assert ekf.covariance[0, 0] == pytest.approx(0.04)  # untouched, no correlation


def test_ekf_trusts_the_gyro_over_slipping_wheels_on_a_turn():
    ekf = OdometryEkf(track_m=0.5)
    for _ in range(100):  # the wheels say 0.4 rad/s, the body (gyro) turns 0.36 rad/s
        ekf.predict(0.02)
        ekf.update_encoders(-0.1 * 0.02, 0.1 * 0.02, 0.02)
        ekf.update_imu_yaw_rate(0.36)
    assert ekf.state[5] == pytest.approx(0.36, abs=0.005)
    assert ekf.pose[2] == pytest.approx(0.72, abs=0.02)
    with pytest.raises(ValueError):
        OdometryEkf().update_encoders(0.1, 0.1, 0.02)


def test_ekf_with_a_bias_state_learns_the_gyro_bias_while_driving_straight():
    plain, biased = OdometryEkf(track_m=0.5), OdometryEkf(track_m=0.5, gyro_bias=True)
    for _ in range(1500):  # 30 s straight at 0.5 m/s; the gyro reads 0.01 rad/s too much
        for f in (plain, biased):
            f.predict(0.02)
            f.update_encoders(0.01, 0.01, 0.02)
            f.update_imu_yaw_rate(0.01)
    assert biased.gyro_bias == pytest.approx(0.01, abs=0.001)
    assert abs(biased.pose[2]) < abs(plain.pose[2]) / 3
    assert biased.state.shape == (7,) and biased.covariance.shape == (7, 7)
