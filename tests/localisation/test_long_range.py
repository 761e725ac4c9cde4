"""Long-range ties (long_range.py): scans matched against a whole earlier
region of the map, kept only in groups that agree."""

import math

import numpy as np

from app.core.localisation.long_range import LongRangeConfig, _largest_group, long_range_ties
from app.core.localisation.se2 import compose, relative
from app.core.localisation.slam import scan_points


def test_an_aliased_match_is_left_out_of_the_agreeing_group():
    """Four matches onto one region agree with the solved chain; a fifth,
    a wall-spacing (0.7 m) off, scores as well alone but agrees with none."""
    chain = np.array([compose((0.0, 0.0, 0.0), (k, 0.0, 0.02 * k)) for k in range(6)])
    poses = np.array([compose((0.3, -0.2, 0.03), p) for p in chain])  # drifted estimate
    path = np.arange(6.0)
    found = [(k, compose((0.0, 0.0, 0.0), chain[k]), np.eye(3), 0.5) for k in range(5)]
    found[2] = (2, compose(chain[2], (0.7, 0.0, 0.0)), np.eye(3), 0.5)
    group = _largest_group(found, poses, path, LongRangeConfig())
    assert sorted(g[0] for g in group) == [0, 1, 3, 4]


def turned_start(edmonton, n=170):
    """Edmonton's first ``n`` reference poses (in the first scan's frame) with the
    start area (scans 0..59) turned 2° about scan 62, as drift along the unclosed
    stretch would leave it: (scan points, reference poses, poses, path length at
    each, the ties' covariance floor)."""
    pts = scan_points(edmonton)
    ref = np.array([s.pose for s in edmonton.scans])
    ref = np.array([relative(ref[0], p) for p in ref])
    poses = ref[:n].copy()
    pivot = poses[62]
    turn = compose(pivot, compose((0.0, 0.0, math.radians(2)), relative(pivot, np.zeros(3))))
    poses[:60] = [compose(turn, p) for p in poses[:60]]
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:n, :2], axis=0).T))]
    floor = np.diag([0.03, 0.03, math.radians(0.5)]) ** 2
    return pts, ref, poses, path, floor


def test_edmonton_start_is_tied_to_the_pass_100_m_later(edmonton):
    """Edmonton's start area (scans 0..59) is turned 2° about scan 62 as drift
    along the unclosed stretch would leave it; scans 148..156, 14 m away and
    100 m of path later, are tied to it, each tie within 0.3 m / 1.5° of the
    reference; no old scan within 10 m (loop closure's reach) sees them."""
    pts, ref, poses, path, floor = turned_start(edmonton)
    n = len(poses)
    ties = long_range_ties(poses, path, [(k, pts[k]) for k in range(n)], 4.0, floor,
                           LongRangeConfig(chunk_m=60.0))
    onto_start = [c for c in ties if c.old < 60 and 140 <= c.new <= 160]
    assert len(onto_start) >= 3
    for c in onto_start:
        assert np.min(np.hypot(*(ref[:60, :2] - ref[c.new, :2]).T)) > 10.0
        truth = relative(ref[c.old], ref[c.new])
        d = relative(truth, c.z)
        assert math.hypot(d[0], d[1]) < 0.3 and abs(d[2]) < math.radians(1.5)
    for c in ties:  # every tie, onto any region, is right
        d = relative(relative(ref[c.old], ref[c.new]), c.z)
        assert math.hypot(d[0], d[1]) < 0.4 and abs(d[2]) < math.radians(2)


def test_no_region_near_enough_gives_no_tie():
    """Regions 40 m apart, beyond the 25 m reach: nothing is matched."""
    pts = [np.column_stack((np.linspace(-3, 3, 60), np.full(60, 2.0)))] * 4
    poses = np.array([(0.0, 0.0, 0.0), (40.0, 0.0, 0.0), (80.0, 0.0, 0.0), (120.0, 0.0, 0.0)])
    path = np.array([0.0, 40.0, 80.0, 120.0])
    ties = long_range_ties(poses, path, list(enumerate(pts)), 4.0, np.eye(3) * 1e-4,
                           LongRangeConfig())
    assert ties == []


def _turned_start(edmonton, every: int, turn_deg: float):
    """Every ``every``-th of edmonton's first 170 scans at their reference
    poses, the start (reference scans 0..59) turned ``turn_deg`` about
    scan 62, as one match a few degrees off at that turn leaves the map;
    (poses, path, landmarks, reference poses)."""
    pts = scan_points(edmonton)[:170:every]
    ref = np.array([s.pose for s in edmonton.scans])[:170:every]
    ref = np.array([relative(ref[0], p) for p in ref])
    poses = ref.copy()
    pivot = poses[62 // every]
    turn = compose(pivot, compose((0.0, 0.0, math.radians(turn_deg)),
                                  relative(pivot, np.zeros(3))))
    start = 60 // every
    poses[:start] = [compose(turn, p) for p in poses[:start]]
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))]
    return poses, path, [(k, pts[k]) for k in range(len(pts))], ref, start


def _ties_onto_start_are_right(ties, ref, start):
    onto_start = [c for c in ties if c.old < start and c.new > start]
    for c in ties:  # every tie, onto any region, is right
        d = relative(relative(ref[c.old], ref[c.new]), c.z)
        assert math.hypot(d[0], d[1]) < 0.4 and abs(d[2]) < math.radians(2)
    return onto_start


def test_keyframes_2_m_apart_still_tie_the_start(edmonton):
    """Every second edmonton scan (keyframes about 2 m apart): the landmarks
    matched are chosen by path (every 2 m), not as every second keyframe
    (one per 4 m, too few to make a group of three agreeing matches), and
    the turned start is tied to the pass 100 m later."""
    poses, path, lms, ref, start = _turned_start(edmonton, 2, 2.0)
    floor = np.diag([0.03, 0.03, math.radians(0.5)]) ** 2
    ties = long_range_ties(poses, path, lms, 4.0, floor, LongRangeConfig(chunk_m=60.0))
    assert len(_ties_onto_start_are_right(ties, ref, start)) >= 3


def test_the_search_window_grows_with_the_path_to_the_region(edmonton):
    """The start turned 5°: beyond a fixed ±4° window, but 90 m and more of
    path from the scans that see it, whose window has grown to 6°; the
    ties found put it back."""
    poses, path, lms, ref, start = _turned_start(edmonton, 1, 5.0)
    floor = np.diag([0.03, 0.03, math.radians(0.5)]) ** 2
    ties = long_range_ties(poses, path, lms, 4.0, floor, LongRangeConfig(chunk_m=60.0))
    assert len(_ties_onto_start_are_right(ties, ref, start)) >= 3


def test_landmarks_are_sampled_by_path_not_by_count():
    from app.core.localisation.long_range import _every_m

    path = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 4.0, 6.0, 8.5, 9.0])
    assert _every_m(np.arange(9), path, 2.0) == [0, 4, 5, 6, 7]
