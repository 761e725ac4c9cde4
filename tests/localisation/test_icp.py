import math

import numpy as np

from app.core.localisation.icp import Reference, icp, match
from app.core.localisation.preprocess import preprocess
from app.core.localisation.se2 import relative, transform_points


def _points(log, k):
    s = log.scans[k]
    return preprocess(s.ranges_m, log.beam_angles(s.ranges_m.size), no_return_m=log.no_return_m())


def test_icp_recovers_a_known_transform_of_a_real_scan_from_a_poor_guess(freiburg):
    rng = np.random.default_rng(4)
    src = _points(freiburg, 120)
    truth = np.array([0.6, -0.35, math.radians(14)])
    ref_pts = transform_points(truth, src) + rng.normal(0, 0.01, src.shape)
    ref = Reference(ref_pts)
    guess = np.zeros(3)  # 0.7 m and 14° away
    r = match(src, ref, guess, window_xy_m=1.0, window_theta_rad=math.radians(20))
    assert np.hypot(*(r.pose[:2] - truth[:2])) < 0.01
    assert abs(r.pose[2] - truth[2]) < math.radians(0.2)
    assert r.inlier_fraction > 0.9 and r.converged


def test_icp_matches_consecutive_real_scans_as_the_reference_does(freiburg):
    errs = []
    for k in range(30, 50):
        a, b = np.array(freiburg.scans[k - 1].pose), np.array(freiburg.scans[k].pose)
        rel = relative(a, b)
        guess = rel + np.array([0.15, -0.1, math.radians(4)])
        r = match(_points(freiburg, k), Reference(_points(freiburg, k - 1)), guess,
                  window_xy_m=0.5, window_theta_rad=math.radians(10))
        errs.append((math.hypot(*(r.pose[:2] - rel[:2])), abs(r.pose[2] - rel[2])))
    e = np.array(errs)
    assert np.median(e[:, 0]) < 0.05 and np.median(e[:, 1]) < math.radians(0.5)


def test_icp_covariance_is_large_along_a_featureless_corridor():
    rng = np.random.default_rng(2)
    x = np.linspace(-10, 10, 400)
    walls = np.r_[np.column_stack((x, np.full_like(x, 1.0))),
                  np.column_stack((x, np.full_like(x, -1.0)))]
    src = walls + rng.normal(0, 0.01, walls.shape)
    r = icp(src, Reference(walls), np.array([0.3, 0.05, 0.01]))
    sx, sy = math.sqrt(r.covariance[0, 0]), math.sqrt(r.covariance[1, 1])
    assert abs(r.pose[1]) < 0.01  # across the corridor: fixed
    assert sx > 100 * sy  # along it: no information, and the covariance says so
    assert sx > 1.0
