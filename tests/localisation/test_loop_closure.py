import math

import numpy as np
import pytest

from app.core.localisation.evaluate import ate_m, drifting_odometry
from app.core.localisation.icp import IcpConfig
from app.core.localisation.loop_closure import (
    Closure,
    LoopConfig,
    ViewOverlap,
    consistent,
    cycle_error,
    graph_path_m,
    rank_candidates,
    verify,
)
from app.core.localisation.mapping import MappingConfig
from app.core.localisation.se2 import compose, relative, transform_points
from app.core.localisation.slam import run_mapping, scan_points

pytestmark = pytest.mark.slow(25)


@pytest.fixture(scope="module")
def real(freiburg):
    pts = scan_points(freiburg)
    ref = np.array([s.pose for s in freiburg.scans])
    return pts, np.array([relative(ref[0], p) for p in ref])


def _group(pts, ref, lo, hi, at=None):
    """Scans lo..hi-1 in the world frame; ``at``: moved so that scan lo sits there."""
    shift = np.zeros(3) if at is None else compose(at, relative(ref[lo], np.zeros(3)))
    return np.vstack([transform_points(compose(shift, ref[i]), pts[i]) for i in range(lo, hi)])


def test_graph_path_takes_the_shortcut_through_an_accepted_closure():
    path = np.arange(0.0, 100.0)  # one metre per node
    d = graph_path_m(path, 90, np.array([5, 50, 85]), [])
    assert d == pytest.approx([85.0, 40.0, 5.0])
    d = graph_path_m(path, 90, np.array([5, 50, 85]), [(3, 80)])  # node 80 closed onto node 3
    assert d == pytest.approx([2.0 + 10.0, 40.0, 5.0])


def test_two_true_closures_agree_and_a_displaced_one_does_not():
    truth = [np.zeros(3)]
    for _ in range(40):  # a 10 m square walked twice, 1 m steps
        turn = math.pi / 2 if len(truth) % 10 == 0 else 0.0
        truth.append(compose(truth[-1], (1.0, 0.0, turn)))
    poses = np.array(truth)
    path = np.arange(len(poses), dtype=float)
    cov = np.eye(3) * 1e-4
    a = Closure(3, 23, relative(poses[3], poses[23]), cov, False, 0.5)
    b = Closure(5, 25, relative(poses[5], poses[25]), cov, False, 0.5)
    assert np.allclose(cycle_error(a, b, poses), 0.0, atol=1e-9)
    assert consistent(a, b, poses, path, LoopConfig())
    wrong = Closure(5, 25, compose(b.z, (1.2, 0.0, 0.0)), cov, False, 0.5)  # aliased 1.2 m on
    assert not consistent(a, wrong, poses, path, LoopConfig())
    turned = Closure(5, 25, compose(b.z, (0.0, 0.0, math.radians(6))), cov, False, 0.5)
    assert not consistent(a, turned, poses, path, LoopConfig())


def test_candidates_are_the_places_the_scan_sees(real):
    pts, ref = real
    olds = [(i, ref[i], pts[i]) for i in range(0, 30)]
    picked = rank_candidates(ref[41], pts[41], olds, np.full(len(olds), 4.0), ViewOverlap(),
                             LoopConfig())
    assert picked, "scan 41 stands where scans 3..7 stood"
    for n in picked:
        assert math.hypot(*(ref[olds[n][0]][:2] - ref[41][:2])) < 4.0
    # the same scan placed far from every old landmark has no candidate
    far = compose(ref[41], (30.0, 30.0, 0.0))
    assert rank_candidates(far, pts[41], olds, np.full(len(olds), 4.0), ViewOverlap(),
                           LoopConfig()) == []


def test_verification_recovers_a_revisit_from_a_poor_guess(real):
    pts, ref = real
    group = _group(pts, ref, 3, 8)
    guess = compose(ref[41], (0.6, -0.4, math.radians(7)))
    r, g, searched = verify(pts[41], group, guess, 1.0, math.radians(12), IcpConfig(),
                            LoopConfig(), may_search=True)
    assert g is not None
    e = relative(ref[41], r.pose)
    assert math.hypot(e[0], e[1]) < 0.08 and abs(e[2]) < math.radians(1.0)


def test_verification_refuses_a_place_the_scan_has_never_seen(real):
    pts, ref = real
    elsewhere = _group(pts, ref, 150, 155, at=ref[41])  # another room put where scan 41 is
    r, g, _ = verify(pts[41], elsewhere, ref[41], 1.0, math.radians(12), IcpConfig(),
                     LoopConfig(), may_search=True)
    assert g is None


def test_final_pass_adds_edges_and_no_closure_is_false(real):
    pts, ref = real
    odo = drifting_odometry(ref, seed=3)
    est, mapper = run_mapping(pts, odo, MappingConfig(final_pass=True))
    assert mapper.final_closures > 50
    assert ate_m(est, ref) < 0.1
    for e in mapper.edges:
        if e.loop:  # no closure onto a wrong place (an aliased wall is a metre or more off)
            d = relative(relative(ref[e.i], ref[e.j]), e.z)
            assert math.hypot(d[0], d[1]) < 0.3 and abs(d[2]) < math.radians(4)
