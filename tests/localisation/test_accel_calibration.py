"""The accelerometer's bias from standstills at several headings (eqs. 1-2)."""

import math

import numpy as np

from app.core.localisation.accel_calibration import fit_accel_bias

G = 9.81


def _stops(headings_deg, bias, rng, n=400, noise=0.02, scale=1.0):
    return [np.column_stack([
        scale * G * math.sin(math.radians(h)) + bias[0] + noise * rng.standard_normal(n),
        scale * G * math.cos(math.radians(h)) + bias[1] + noise * rng.standard_normal(n),
    ]) for h in headings_deg]


def test_four_stops_give_the_bias_whatever_the_turns_between_them():
    rng = np.random.default_rng(3)
    bias = (-0.0071, 0.0039)
    errs = []
    for _ in range(50):  # headings off the nominal by slipping turns
        heads = [0.0, 90.0, 180.0, 270.0] + rng.uniform(-12, 12, 4)
        cal = fit_accel_bias(_stops(heads, bias, rng, scale=1.003))
        assert cal is not None and abs(cal.radius - 1.003 * G) < 0.01
        errs.append((cal.bias[0] - bias[0], cal.bias[1] - bias[1], cal.sigma))
    e = np.array(errs)
    rms = np.sqrt((e[:, :2] ** 2).mean())
    assert rms < 0.001  # a tenth of a milligravity
    assert 0.5 < rms / e[:, 2].mean() < 2.0  # the stated standard error is honest


def test_stops_that_do_not_go_round_are_refused():
    rng = np.random.default_rng(4)
    assert fit_accel_bias(_stops([0.0, 40.0, 80.0], (0.01, 0.0), rng)) is None
    assert fit_accel_bias(_stops([0.0, 180.0], (0.01, 0.0), rng)) is None
    assert fit_accel_bias(_stops([0.0, 90.0, 180.0], (0.01, 0.0), rng)) is not None


def test_the_crawler_calibrates_at_start_though_its_turns_slip():
    from sim_robot.climber.accel_stops import calibrate_accelerometer
    from sim_robot.climber.accelerometer import WallAccelerometer

    rng = np.random.default_rng(7)
    accel = WallAccelerometer(rng, bias_mps2=0.02)
    body = {"th": 0.3, "est": 0.3, "f": (0.0, 0.0)}
    dt = 0.05

    class Est:
        @property
        def pose(self):
            return 0.0, 0.0, body["est"]

    def move(v, w):
        body["est"] += w * dt
        body["th"] += 0.85 * w * dt  # the turn slips: 15 % short of what the estimate says
        body["f"] = accel.sample(dt, body["th"], 0.0, 0.85 * w)

    cal = calibrate_accelerometer(move, lambda: body["f"], Est(), dt)
    assert cal is not None and cal.stops == 4
    err = np.hypot(cal.bias[0] - accel.bias[0], cal.bias[1] - accel.bias[1])
    assert cal.sigma < 0.001 and err < 5 * cal.sigma  # a tenth of a milligravity per axis
    assert abs(body["est"] - 0.3 - 2 * math.pi) < math.radians(0.5)  # back where it started
