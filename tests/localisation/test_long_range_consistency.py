"""The long-range ties' agreement test by the matches' and the chain's
covariances (long_range.py, 3.; Mangelson et al. 2018's pairwise consistency),
the uniqueness test (4.) and the gate by the graph's marginal (5.)."""

import math

import numpy as np

from app.core.localisation.long_range import (
    LongRangeConfig,
    _agree,
    _largest_group,
    _moved,
    chain_covariance,
    graph_marginal,
    long_range_ties,
)
from app.core.localisation.pose_graph import Edge
from app.core.localisation.se2 import compose, relative

from .test_long_range import turned_start

SIG_TH = math.radians(0.5)


def test_a_chains_heading_errors_move_its_far_end_by_their_lever_arms():
    poses = np.array([(float(k), 0.0, 0.0) for k in range(5)])
    covs = [np.zeros((3, 3))] + [np.diag([0.0, 0.0, SIG_TH ** 2])] * 4
    c = chain_covariance(poses, covs, 0, 4, np.zeros((3, 3)))
    # steps 1..4 turn node 4 about nodes 1..4: lever arms 3, 2, 1, 0 m
    np.testing.assert_allclose(c[1, 1], SIG_TH ** 2 * (9 + 4 + 1 + 0))
    np.testing.assert_allclose(c[2, 2], 4 * SIG_TH ** 2)
    np.testing.assert_allclose(c[0, 0], 0.0, atol=1e-15)  # no error along the chain
    np.testing.assert_allclose(chain_covariance(poses, covs, 4, 0, np.zeros((3, 3))), c)
    floor = np.diag([0.03, 0.03, 0.0]) ** 2
    c2 = chain_covariance(poses, covs, 0, 4, floor)
    np.testing.assert_allclose(c2[0, 0], 4 * 0.03 ** 2)


def _matches(off_a, off_b, cov):
    """Two matches of nodes 0 and 4 of a straight 4 m chain, each moved by
    its offset (world frame) from the chain's own poses."""
    poses = np.array([(float(k), 0.0, 0.0) for k in range(5)])
    a = (0, poses[0] + np.asarray(off_a, float), cov, 0.5)
    b = (4, poses[4] + np.asarray(off_b, float), cov, 0.5)
    return a, b, poses, np.arange(5.0)


def test_matches_weakly_held_along_a_direction_may_part_along_it_and_no_further():
    cfg = LongRangeConfig()
    loose_x = np.diag([0.25 ** 2, 0.02 ** 2, math.radians(0.2) ** 2])  # a far wall seen edge-on
    chain = np.diag([0.03 ** 2, 0.03 ** 2, math.radians(0.3) ** 2])
    a, b, poses, path = _matches((0.0, 0.0, 0.0), (0.4, 0.0, 0.0), loose_x)
    assert not _agree(a, b, poses, path, cfg)  # the fixed test: 0.4 m > 0.19 m
    assert _agree(a, b, poses, path, cfg, chain)  # 1.1 σ along the free direction
    a, b, poses, path = _matches((0.0, 0.0, 0.0), (0.0, 0.4, 0.0), loose_x)
    assert not _agree(a, b, poses, path, cfg, chain)  # 0.4 m across it: 11 σ


def test_an_aliased_match_still_stands_alone():
    """As test_long_range's: a match a wall-spacing (0.7 m) off among four
    that agree with the chain, now by the covariances."""
    chain = np.array([compose((0.0, 0.0, 0.0), (k, 0.0, 0.02 * k)) for k in range(6)])
    poses = np.array([compose((0.3, -0.2, 0.03), p) for p in chain])
    path = np.arange(6.0)
    cov = np.diag([0.06 ** 2, 0.06 ** 2, math.radians(0.5) ** 2])
    found = [(k, chain[k], cov, 0.5) for k in range(5)]
    found[2] = (2, compose(chain[2], (0.7, 0.0, 0.0)), cov, 0.5)
    steps = [np.diag([0.03 ** 2, 0.03 ** 2, math.radians(0.3) ** 2])] * 6
    floor = np.diag([0.03, 0.03, math.radians(0.5)]) ** 2
    group = _largest_group(found, poses, path, LongRangeConfig(),
                           lambda i, j: chain_covariance(poses, steps, i, j, floor))
    assert sorted(g[0] for g in group) == [0, 1, 3, 4]


