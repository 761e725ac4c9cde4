"""Loop closure against a submap of the candidate's keyframes
(loop_closure.verify_submap) and the pose graph's defence against a wrong
closure (robust kernel, then pruning)."""

import math

import numpy as np
import pytest

from app.core.localisation.evaluate import drifting_odometry
from app.core.localisation.icp import IcpConfig
from app.core.localisation.loop_closure import LoopConfig, verify, verify_submap
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.pose_graph import Edge, _sqrt_info
from app.core.localisation.se2 import compose, relative, transform_points
from app.core.localisation.slam import run_mapping, scan_points
from app.core.localisation.submap_match import Submap


@pytest.fixture(scope="module")
def real(freiburg):
    pts = scan_points(freiburg)
    ref = np.array([s.pose for s in freiburg.scans])
    return pts, np.array([relative(ref[0], p) for p in ref])


def _place(pts, ref, lo, hi, at=None):
    """Keyframes lo..hi-1 as (pose, points); ``at``: moved so that lo sits there."""
    shift = np.zeros(3) if at is None else compose(at, relative(ref[lo], np.zeros(3)))
    return [(compose(shift, ref[i]), pts[i]) for i in range(lo, hi)]


def test_a_revisit_only_the_submap_matcher_closes(real):
    """Scan 41 comes back to where keyframes 3..7 stood, its estimate 1 m and
    9° off (drift round a loop): ICP and its correlative fallback (window
    0.6 m / 10°) do not close it; the submap's wider search and grid fit do,
    to within a few centimetres of the reference."""
    pts, ref = real
    place = _place(pts, ref, 3, 8)
    guess = compose(ref[41], (0.7, 0.7, math.radians(9)))
    stacked = np.vstack([transform_points(p, q) for p, q in place])
    r_icp, g_icp, searched = verify(pts[41], stacked, guess, 0.6, math.radians(10), IcpConfig(),
                                    LoopConfig(), may_search=True)
    assert searched
    e_icp = relative(ref[41], r_icp.pose)
    assert g_icp is None or math.hypot(e_icp[0], e_icp[1]) > 0.1 or abs(e_icp[2]) > 0.01
    r, g = verify_submap(pts[41], Submap(place), guess, 0.6, math.radians(10), LoopConfig())
    assert g == "strong"
    e = relative(ref[41], r.pose)
    assert math.hypot(e[0], e[1]) < 0.05 and abs(e[2]) < math.radians(0.5)
    sig = np.sqrt(np.diag(r.covariance))
    assert np.all(sig > 0) and sig[0] < 0.05 and sig[2] < math.radians(1)


def test_the_submap_matcher_refuses_a_place_the_scan_has_never_seen(real):
    pts, ref = real
    elsewhere = _place(pts, ref, 150, 155, at=ref[41])  # another room put where scan 41 is
    _, g = verify_submap(pts[41], Submap(elsewhere), ref[41], 1.0, math.radians(10),
                         LoopConfig())
    assert g is None


def test_the_mapper_closes_the_first_freiburg_loop_with_the_submap_matcher(real):
    """Scans 0..59 with drifting odometry, loop closures verified by the
    submap alone: the return to the start (scans 3..7 from about scan 41)
    is closed, and no closure is onto a wrong place."""
    pts, ref = real
    n = 60
    cfg = MappingConfig(loop=LoopConfig(matcher="submap"))
    _, mapper = run_mapping(pts[:n], drifting_odometry(ref[:n], seed=1), cfg)
    loops = [e for e in mapper.edges if e.loop]
    assert any(e.i < 12 and e.j > 35 for e in loops)
    for e in loops:  # an aliased wall would be a metre or more off
        d = relative(relative(ref[e.i], ref[e.j]), e.z)
        assert math.hypot(d[0], d[1]) < 0.3 and abs(d[2]) < math.radians(4)


def _square_mapper(n_laps=2, side=10):
    """A mapper holding a graph (no scans) of a square walked twice in 1 m
    steps, odometry edges exact, and true closures from lap 2 onto lap 1."""
    truth = [np.zeros(3)]
    while len(truth) < 4 * side * n_laps:
        turn = math.pi / 2 if len(truth) % side == 0 else 0.0
        truth.append(compose(truth[-1], (1.0, 0.0, turn)))
    truth = np.array(truth)
    m = LaserMapper(MappingConfig())
    m.poses = list(truth.copy())
    odo = _sqrt_info(np.diag([0.03, 0.03, 0.01]) ** 2)
    m.edges = [Edge(k - 1, k, relative(truth[k - 1], truth[k]), odo)
               for k in range(1, len(truth))]
    loop = _sqrt_info(np.diag([0.03, 0.03, 0.01]) ** 2)
    for k in range(4 * side, len(truth), 3):
        m.edges.append(Edge(k - 4 * side, k, relative(truth[k - 4 * side], truth[k]), loop,
                            loop=True))
    return m, truth


def test_a_wrong_closure_cannot_bend_the_graph():
    """A closure onto the wrong place (an aliased corridor 2 m on, turned 10°)
    slipped into a graph of true ones: the robust kernel keeps it from pulling
    and the solve drops it; the poses stay on the truth."""
    m, truth = _square_mapper()
    n_loops = sum(e.loop for e in m.edges)
    wrong = Edge(5, 52, compose(relative(truth[5], truth[52]), (2.0, 0.0, math.radians(10))),
                 _sqrt_info(np.diag([0.03, 0.03, 0.01]) ** 2), loop=True)
    m.edges.append(wrong)
    m.poses = [compose(p, (0.05, -0.05, 0.01)) for p in m.poses]  # a start off the solution
    m.optimise()
    assert m.loop_rejected == 1 and not any(e is wrong for e in m.edges)
    assert sum(e.loop for e in m.edges) == n_loops
    x = np.array(m.poses)
    err = [relative(truth[0], truth[k]) - relative(x[0], x[k]) for k in range(len(truth))]
    assert np.max(np.hypot(*np.array(err)[:, :2].T)) < 0.01
