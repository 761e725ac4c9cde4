import math

import numpy as np

from app.core.localisation.icp import Reference, icp, match, scan_normals, stacked_reference
from app.core.localisation.preprocess import preprocess
from app.core.localisation.se2 import relative, rotation, transform_points


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


def test_a_local_map_of_ten_real_keyframes_keeps_each_scans_own_normals(edmonton):
    # ten edmonton scans (1 m apart) at their reference poses as one reference,
    # the next scan matched from its reference pose
    k = 72
    ref = [np.array(edmonton.scans[j].pose) for j in range(k - 10, k)]
    pts = [_points(edmonton, j) for j in range(k - 10, k)]
    # normals by PCA over the stack: a point's nearest neighbours are the same
    # spot seen by the other scans, a blob that fails the line test
    stacked = np.vstack([transform_points(p, q) for p, q in zip(ref, pts, strict=True)])
    plain = Reference(stacked, bucket_m=0.25)
    own = stacked_reference([(p, q, *scan_normals(q)) for p, q in zip(ref, pts, strict=True)],
                            bucket_m=0.25)
    assert np.mean(own.planar) > np.mean(plain.planar) + 0.2
    truth = np.array(edmonton.scans[k].pose)
    r = icp(_points(edmonton, k), own, truth)
    assert r.converged and r.inlier_fraction > 0.7
    move = relative(truth, r.pose)
    assert math.hypot(move[0], move[1]) < 0.05 and abs(move[2]) < math.radians(0.5)
    # the own normals, turned by each pose, are the PCA of each scan alone
    n0, _ = scan_normals(pts[0])
    assert np.allclose(np.abs(np.einsum("ij,ij->i", own.normals[:len(pts[0])],
                                        n0 @ rotation(ref[0][2]).T)), 1.0)
