"""The submap's own uncertainty added to a match (match_covariance.py, 3.)."""

import math

import numpy as np

from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.match_covariance import submap_spread
from app.core.localisation.submap_match import Submap, match_submap

S_TH = math.radians(0.5)  # each fused step's heading σ


def _chain(n, step_m=1.0):
    """n nodes 1 m apart along x, each step with heading σ S_TH and 2 cm."""
    positions = np.column_stack((np.arange(n) * step_m, np.zeros(n)))
    covs = [np.zeros((3, 3))] + [np.diag([0.02 ** 2, 0.02 ** 2, S_TH ** 2])] * (n - 1)
    return positions, covs


def test_a_one_keyframe_submap_adds_nothing():
    positions, covs = _chain(4)
    assert np.all(submap_spread((3.5, 0.0), 3, [3], positions, covs) == 0.0)
    assert np.all(submap_spread((3.5, 0.0), 3, [3], positions, covs, "full") == 0.0)


def test_the_heading_term_by_hand_and_its_lever_arm():
    """Three keyframes, anchored at the newest: step 2 moves two of the
    three keyframes (W = 2/3), step 1 one (W = 1/3)."""
    positions, covs = _chain(3)
    sp = submap_spread((3.0, 0.0), 2, [0, 1, 2], positions, covs)
    assert math.isclose(sp[2, 2], S_TH ** 2 * (4 / 9 + 1 / 9), rel_tol=1e-12)
    # the turn about node 2 (1 m behind the scan) and node 1 (2 m) moves it sideways
    assert math.isclose(sp[1, 1], S_TH ** 2 * (4 / 9 * 1.0 + 1 / 9 * 4.0), rel_tol=1e-12)
    assert sp[0, 0] == 0.0  # the heading part alone does not move it along the chain
    full = submap_spread((3.0, 0.0), 2, [0, 1, 2], positions, covs, "full")
    assert full[0, 0] > 0 and full[2, 2] == sp[2, 2]


def test_the_heading_term_grows_with_the_keyframes_spread():
    positions, covs = _chain(8)
    th = [submap_spread((7.5, 0.0), 7, range(7 - n, 8), positions, covs)[2, 2]
          for n in range(1, 8)]
    assert th[0] > 0 and all(b > a for a, b in zip(th, th[1:], strict=False))
    # the same keyframes with larger step errors (turns): larger still
    big = [c * 4 for c in covs]
    assert submap_spread((7.5, 0.0), 7, range(3, 8), positions, big)[2, 2] > 3.9 * th[3]


def _room_points(pose, rng, n=360):
    """A 12 m × 8 m room's walls as a 180°-less scan: the wall points seen
    from ``pose`` (all of them, in the pose's frame), lightly noisy."""
    corners = [(-2.0, -4.0), (10.0, -4.0), (10.0, 4.0), (-2.0, 4.0), (-2.0, -4.0)]
    pts = []
    for (x1, y1), (x2, y2) in zip(corners[:-1], corners[1:], strict=True):
        t = np.linspace(0, 1, n // 4, endpoint=False)
        pts.append(np.column_stack((x1 + t * (x2 - x1), y1 + t * (y2 - y1))))
    world = np.vstack(pts) + rng.normal(0, 0.005, (n, 2))
    c, s = math.cos(pose[2]), math.sin(pose[2])
    d = world - pose[:2]
    return np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]))


def _turned(pose, centre, eta):
    """``pose`` turned by ``eta`` about the point ``centre``."""
    c, s = math.cos(eta), math.sin(eta)
    d = pose[:2] - centre
    return np.array([centre[0] + c * d[0] - s * d[1], centre[1] + s * d[0] + c * d[1],
                     pose[2] + eta])


def test_the_heading_term_matches_the_matches_real_spread():
    """Keyframes placed by a chain of steps with independent heading errors
    (anchored at the newest: step m's error turns every older keyframe about
    node m): a scan matched on their submap turns with it, by less than
    Σ_spread says (about half its variance: the model is an upper bound) but
    by the same order."""
    rng = np.random.default_rng(7)
    truth = [np.array([float(i), 0.0, 0.0]) for i in range(5)]
    positions = np.array([p[:2] for p in truth])
    covs = [np.zeros((3, 3))] + [np.diag([0.0, 0.0, S_TH ** 2])] * 4
    scan_pose = np.array([5.0, 0.3, 0.0])
    scans = [_room_points(p, rng) for p in truth]
    src = _room_points(scan_pose, rng)
    errs = []
    for _ in range(60):
        placed = list(truth)
        for m in range(4, 0, -1):
            eta = rng.normal(0, S_TH)
            placed = [_turned(p, placed[m][:2], eta) if i < m else p
                      for i, p in enumerate(placed)]
        r = match_submap(src, Submap(list(zip(placed, scans, strict=True))), scan_pose)
        errs.append(r.pose[2] - scan_pose[2])
    predicted = submap_spread(scan_pose, 4, range(5), positions, covs)[2, 2]
    real = float(np.mean(np.square(errs)))
    assert 0.3 < real / predicted < 1.2


def test_the_mapper_adds_it_to_the_fused_step_but_not_on_one_keyframe():
    """Scans 1 m apart in the room, odometry exact: the first match (on a
    one-keyframe submap) is fused the same with or without the term; a later
    one, on a submap of several keyframes, less surely in heading."""
    rng = np.random.default_rng(2)
    poses = [np.array([0.6 * i, 0.1 * (i % 2), 0.05 * i]) for i in range(5)]
    scans = [_room_points(p, rng) for p in poses]
    covs = {}
    for part in ("off", "heading"):
        m = LaserMapper(MappingConfig(submap_spread=part, loop_closure=False))
        for p, pts in zip(poses, scans, strict=True):
            m.add_scan(p, pts)
        assert len(m.landmarks) == 5
        covs[part] = m.step_covs
    np.testing.assert_allclose(covs["heading"][1], covs["off"][1], rtol=1e-9, atol=0)
    assert covs["heading"][4][2, 2] > 1.05 * covs["off"][4][2, 2]
