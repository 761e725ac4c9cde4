"""The ICP fit's and the grid fit's disagreement as part of a match's
covariance (MappingConfig.match_disagreement_k, mapping.py)."""

import math

import numpy as np

from app.core.localisation.icp import IcpResult
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.se2 import relative


def _room_points(pose, rng, n=360):
    """A 12 m × 8 m room's walls seen from ``pose`` (in its frame), lightly noisy."""
    corners = [(-2.0, -4.0), (10.0, -4.0), (10.0, 4.0), (-2.0, 4.0), (-2.0, -4.0)]
    pts = []
    for (x1, y1), (x2, y2) in zip(corners[:-1], corners[1:], strict=True):
        t = np.linspace(0, 1, n // 4, endpoint=False)
        pts.append(np.column_stack((x1 + t * (x2 - x1), y1 + t * (y2 - y1))))
    world = np.vstack(pts) + rng.normal(0, 0.003, (n, 2))
    return np.array([relative(pose, (x, y, 0.0))[:2] for x, y in world])


def _refined(k, icp_pose, points, truth):
    m = LaserMapper(MappingConfig(match_disagreement_k=k, loop_closure=False))
    m.add_scan(np.zeros(3), points[0])
    cov = np.diag([0.01 ** 2, 0.01 ** 2, math.radians(0.1) ** 2])
    r = IcpResult(np.array(icp_pose, float), cov, 0.01, 1.0, 5, True)
    r, scale, spread = m._submap_refined(points[1], r)
    return r.pose, np.asarray(r.covariance) * scale + spread


def test_a_match_whose_two_fits_part_is_less_sure_by_their_disagreement():
    rng = np.random.default_rng(4)
    truth = np.array([0.5, 0.1, 0.02])
    points = [_room_points(np.zeros(3), rng), _room_points(truth, rng)]
    off = truth + np.array([0.0, 0.0, math.radians(0.8)])  # ICP's fit, 0.8° off
    pose0, cov0 = _refined(0.0, off, points, truth)
    pose2, cov2 = _refined(2.0, off, points, truth)
    np.testing.assert_allclose(pose2, pose0)  # the fit itself is the grid's either way
    assert abs(pose0[2] - truth[2]) < math.radians(0.2)  # ...and near the truth
    d = pose0 - off
    np.testing.assert_allclose(cov2 - cov0, 4.0 * np.outer(d, d), atol=1e-12)
    assert math.sqrt(cov2[2, 2]) > 2 * math.sqrt(cov0[2, 2])
    # where the two fits agree, nothing is added worth the name
    _, cov_same = _refined(2.0, pose0, points, truth)
    assert cov_same[2, 2] < cov0[2, 2] * 1.01
