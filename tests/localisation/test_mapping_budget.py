"""The mapping step's bounded work: a pose-graph solve spread over several
calls, the compiled matcher on mapping's references, the stamped likelihood
field, and the odometry calibration's turn per metre."""

import math

import numpy as np
from scipy.spatial import cKDTree

from app.core.localisation.icp import IcpConfig, LikelihoodField, Reference, icp
from app.core.localisation.odometry_calibration import OdometryCalibration
from app.core.localisation.pose_graph import Edge, _sqrt_info, gauss_newton, solve_pose_graph
from app.core.localisation.se2 import compose, relative
from app.core.localisation.slam import scan_points


def _square_graph():
    truth = [np.zeros(3)]
    for _ in range(12):  # three laps of a 2 m square
        truth.append(compose(truth[-1], (2.0, 0.0, math.pi / 2)))
    info = _sqrt_info(np.diag([0.05 ** 2, 0.05 ** 2, 0.02 ** 2]))
    edges, x0 = [], [truth[0]]
    for k in range(1, len(truth)):  # odometry turns 4° too far at each corner
        z = relative(truth[k - 1], truth[k]) + np.array([0.0, 0.0, math.radians(4)])
        edges.append(Edge(k - 1, k, z, info))
        x0.append(compose(x0[-1], z))
    tight = _sqrt_info(np.diag([0.01 ** 2, 0.01 ** 2, 0.002 ** 2]))
    edges += [Edge(i, i + 4, np.zeros(3), tight, loop=True) for i in range(8)]
    return np.array(x0), edges


def test_a_solve_spread_over_calls_reaches_the_one_shot_solution():
    x0, edges = _square_graph()
    whole = solve_pose_graph(x0, edges, iterations=50, tol=1e-10)
    x, done, calls = x0, False, 0
    while not done and calls < 50:
        x, done = gauss_newton(x, edges, 2, tol=1e-10)  # two iterations a call
        calls += 1
    assert done and calls >= 2  # it did take more than one call
    np.testing.assert_allclose(x, whole, atol=1e-8)
    first, done1 = gauss_newton(x0, edges, 1)
    assert not done1 and np.max(np.abs(first - x0)) > 0.1  # one call moved, unfinished


def test_compiled_matcher_on_a_mapping_reference_agrees_with_the_kd_tree(freiburg):
    """Mapping's references (bucket_m, no faces) run the compiled ICP loop; it
    finds what the k-d tree's NumPy loop finds on real scans, good fits and
    poor ones alike."""
    pts = scan_points(freiburg)
    ref_pose = np.array(freiburg.scans[40].pose)
    cfg = IcpConfig()
    seen = set()
    for k in (41, 42, 60, 120):
        world = np.vstack([_in(relative(ref_pose, freiburg.scans[i].pose), pts[i])
                           for i in range(36, 41)])
        plain, compiled = Reference(world), Reference(world, bucket_m=cfg.bucket_m)
        assert plain.buckets is None and compiled.buckets is not None
        guess = relative(ref_pose, freiburg.scans[k].pose) + np.array([0.15, -0.1, 0.05])
        a, b = icp(pts[k], plain, guess, cfg), icp(pts[k], compiled, guess, cfg)
        assert a.converged == b.converged
        np.testing.assert_allclose(b.pose, a.pose, atol=1e-6)
        assert abs(b.inlier_fraction - a.inlier_fraction) < 0.01
        seen.add(a.inlier_fraction > 0.6)
    assert seen == {True, False}  # both a good fit and a poor one were compared


def _in(pose, p):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return p @ np.array([[c, s], [-s, c]]) + pose[:2]


def test_stamped_field_is_the_gaussian_of_the_distance_to_the_nearest_point():
    rng = np.random.default_rng(3)
    pts = np.vstack([np.column_stack((np.linspace(0, 4, 80), np.zeros(80))),
                     rng.uniform(-1, 5, size=(40, 2))])
    f = LikelihoodField(pts, res_m=0.1, sigma_m=0.2, margin_m=1.0, stamped=True)
    h, w = f.field.shape
    ys, xs = np.mgrid[0:h, 0:w]
    centres = np.column_stack((f.lo[0] + (xs.ravel() + 0.5) * f.res,
                               f.lo[1] + (ys.ravel() + 0.5) * f.res))
    d, _ = cKDTree(pts).query(centres)
    want = np.where(d <= 0.6, np.exp(-0.5 * (d / 0.2) ** 2), 0.0).reshape(h, w)
    np.testing.assert_allclose(f.field, want, atol=1e-12)
    assert f.field.max() > 0.9 and (f.field == 0).mean() > 0.2
    # the default (distance transform of cells) scores the same points much alike
    e = LikelihoodField(pts, res_m=0.1, sigma_m=0.2, margin_m=1.0)
    probe = pts + rng.normal(0.0, 0.1, pts.shape)
    assert abs(float(f.score(probe)) - float(e.score(probe))) < 0.15 * len(probe)


def test_calibration_learns_a_turn_per_metre_and_a_turn_gain():
    """Odometry whose wheels differ (a turn of +1.2°/m driven) and whose track
    is off (turns 8 % too large): after some matched steps the corrected
    odometry turns as the matches do."""
    cal = OdometryCalibration()
    rng = np.random.default_rng(1)
    b, g = math.radians(1.2), 1.08
    cov = np.diag([1e-4, 1e-4, math.radians(0.3) ** 2])
    for _ in range(200):
        d, turn = rng.uniform(0.5, 1.0), rng.normal(0.0, 0.4)
        matched = np.array([d, 0.0, turn])
        u = np.array([d, 0.0, turn * g + b * d])
        cal.learn(u, matched + np.array([0, 0, rng.normal(0, math.radians(0.3))]), cov)
    assert abs(cal.turn_per_m * 1.08 + b) < math.radians(0.25)
    assert abs(cal.turn_gain - 1 / g) < 0.02
    u = np.array([1.0, 0.0, 0.3 * g + b])
    assert abs(cal.correct(u)[2] - 0.3) < math.radians(0.5)


def test_mapping_steps_spread_the_solve_and_finish_solves_it(freiburg, monkeypatch):
    """While scans come in, no step runs more than its share of Gauss-Newton
    iterations; after finish() the graph is solved to the end."""
    import app.core.localisation.mapping as mapping
    from app.core.localisation.evaluate import drifting_odometry

    calls = []
    real = mapping.gauss_newton

    def counted(x0, edges, iterations, *args, **kw):
        calls.append(iterations)
        return real(x0, edges, iterations, *args, **kw)

    monkeypatch.setattr(mapping, "gauss_newton", counted)
    pts = scan_points(freiburg)[:160]
    ref = np.array([s.pose for s in freiburg.scans[:160]])
    ref = np.array([relative(ref[0], p) for p in ref])
    mapper = mapping.LaserMapper(mapping.MappingConfig())
    for o, p in zip(drifting_odometry(ref, seed=3), pts, strict=True):
        mapper.add_scan(o, p)
    assert mapper.loop_closures >= 3 and len(calls) >= 5
    assert max(calls) <= mapper.cfg.solve_iterations_per_step
    est = mapper.finish()
    again = solve_pose_graph(est, mapper.edges, iterations=5)
    assert np.max(np.abs(again - est)) < 1e-3  # finish left a solved graph
