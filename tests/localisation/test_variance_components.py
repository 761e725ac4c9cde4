"""Variance components of the pose graph's edge classes (variance_components.py)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.localisation.pose_graph import Edge, _sqrt_info, solve_pose_graph
from app.core.localisation.se2 import compose, relative
from app.core.localisation.variance_components import (
    VarianceComponentConfig,
    class_factors,
    edge_classes,
    reweighted_solve,
)


def _graph(seed: int, step_sigma: float, loop_sigma: float, stated: float):
    """A 120-node wander; steps between neighbours measured with noise
    ``step_sigma`` (x, y; a tenth in rad), loop edges between nodes 5-15
    apart with ``loop_sigma``; both stated with σ = ``stated``."""
    rng = np.random.default_rng(seed)
    truth = [np.zeros(3)]
    for _ in range(119):
        truth.append(compose(truth[-1], (1.0, rng.normal(0, 0.1), rng.normal(0, 0.3))))
    truth = np.array(truth)
    cov = np.diag([stated ** 2, stated ** 2, (stated / 10) ** 2])
    edges, classes = [], []
    for k in range(1, len(truth)):
        z = relative(truth[k - 1], truth[k]) + rng.normal(0, 1, 3) * np.array(
            [step_sigma, step_sigma, step_sigma / 10])
        edges.append(Edge(k - 1, k, z, _sqrt_info(cov)))
        classes.append(0)
    for i in range(0, len(truth) - 16, 2):
        j = i + int(rng.integers(5, 16))
        z = relative(truth[i], truth[j]) + rng.normal(0, 1, 3) * np.array(
            [loop_sigma, loop_sigma, loop_sigma / 10])
        edges.append(Edge(i, j, z, _sqrt_info(cov), loop=True))
        classes.append(1)
    dead = [np.zeros(3)]
    for e in edges[:len(truth) - 1]:
        dead.append(compose(dead[-1], e.z))
    return truth, np.array(dead), edges, np.array(classes)


def test_factors_recover_each_class_variance():
    """Steps with σ 0.02 and loop edges with σ 0.06, both stated 0.05: one
    estimate from the stated weights already ranks them (steps below loops);
    iterated (VCE-2), the absolute factors come out near (0.02/0.05)² = 0.16
    and (0.06/0.05)² = 1.44, and the relative one near their ratio 0.11."""
    truth, dead, edges, classes = _graph(3, 0.02, 0.06, 0.05)
    x = solve_pose_graph(dead, edges, cauchy_c=1e6)
    s2, red = class_factors(x, edges, classes, cauchy_c=1e6)
    assert 0 < red[0] < 3 * 119 and 0 < red[1] < 3 * int(np.sum(classes == 1))
    assert s2[0] < 0.6 * s2[1], s2
    cfg = VarianceComponentConfig(cauchy_c=1e6, iterations=20, tol=0.01)
    _, _, f = reweighted_solve(dead, edges, classes, replace(cfg, relative=False))
    assert 0.08 < f[0] < 0.3 and 1.0 < f[1] < 2.2, f
    _, scaled, f = reweighted_solve(dead, edges, classes, cfg)
    assert f[1] == 1.0 and 0.05 < f[0] < 0.25, f
    assert np.allclose(scaled[0].sqrt_info, edges[0].sqrt_info / math.sqrt(f[0]))


def test_reweighted_solve_brings_the_steps_closer_to_truth():
    """With the steps stated 2.5x too loose, the loop edges' errors leak into
    them; the reweighted solve holds them nearer their true lengths."""
    errs = {"stated": [], "reweighted": []}
    for seed in range(4):
        truth, dead, edges, classes = _graph(seed, 0.02, 0.06, 0.05)
        x0 = solve_pose_graph(dead, edges)
        x1, _, _ = reweighted_solve(dead, edges, classes)
        for lab, x in (("stated", x0), ("reweighted", x1)):
            e = [relative(relative(truth[k - 1], truth[k]), relative(x[k - 1], x[k]))
                 for k in range(1, len(truth))]
            errs[lab].append(np.mean([math.hypot(a[0], a[1]) for a in e]))
    assert np.mean(errs["reweighted"]) < 0.85 * np.mean(errs["stated"]), errs


def test_a_class_with_too_little_redundancy_keeps_its_factor():
    """One loop edge over a chain checks nearly nothing of itself: its class
    keeps the factor 1 however large its residual."""
    truth, dead, edges, classes = _graph(1, 0.02, 0.06, 0.05)
    keep = [k for k, c in enumerate(classes) if c == 0] + [int(np.flatnonzero(classes == 1)[0])]
    edges = [edges[k] for k in keep]
    classes = classes[keep]
    x = solve_pose_graph(dead, edges)
    s2, red = class_factors(x, edges, classes)
    assert red[1] < 3.0 and s2[1] == 1.0


def test_edge_classes_are_steps_and_loops():
    step = Edge(0, 1, np.zeros(3), np.eye(3))
    loop = Edge(0, 5, np.zeros(3), np.eye(3), loop=True)
    assert list(edge_classes([step, loop, step])) == [0, 1, 0]


def test_mapper_reweights_its_steps_on_a_real_log(freiburg):
    """freiburg-101 with drifting odometry: the fused steps' stated
    covariances (the odometry model's 3-5x margin and the edge floor) are
    looser than the loop edges bear out, so their class factor is below 1;
    the reweighted solve's steps agree better with the reference (RPE over
    1 m) than the same graph solved with the stated covariances (the
    mapper's edges with the factors taken back out, solved as
    reweighted_solve's first pass solves them)."""
    from app.core.localisation.evaluate import drifting_odometry, rpe
    from app.core.localisation.mapping import MappingConfig
    from app.core.localisation.slam import run_mapping, scan_points

    pts = scan_points(freiburg)
    ref = np.array([s.pose for s in freiburg.scans])
    ref = np.array([relative(ref[0], p) for p in ref])
    odo = drifting_odometry(ref, seed=1)
    cfg = MappingConfig(final_pass=True)
    est, mapper = run_mapping(pts, odo, cfg)
    f = mapper.class_factors
    assert len(f) == 2 and f[1] == 1.0
    assert f[0] < 0.8, f
    stated = [Edge(e.i, e.j, e.z, e.sqrt_info * np.sqrt(f[c]), e.loop)
              for e, c in zip(mapper.edges, edge_classes(mapper.edges), strict=True)]
    plain = solve_pose_graph(est, stated, cfg.variance_cfg.cauchy_c)
    assert rpe(est, ref, 1.0).trans_m < rpe(plain, ref, 1.0).trans_m - 0.0005


def test_each_class_redundancy_as_solved_in_full():
    """The most numerous class's redundancy is what the others leave of the unknowns
    (Σ_g tr(N⁻¹ N_g) = tr(I)): the same as solving its own trace, column by column. With
    more loop edges than steps (a log of many revisits), three classes, and the robust
    weights on."""
    from scipy.sparse import identity
    from scipy.sparse.linalg import splu

    from app.core.localisation.pose_graph import Linearisation

    truth, dead, edges, classes = _graph(5, 0.02, 0.06, 0.05)
    rng = np.random.default_rng(5)
    for _ in range(3):  # the loop edges made the most numerous class
        for i in range(0, len(truth) - 16, 2):
            j = i + int(rng.integers(5, 16))
            z = relative(truth[i], truth[j]) + rng.normal(0, [0.06, 0.06, 0.006])
            edges.append(Edge(i, j, z, edges[-1].sqrt_info, loop=True))
    classes = np.array(edge_classes(edges))
    classes[5:40] = 2  # a third class among the steps
    assert np.bincount(classes).argmax() == 1
    x = solve_pose_graph(dead, edges)
    s2, red = class_factors(x, edges, classes)
    jac, rw, _ = Linearisation(edges, len(x)).at(x, 3.0)
    h = (jac.T @ jac).tocsc()
    lu = splu(h + identity(h.shape[0], format="csc") * 1e-9)
    cls3 = np.repeat(classes, 3)
    for g in range(3):
        rows = np.flatnonzero(cls3 == g)
        jg_t = jac.T.tocsr()[:, rows].toarray()
        want = rows.size - float(np.sum(jg_t * lu.solve(jg_t)))
        assert red[g] == pytest.approx(want, rel=1e-6, abs=1e-6)
        assert s2[g] == pytest.approx(float(rw[rows] @ rw[rows]) / want, rel=1e-6)
