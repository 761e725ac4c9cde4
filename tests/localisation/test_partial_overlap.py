"""Scan matches that overlap the local map only in part (partial_overlap.py)."""

import math

import numpy as np

from app.core.localisation.icp import IcpResult, Reference
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.odometry_noise import OdometryNoiseConfig
from app.core.localisation.partial_overlap import (
    PartialOverlap,
    PartialOverlapConfig,
    partial_covariance,
)
from app.core.localisation.se2 import compose, relative, wrap
from app.core.localisation.slam import scan_points


def _wall(x0, y0, x1, y1, step=0.05):
    n = int(math.hypot(x1 - x0, y1 - y0) / step) + 1
    return np.column_stack((np.linspace(x0, x1, n), np.linspace(y0, y1, n)))


def test_a_corridor_leaves_its_axis_free_and_the_share_widens_the_covariance():
    walls = np.vstack((_wall(-3, -1, 3, -1), _wall(-3, 1, 3, 1)))  # a corridor along x
    ref = Reference(walls)
    cov = np.diag([1e-4, 1e-4, 1e-6])
    out = partial_covariance(walls, ref, np.zeros(3), cov, 0.3, 0.45, MappingConfig().icp,
                             PartialOverlapConfig())
    assert out[0, 0] > 0.9  # along the corridor: free (σ 1 m)
    assert math.isclose(out[1, 1], 1e-4 * 0.45 / 0.3, rel_tol=1e-6)  # across: R · f₀ / f
    assert math.isclose(out[2, 2], 1e-6 * 0.45 / 0.3, rel_tol=1e-6)
    room = np.vstack((walls, _wall(3, -1, 3, 1)))  # closed at one end: x is held
    held = partial_covariance(room, Reference(room), np.zeros(3), cov, 0.3, 0.45,
                              MappingConfig().icp, PartialOverlapConfig())
    assert held[0, 0] < 1e-3


def test_a_partial_fit_needs_enough_inlier_points():
    def fit(share):
        return IcpResult(np.zeros(3), np.eye(3), 0.02, share, 30, False)

    def accepts(share, cfg=None):
        return PartialOverlap(cfg or PartialOverlapConfig(), OdometryNoiseConfig(), 0.45,
                              MappingConfig().icp).accepts(
            fit(share), 150)

    assert accepts(0.3)  # 45 points
    assert not accepts(0.15)  # 22 points
    assert not accepts(0.5)  # a full fit, not a partial one
    assert not accepts(0.3, PartialOverlapConfig(enabled=False))


def test_scans_two_metres_apart_into_new_parts_of_a_hall_are_matched_not_dead_reckoned(
        edmonton):
    """The first steps of edmonton's odd scans driven backwards overlap the
    local map by 24-45 % of their points (the hall's walls seen for the first
    time); the mapper used to dead reckon them, carrying odometry's turn error
    whole. Odometry here turns 3° too far every step: the partial fits hold
    the heading."""
    pts = scan_points(edmonton)
    idx = np.arange(len(pts))[::-1][::2][:6]
    ref = np.array([edmonton.scans[i].pose for i in idx])
    ref = np.array([relative(ref[0], p) for p in ref])
    odo = [ref[0]]
    for k in range(1, len(ref)):
        u = relative(ref[k - 1], ref[k])
        odo.append(compose(odo[-1], u + np.array([0.0, 0.0, math.radians(3)])))

    def heading_errors(cfg):
        m = LaserMapper(cfg)
        for o, i in zip(odo, idx, strict=True):
            m.add_scan(o, pts[i])
        est = np.array(m.poses)
        steps = [float(wrap(relative(est[k - 1], est[k])[2] - relative(ref[k - 1], ref[k])[2]))
                 for k in range(1, len(ref))]
        return np.degrees(np.abs(steps)), m

    off, m = heading_errors(MappingConfig())
    old, m_old = heading_errors(MappingConfig(partial=PartialOverlapConfig(enabled=False)))
    assert m_old.icp_failures >= 3 and np.sum(old > 2.5) >= 3  # dead reckoned: 3° off
    print(off, old, m.partial_matches, m.icp_failures, m_old.icp_failures)
    assert m.partial_matches >= 3 and m.icp_failures <= 1
    # the first step (29 of 121 points on the one keyframe's walls) stays dead reckoned
    assert np.all(off[1:] < 1.0) and off.sum() < old.sum() / 2
