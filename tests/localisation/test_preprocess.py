import numpy as np

from app.core.localisation.preprocess import (
    PreprocessConfig,
    preprocess,
    range_filter,
    segment,
    smooth,
)


def test_range_filter_drops_zero_dust_no_return_and_nan():
    r = np.array([0.0, 0.03, 1.0, 81.91, 5.0, np.nan, 40.0, 29.0])
    ok = range_filter(r, min_range_m=0.05, max_range_m=50.0, no_return_m=81.91)
    assert ok.tolist() == [False, False, True, False, True, False, True, True]
    assert not range_filter(r, 0.05, 30.0)[6]  # beyond the usable range


def test_segmentation_drops_a_mixed_point_between_near_and_far_objects():
    # a near wall (2 m), one beam half on it and half on the far wall (3.5 m), far wall (5 m)
    r = np.r_[np.full(10, 2.0), 3.5, np.full(10, 5.0)]
    labels = segment(r, np.ones(r.size, bool), jump_m=0.3, jump_ratio=0.05, min_segment_points=3)
    assert labels[10] == -1
    assert len(set(labels[:10])) == 1 and len(set(labels[11:])) == 1
    assert labels[0] != labels[-1]
    # an invalid beam also splits, and segments shorter than the minimum go
    valid = np.ones(r.size, bool)
    valid[2] = False
    assert (segment(r, valid, 0.3, 0.05, 3)[:2] == -1).all()


def test_smoothing_reduces_jitter_within_a_segment_but_keeps_the_step():
    rng = np.random.default_rng(1)
    truth = np.r_[np.full(50, 2.0), np.full(50, 4.0)]
    r = truth + rng.normal(0, 0.01, truth.size)
    labels = segment(r, np.ones(r.size, bool), 0.3, 0.05, 3)
    s = smooth(r, labels, 5)
    assert np.std(s[5:45] - 2.0) < 0.8 * np.std(r[5:45] - 2.0)
    assert abs(s[49] - 2.0) < 0.03 and abs(s[50] - 4.0) < 0.03  # no rounding across the jump
    assert np.array_equal(smooth(r, labels, 1), r)


def test_preprocess_chains_the_steps_into_sensor_frame_points():
    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    r = np.full(181, 3.0)
    r[0] = 0.0
    r[90] = 81.9
    pts = preprocess(r, angles, PreprocessConfig(), no_return_m=81.9)
    assert len(pts) == 179
    assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), 3.0)
    assert pts[:, 0].min() > -1e-9  # all in front of or beside the sensor


def test_smoothing_leaves_a_reading_that_differs_from_its_neighbours_by_more_than_jitter():
    # a far wall at 20 m with a chair leg at 19.2 m in one beam: one segment
    # (the jump is under 8 % of the range), but no range jitter to smooth
    r = np.r_[np.full(5, 20.0), 19.2, np.full(5, 20.0)]
    labels = segment(r, np.ones(r.size, bool), 0.3, 0.08, 3)
    assert len(set(labels.tolist())) == 1
    plain = smooth(r, labels, 3)
    assert plain[5] == 20.0  # the plain median moves the leg onto the wall
    kept = smooth(r, labels, 3, tol_m=0.05, tol_ratio=0.01)
    assert kept[5] == 19.2 and kept[4] == 20.0 and kept[6] == 20.0
    # jitter within the tolerance is still smoothed
    j = np.r_[np.full(5, 20.0), 20.1, np.full(5, 20.0)]
    assert smooth(j, labels, 3, tol_m=0.05, tol_ratio=0.01)[5] == 20.0
