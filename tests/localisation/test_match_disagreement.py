"""The ICP fit's and the grid fit's disagreement as part of a match's
covariance (MappingConfig.match_disagreement_k, mapping.py)."""

import math

import numpy as np

from app.core.localisation.icp import IcpResult
from app.core.localisation.mapping import LaserMapper, MappingConfig

from .rooms import room_points


def _refined(k, icp_pose, points, truth):
    m = LaserMapper(MappingConfig(match_disagreement_k=k, loop_closure=False))
    m.add_scan(np.zeros(3), points[0])
    cov = np.diag([0.01 ** 2, 0.01 ** 2, math.radians(0.1) ** 2])
    r = IcpResult(np.array(icp_pose, float), cov, 0.01, 1.0, 5, True)
    r, scale, spread, d = m._submap_refined(points[1], r)
    return r.pose, np.asarray(r.covariance) * scale + spread + k ** 2 * np.outer(d, d)


def test_a_match_whose_two_fits_part_is_less_sure_by_their_disagreement():
    rng = np.random.default_rng(4)
    truth = np.array([0.5, 0.1, 0.02])
    points = [room_points(np.zeros(3), rng), room_points(truth, rng)]
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


def test_position_mode_leaves_the_heading_part_of_the_disagreement_out():
    rng = np.random.default_rng(4)
    truth = np.array([0.5, 0.1, 0.02])
    points = [room_points(np.zeros(3), rng), room_points(truth, rng)]
    off = truth + np.array([0.05, -0.03, math.radians(0.8)])  # ICP's fit, off in all three
    m = LaserMapper(MappingConfig(match_disagreement="position", loop_closure=False))
    m.add_scan(np.zeros(3), points[0])
    r = IcpResult(off.copy(), np.diag([1e-4, 1e-4, 1e-6]), 0.01, 1.0, 5, True)
    r, _, _, d = m._submap_refined(points[1], r)
    assert d[2] == 0.0  # the heading's disagreement is not counted...
    np.testing.assert_allclose(d[:2], r.pose[:2] - off[:2])  # ...the position's is
    assert math.hypot(*d[:2]) > 0.03


def _fuse(mode, d_deg):
    from app.core.localisation.match_covariance import fused_step
    q = np.diag([0.07 ** 2, 0.07 ** 2, math.radians(1.6) ** 2])  # odometry, a 1 m step
    rc_fit = np.diag([0.02 ** 2, 0.02 ** 2, math.radians(0.35) ** 2])
    d = np.array([0.0, 0.0, math.radians(d_deg)])
    rc = rc_fit + 1.5 ** 2 * np.outer(d, d)
    return fused_step(q, rc_fit, rc, d, mode, 16.0), q, rc_fit, rc


def test_edge_mode_keeps_the_fits_gain_and_states_the_disagreement_in_the_step():
    (g_fusion, c_fusion), q, rc_fit, rc = _fuse("fusion", 0.6)
    (g_edge, c_edge), *_ = _fuse("edge", 0.6)
    # "fusion": the disagreement hands more of the heading to odometry (the
    # gain weighs the match's innovation; 1 − K is odometry's share)
    np.testing.assert_allclose(g_fusion, q @ np.linalg.inv(q + rc))
    assert 1 - g_fusion[2, 2] > 2 * (1 - g_edge[2, 2])
    # "edge": the fit's own gain (odometry's bias leaks no more than without d)...
    np.testing.assert_allclose(g_edge, q @ np.linalg.inv(q + rc_fit))
    # ...and the step says it is less sure than the fit alone would make it
    plain = (np.eye(3) - g_edge) @ q
    assert c_edge[2, 2] > 2 * plain[2, 2]
    # the Joseph form with the optimal gain is the usual (I − K) Q
    np.testing.assert_allclose(c_fusion, (np.eye(3) - g_fusion) @ q)


def test_edge_mode_hands_a_grossly_parted_step_to_odometry():
    (g_edge, _), q, rc_fit, rc = _fuse("edge", 5.0)  # 5°: 14 σ of the fit, a rival minimum
    (g_fusion, _), *_ = _fuse("fusion", 5.0)
    np.testing.assert_allclose(g_edge, g_fusion)
    assert g_edge[2, 2] < 0.1  # mostly odometry's heading