def test_edmonton_start_is_tied_by_the_covariance_test_too(edmonton):
    """test_long_range's edmonton case (the start turned 2° about scan 62),
    with the steps' covariances given: the start is tied, every tie right."""
    pts, ref, poses, path, floor = turned_start(edmonton)
    n = len(poses)
    steps = [np.zeros((3, 3))] + [np.diag([0.03 ** 2, 0.03 ** 2, math.radians(0.4) ** 2])] * (n - 1)
    ties = long_range_ties(poses, path, [(k, pts[k]) for k in range(n)], 4.0, floor,
                           LongRangeConfig(chunk_m=60.0), step_covs=steps)
    assert len([c for c in ties if c.old < 60 and 140 <= c.new <= 160]) >= 3
    for c in ties:
        d = relative(relative(ref[c.old], ref[c.new]), c.z)
        assert math.hypot(d[0], d[1]) < 0.4 and abs(d[2]) < math.radians(2)


UNIQUE = LongRangeConfig(unique_ratio=2.0)  # the uniqueness test (long_range.py, 4.)


def _aliased_three_right_two(shift_m=1.5):
    """Five matches onto one region from scans 0..4 of a straight chain 2 m
    apart: scans 0, 1, 2 all slid by the same ``shift_m`` along the hall (a
    wall spacing; they agree with each other), scans 3, 4 where the chain
    puts them."""
    chain = np.array([compose((0.0, 0.0, 0.0), (2.0 * k, 0.0, 0.0)) for k in range(5)])
    path = 2.0 * np.arange(5.0)
    cov = np.diag([0.05 ** 2, 0.05 ** 2, math.radians(0.5) ** 2])
    found = [(k, compose(chain[k], (shift_m, 0.0, 0.0)) if k < 3 else chain[k], cov, 0.5)
             for k in range(5)]
    return chain, path, found


def test_a_consistently_aliased_group_against_a_right_pair_is_ambiguous():
    """Three aliased matches outnumber two right ones; pairwise agreement
    alone keeps the three (unique_ratio 0, the default), the uniqueness test
    keeps neither: the map sides with the pair."""
    chain, path, found = _aliased_three_right_two()
    before = _largest_group(found, chain, path, LongRangeConfig())  # the default: off
    assert sorted(g[0] for g in before) == [0, 1, 2]
    assert _largest_group(found, chain, path, UNIQUE) == []


def test_a_clear_majority_is_kept_beside_a_lone_rival():
    """Four right matches and one aliased: the four are at least twice the
    rival, so they are kept."""
    chain, path, found = _aliased_three_right_two()
    found = [(k, chain[k] if k != 2 else compose(chain[2], (1.5, 0.0, 0.0)), c, f)
             for k, _, c, f in found]
    group = _largest_group(found, chain, path, UNIQUE)
    assert sorted(g[0] for g in group) == [0, 1, 3, 4]


def test_matches_too_far_apart_to_compare_are_no_rivals():
    """Two groups onto one region more than pair_path_m of path apart cannot
    conflict: the larger one is kept."""
    chain = np.array([compose((0.0, 0.0, 0.0), (2.0 * k, 0.0, 0.0)) for k in range(5)])
    path = np.array([0.0, 2.0, 4.0, 40.0, 42.0])
    cov = np.diag([0.05 ** 2, 0.05 ** 2, math.radians(0.5) ** 2])
    found = [(k, chain[k] if k < 3 else compose(chain[k], (1.5, 0.0, 0.0)), cov, 0.5)
             for k in range(5)]
    group = _largest_group(found, chain, path, UNIQUE)
    assert sorted(g[0] for g in group) == [0, 1, 2]


