import math

import numpy as np
import pytest

from sim_robot.sensors import Battery, Dht22, GasSensor, Imu, TurnSlip, Ultrasonic
from sim_robot.world import World


@pytest.fixture(scope="module")
def world():
    return World(seed=1)


def test_gas_sensor_first_order_step_response():
    g = GasSensor(np.random.default_rng(0), tau_s=4.0, noise_lel=0.0, drift_lel_per_h=0.0)
    dt = 0.05
    t = 0.0
    g.sample(t, 0.0)
    out = []
    while t < 20.0:
        t += dt
        out.append(g.sample(t, 20.0))
    out = np.array(out)
    times = dt * (1 + np.arange(len(out)))
    # after one time constant 63 %, after three 95 %; never overshoots
    assert out[np.searchsorted(times, 4.0 - 1e-9)] == pytest.approx(20 * (1 - math.exp(-1)),
                                                                     rel=0.02)
    assert out[np.searchsorted(times, 12.0 - 1e-9)] == pytest.approx(20 * 0.95, rel=0.02)
    assert out.max() <= 20.0 + 1e-9
    assert np.all(np.diff(out) >= 0)


def test_gas_sensor_noise_and_drift_stay_small():
    g = GasSensor(np.random.default_rng(1))
    vals = [g.sample(i * 0.05, 0.0) for i in range(2000)]
    assert -0.1 < np.mean(vals) < 0.5
    assert min(vals) < 0.0  # signed: the noise reads either side of zero


def test_gas_sensor_fault_reads_below_zero_and_saturation_above_range():
    g = GasSensor(np.random.default_rng(2), noise_lel=0.0, drift_lel_per_h=0.0)
    g.offset_lel = -8.0
    assert g.sample(0.0, 0.0) == pytest.approx(-8.0)
    g.offset_lel = -80.0
    assert g.sample(0.1, 0.0) == GasSensor.OUT_MIN_LEL  # the transmitter's bottom
    g = GasSensor(np.random.default_rng(3), noise_lel=0.0, drift_lel_per_h=0.0)
    assert g.sample(0.0, 150.0) == GasSensor.OUT_MAX_LEL  # over-range, not 100


def test_dht22_resolution_and_update_period():
    d = Dht22(np.random.default_rng(2), period_s=2.0)
    seen = []
    for i in range(201):  # 10 s at 20 Hz
        t = i * 0.05
        temp, hum = d.sample(t, 21.0 + 0.3 * t, 50.0 - 0.5 * t)
        assert round(temp * 10) == pytest.approx(temp * 10, abs=1e-9)
        assert round(hum * 10) == pytest.approx(hum * 10, abs=1e-9)
        seen.append((t, temp, hum))
    assert d.updates == 6  # t = 0, 2, 4, 6, 8, 10
    changes = [t for (t, a, b), (_, c, e) in zip(seen, seen[1:], strict=False) if (a, b) != (c, e)]
    assert all(abs(t / 2 - round(t / 2)) < 0.06 for t in np.array(changes) + 0.05)


def test_ultrasonic_sees_a_wall_at_the_right_distance(world):
    u = Ultrasonic(np.random.default_rng(3))
    # control room south wall at y = 49.0; robot at y = 47.5 facing north, sensor 0.2 m ahead
    left, front, right = u.sample(world, 66.0, 47.5, math.pi / 2)
    assert front == pytest.approx(49.0 - 47.7, abs=0.06)
    assert left > front and right > front
    # nothing within 4 m: reports the maximum
    assert u.sample(world, 66.0, 45.0, -math.pi / 2)[1] == pytest.approx(4.0)


def test_battery_discharges_faster_while_driving():
    idle, drive = Battery(), Battery()
    for _ in range(600):
        idle.step(1.0, 0.0, charging=False)
        drive.step(1.0, 0.8, charging=False)
    assert drive.soc < idle.soc < 0.92
    assert 18.0 < drive.voltage() < idle.voltage() < 25.3


def test_imu_has_bias_and_noise():
    imu = Imu(np.random.default_rng(4), bias_rps=0.01)
    vals = np.array([imu.sample(0.05, 0.5) for _ in range(400)])
    assert vals.mean() == pytest.approx(0.51, abs=0.003)
    assert vals.std() > 0.001


def test_turn_slip_is_nil_straight_and_grows_with_the_turn_rate():
    slip = TurnSlip(np.random.default_rng(3))
    assert all(slip.step(0.02, 0.0) == 0.0 for _ in range(200))
    slow = np.mean([slip.step(0.02, 0.1) for _ in range(3000)])
    fast = np.mean([slip.step(0.02, 0.6) for _ in range(3000)])
    assert 0.0 < slow < fast <= 0.5
    assert fast == pytest.approx(0.06 * 0.6, abs=0.02)


def test_imu_bias_wanders_like_a_random_walk_over_minutes_but_stays_bounded_over_days():
    rng = np.random.default_rng(11)
    imus = [Imu(rng, bias_rps=0.0) for _ in range(300)]
    for imu in imus:  # one minute in 0.05 s steps: the walk's own spread, walk·sqrt(60 s)
        for _ in range(1200):
            imu.sample(0.05, 0.0)
    minute = np.std([imu.bias for imu in imus])
    assert minute == pytest.approx(0.0002 * math.sqrt(60.0), rel=0.15)
    for imu in imus:  # then three days in hour steps
        for _ in range(72):
            imu.sample(3600.0, 0.0)
    days = np.std([imu.bias for imu in imus])
    # bounded near walk·sqrt(tau/2) = 0.0085 rad/s; a pure walk would be at 0.10 rad/s
    assert days == pytest.approx(0.0002 * math.sqrt(3600.0 / 2), rel=0.15)
