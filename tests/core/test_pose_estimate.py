"""The desk's view of the robot's localisation: quality, ellipse, set-pose drag."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.comm import protocol as P
from app.core.pose_estimate import (
    covariance_ellipse,
    pose_from_drag,
    quality_from_pose,
    quality_line,
)


def test_ellipse_axes_follow_the_covariance_rotated():
    th = math.radians(30)
    r = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    cov = r @ np.diag([0.3 ** 2, 0.1 ** 2]) @ r.T
    pts = covariance_ellipse(cov, (5.0, -1.0), probability=0.95, segments=360)
    d = pts - (5.0, -1.0)
    k = math.sqrt(-2 * math.log(0.05))
    # every point lies on the k-σ contour: dᵀ Σ⁻¹ d = k²
    m = np.einsum("ij,jk,ik->i", d, np.linalg.inv(cov), d)
    assert m == pytest.approx(np.full(len(d), k * k), rel=1e-9)
    far = d[np.argmax(np.hypot(d[:, 0], d[:, 1]))]
    assert np.hypot(*far) == pytest.approx(0.3 * k, rel=1e-3)
    assert abs(math.atan2(far[1], far[0]) % math.pi - th) < math.radians(1)
    assert np.allclose(pts[0], pts[-1])  # closed


def test_a_degenerate_covariance_draws_a_line_not_a_crash():
    pts = covariance_ellipse(np.array([[0.01, 0.0], [0.0, -1e-9]]), (0, 0))
    assert np.isfinite(pts).all() and np.abs(pts[:, 1]).max() == 0.0


def test_quality_comes_only_from_a_complete_finite_block():
    assert quality_from_pose(P.Pose(1, 2, 0)) is None
    q = quality_from_pose(P.Pose(1, 2, 0, 0, 0, 0.0004, 0, 0.0001, 0.0001, 0.95, 0.02, 1))
    assert q.sigma_xy_m == pytest.approx(0.02) and not q.lost
    assert "match 95 %" in quality_line(q)[0] and quality_line(q)[1] is False
    lost = quality_from_pose(P.Pose(1, 2, 0, 0, 0, 0.3, 0, 0.3, 0.1, 0.1, 0.2, 2))
    text, needs = quality_line(lost)
    assert needs and "LOST" in text
    assert quality_from_pose(P.Pose(1, 2, 0, 0, 0, float("nan"), 0, 0, 0, 0, 0, 1)) is None
    assert quality_from_pose(P.Pose(1, 2, 0, 0, 0, 0.1, 0, 0.1, 0, 0, 0, 9)) is None


def test_drag_gives_position_and_heading():
    assert pose_from_drag(1.0, 2.0, 1.0, 3.0) == {"x_m": 1.0, "y_m": 2.0,
                                                  "theta_rad": round(math.pi / 2, 4)}
    assert pose_from_drag(1.0, 2.0, 0.0, 2.0)["theta_rad"] == pytest.approx(math.pi, abs=1e-4)
    assert pose_from_drag(1.0, 2.0, 1.05, 2.05) is None  # too short for a heading
    assert pose_from_drag(float("nan"), 2.0, 3.0, 2.0) is None
