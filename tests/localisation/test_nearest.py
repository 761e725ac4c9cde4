"""The compiled bucket search answers what the k-d tree answers: the nearest
reference point within the gate whose face the sensor sees."""

import numpy as np

from app.core.localisation.icp import Reference, _correspond
from app.core.localisation.localiser import wall_surface
from app.core.localisation.map_io import FREE, OCCUPIED, OccupancyGrid


def _walls():
    cells = np.full((80, 100), FREE, np.int8)
    cells[:, 30:34] = OCCUPIED  # a thick wall: two faces 0.4 m apart
    cells[:2, :] = OCCUPIED
    cells[50:53, 60:90] = OCCUPIED
    cells[20, 70] = OCCUPIED  # a lone post, seen from all sides
    return wall_surface(OccupancyGrid(cells, 0.1, (-1.0, 2.0)))


def test_bucket_search_matches_the_kd_tree_with_faces():
    pts, facing = _walls()
    tree = Reference(pts, facing=facing)
    buckets = Reference(pts, facing=facing, bucket_m=0.1)
    assert tree.buckets is None and buckets.buckets is not None
    rng = np.random.default_rng(5)
    lo, hi = pts.min(axis=0) - 0.5, pts.max(axis=0) + 0.5
    n_back = 0
    for gate in (0.15, 0.3, 0.5, 1.0):
        for _ in range(20):
            origin = rng.uniform(lo, hi)
            moved = rng.uniform(lo, hi, size=(200, 2))
            d0, j0 = _correspond(tree, moved, gate, origin)
            d1, j1 = _correspond(buckets, moved, gate, origin)
            np.testing.assert_array_equal(j1, j0)
            np.testing.assert_allclose(d1, d0, rtol=1e-12)
            # the far-face fallback was exercised: a match that is not the nearest
            dn, _ = tree.tree.query(moved, distance_upper_bound=gate)
            n_back += int(np.count_nonzero(np.isfinite(dn) & (d0 > dn)))
    assert n_back > 50


def test_compiled_icp_agrees_with_the_python_loop():
    """ICP on a bucketed reference (compiled loop) ends where the Python loop
    on the k-d tree ends, with the same fit and covariance, from good and
    poor guesses and with a scan that leaves the map."""
    from app.core.localisation.icp import IcpConfig, icp

    pts, facing = _walls()
    tree = Reference(pts, facing=facing)
    buckets = Reference(pts, facing=facing, bucket_m=0.1)
    cfg = IcpConfig(max_corr_dist_m=0.5, min_corr_dist_m=0.15)
    rng = np.random.default_rng(8)
    truth = np.array([4.0, 4.5, 0.3])
    near = [(2.4, y) for y in np.arange(2.5, 9.0, 0.1)]
    ground = [(x, 2.2) for x in np.arange(2.5, 8.5, 0.1)]
    box = [(x, 7.0) for x in np.arange(5.0, 8.0, 0.1)]
    world = np.array(near + ground + box) + rng.normal(0.0, 0.01, (len(near + ground + box), 2))
    c, s = np.cos(truth[2]), np.sin(truth[2])
    scan = (world - truth[:2]) @ np.array([[c, -s], [s, c]])  # the sensor frame
    outcomes = set()
    for off in [(0.0, 0.0, 0.0), (0.2, -0.1, 0.05), (-0.4, 0.0, 0.0), (0.3, 0.3, -0.1),
                (3.0, 3.0, 1.0)]:
        guess = truth + off
        a = icp(scan, tree, guess, cfg)
        b = icp(scan, buckets, guess, cfg)
        np.testing.assert_allclose(b.pose, a.pose, atol=1e-9)
        np.testing.assert_allclose(b.covariance, a.covariance, rtol=1e-6, atol=1e-12)
        assert (b.iterations, b.converged) == (a.iterations, a.converged)
        assert b.inlier_fraction == a.inlier_fraction
        assert b.rmse_m == a.rmse_m or abs(b.rmse_m - a.rmse_m) < 1e-12
        outcomes.add(a.inlier_fraction > 0.9)
    assert outcomes == {True, False}  # both good fits and a failure were compared


def test_compiled_shift_search_scores_as_the_likelihood_field():
    """The compiled inner loop of the correlative search picks the shift the
    field's own scores rank first, with the same score."""
    from app.core.localisation.icp import LikelihoodField
    from app.core.localisation.icp_kernel import best_shift

    pts, _ = _walls()
    field = LikelihoodField(pts, res_m=0.1, margin_m=1.0)
    rng = np.random.default_rng(2)
    offs = np.arange(-0.5, 0.5 + 1e-9, 0.05)
    dx, dy = np.meshgrid(offs, offs, indexing="ij")
    shifts = np.column_stack((dx.ravel(), dy.ravel()))
    for _ in range(10):
        base = pts[rng.choice(len(pts), 90)] + rng.normal(0.0, 0.2, 2)
        scores = field.score(base[None, :, :] + shifts[:, None, :])
        k, score = best_shift(base, shifts, field.field, float(field.lo[0]),
                              float(field.lo[1]), field.res)
        assert abs(score - scores.max()) < 1e-9
        assert scores[k] >= scores.max() - 1e-9
