"""The odometry calibration's distance scale (odometry_calibration.py)."""

import math

import numpy as np

from app.core.localisation.odometry_calibration import OdometryCalibration


def _steps(rng, n=60, scale=0.916, wrong=0.3):
    """2 m steps whose matched distance is the odometry's times ``scale``,
    3 cm noise; a share ``wrong`` of the matches held by the prediction
    along the motion (ratio 1) or slid by up to 0.5 m."""
    for k in range(n):
        u = np.array([2.0, 0.1 * rng.normal(), math.radians(5) * rng.normal()])
        m = u.copy()
        m[:2] *= scale
        m[:2] += 0.03 * rng.normal(size=2)
        if rng.uniform() < wrong:
            m[:2] = u[:2] if k % 2 else u[:2] + rng.uniform(-0.5, 0.5, 2)
        yield u, m


def test_the_scale_is_learnt_from_matches_that_know_it_relative_to_the_distance():
    cov = np.diag([0.05 ** 2, 0.05 ** 2, math.radians(0.5) ** 2])  # 5 cm on 2 m: 2.5 %
    old = OdometryCalibration()  # only matches stating <= 2 cm along the motion
    new = OdometryCalibration(scale_rel_sigma=0.05)
    rng = np.random.default_rng(3)
    for u, m in _steps(rng):
        old.learn(u, m, cov)
        new.learn(u, m, cov)
    assert old.scale == 1.0
    assert abs(new.scale - 0.916) < 0.02  # the median, through 30 % wrong matches


def test_short_steps_teach_no_scale():
    """0.25 m steps known to 5 cm (20 %) say nothing of a few per cent."""
    cal = OdometryCalibration(scale_rel_sigma=0.05)
    cov = np.diag([0.05 ** 2, 0.05 ** 2, math.radians(0.5) ** 2])
    for _ in range(100):
        cal.learn(np.array([0.25, 0.0, 0.0]), np.array([0.27, 0.0, 0.0]), cov)
    assert cal.scale == 1.0