def test_a_comparable_rival_is_no_veto_when_the_map_sides_with_the_larger_group():
    """Three matches where the solved map has their scans against two
    aliased ones that agree with each other: the three are kept (as on
    edmonton's turned start, where a wrong pair must not veto the ties)."""
    chain, path, found = _aliased_three_right_two()
    found = [(k, chain[k] if k < 3 else compose(chain[k], (1.5, 0.0, 0.0)), c, f)
             for k, _, c, f in found]
    group = _largest_group(found, chain, path, UNIQUE)
    assert sorted(g[0] for g in group) == [0, 1, 2]


def test_edmonton_start_is_still_tied_with_the_uniqueness_test(edmonton):
    """test_long_range's edmonton case by the covariance test: the right three
    ties onto the turned start have a rival pair of wrong matches, but move
    the map less than it, so the uniqueness test keeps them."""
    pts, ref, poses, path, floor = turned_start(edmonton)
    n = len(poses)
    steps = [np.zeros((3, 3))] + [np.diag([0.03 ** 2, 0.03 ** 2, math.radians(0.4) ** 2])] * (n - 1)
    ties = long_range_ties(poses, path, [(k, pts[k]) for k in range(n)], 4.0, floor,
                           LongRangeConfig(chunk_m=60.0, unique_ratio=2.0), step_covs=steps)
    assert len([c for c in ties if c.old < 60 and 140 <= c.new <= 160]) >= 3


def _straight_chain(n=5, sd_xy=0.3, sd_th_deg=3.0):
    poses = np.array([(2.0 * k, 0.0, 0.0) for k in range(n)])
    cov = np.diag([sd_xy ** 2, sd_xy ** 2, math.radians(sd_th_deg) ** 2])
    edges = [Edge(k - 1, k, relative(poses[k - 1], poses[k]), np.linalg.cholesky(
        np.linalg.inv(cov)).T) for k in range(1, n)]
    return poses, cov, edges


def test_the_graph_marginal_of_a_chain_is_its_compounded_steps():
    """With only steps, the marginal of the last node with the first held is
    the steps' covariances compounded along the chain (chain_covariance)."""
    poses, cov, edges = _straight_chain()
    marg = graph_marginal(poses, edges, 0, [4])[4]
    steps = [np.zeros((3, 3))] + [cov] * 4
    assert np.allclose(marg, chain_covariance(poses, steps, 0, 4, np.zeros((3, 3))), rtol=1e-3)
    mid = graph_marginal(poses, edges, 2, [2, 4])  # held in the middle: half the chain
    assert np.allclose(mid[2], 0.0) and np.all(np.diag(mid[4]) < np.diag(marg))
    assert np.allclose(mid[4], chain_covariance(poses, steps, 2, 4, np.zeros((3, 3))), rtol=1e-3)


def test_an_aliased_match_is_gated_where_a_loop_edge_holds_the_map():
    """A match moving the last node 1.5 m along the chain: within the loose
    chain's marginal it passes the gate, but with a loop edge (5 cm) holding
    that node to the held one it is far outside."""
    poses, cov, edges = _straight_chain()
    match = (4, compose(poses[4], (1.5, 0.0, 0.0)), np.diag([0.05 ** 2, 0.05 ** 2, 1e-4]), 0.5)
    loose = graph_marginal(poses, edges, 0, [4])[4]
    loop = Edge(0, 4, relative(poses[0], poses[4]), np.diag([20.0, 20.0, 100.0]), True)
    held = graph_marginal(poses, edges + [loop], 0, [4])[4]
    gate = LongRangeConfig().marginal_chi2  # χ²₃ at 99.9 % (the default)
    assert _moved(match, poses, loose) < gate < _moved(match, poses, held)
