import math

import numpy as np
import pytest

from app.core.localisation.ekf_slam import LandmarkEkf
from app.core.localisation.se2 import compose, relative


def _numeric(f, x, eps=1e-6):
    cols = []
    for i in range(len(x)):
        d = np.zeros(len(x))
        d[i] = eps
        cols.append((f(x + d) - f(x - d)) / (2 * eps))
    return np.column_stack(cols)


def test_jacobians_match_finite_differences():
    robot, u = np.array([1.0, -2.0, 0.7]), np.array([0.8, 0.1, 0.3])
    a, b = LandmarkEkf.motion_jacobians(robot, u)
    assert a == pytest.approx(_numeric(lambda r: compose(r, u), robot), abs=1e-6)
    assert b == pytest.approx(_numeric(lambda v: compose(robot, v), u), abs=1e-6)
    lm = np.array([0.3, 0.5, -0.4])
    h_r, h_n = LandmarkEkf.observation_jacobians(robot, lm)
    assert h_r == pytest.approx(_numeric(lambda r: relative(lm, r), robot), abs=1e-6)
    assert h_n == pytest.approx(_numeric(lambda m: relative(m, robot), lm), abs=1e-6)


def test_a_new_landmark_copies_the_robot_and_its_covariance_blocks():
    ekf = LandmarkEkf()
    ekf.predict((1.0, 0.0, 0.2), np.diag([0.01, 0.01, 0.001]))
    n = ekf.add_landmark()
    assert n == 0 and ekf.landmark_count == 1
    assert ekf.landmark(0) == pytest.approx(ekf.robot)
    assert ekf.p[3:6, 3:6] == pytest.approx(ekf.p[:3, :3])
    assert ekf.p[:3, 3:6] == pytest.approx(ekf.p[:3, :3])  # P_Rn = P_R


def test_closing_on_the_first_landmark_pulls_the_later_ones_back():
    ekf = LandmarkEkf()
    ekf.add_landmark()
    q = np.diag([0.02 ** 2, 0.02 ** 2, math.radians(2) ** 2])
    for _ in range(4):  # a 1 m square; the odometry turns 5° too far each corner
        ekf.predict((1.0, 0.0, math.pi / 2 + math.radians(5)), q)
        ekf.add_landmark()
    drifted = [ekf.landmark(i).copy() for i in range(5)]
    # back at the start: ICP says the robot sits exactly on landmark 0
    d2 = ekf.update(0, np.zeros(3), np.diag([0.01 ** 2, 0.01 ** 2, math.radians(0.5) ** 2]))
    assert d2 > 9  # the drift was far outside the measurement noise
    assert np.hypot(*ekf.robot[:2]) < 0.05
    # the cross-covariances carried the correction to the other landmarks:
    # the square's corners (1, 1) and (0, 1) come back near their places
    for i, true_xy in ((2, (1.0, 1.0)), (3, (0.0, 1.0))):
        before = np.hypot(*(drifted[i][:2] - true_xy))
        after = np.hypot(*(ekf.landmark(i)[:2] - true_xy))
        assert before > 0.08 and after < before / 3
    assert abs(ekf.landmark(1)[2] - math.pi / 2) < abs(drifted[1][2] - math.pi / 2) / 3
    assert np.hypot(*(ekf.landmark(0)[:2])) < 0.01  # the anchor barely moves
