"""The compiled trimmed circle fit gives what the numpy fit gives, bit for bit."""

import numpy as np
import pytest

from app.core.meter.circle_trim import _trimmed_circle_numpy, trimmed_circle


def _ring(rng, n, outliers, centre=(150.0, 148.0), r=95.0, noise=0.4):
    t = rng.uniform(0, 2 * np.pi, n)
    rr = r + rng.normal(0, noise, n)
    rr[:outliers] += rng.uniform(4, 15, outliers)  # numerals, major ticks
    return np.column_stack([centre[0] + rr * np.sin(t), centre[1] - rr * np.cos(t)])


@pytest.mark.parametrize("seed", range(12))
def test_same_as_numpy_fit(seed):
    rng = np.random.default_rng(seed)
    pts = _ring(rng, int(rng.integers(25, 700)), int(rng.integers(0, 60)))
    got, want = trimmed_circle(pts), _trimmed_circle_numpy(pts)
    assert (got is None) == (want is None)
    if want is not None:
        assert got == want  # the same floats: compared as fits elsewhere
        (m, n), rms, r = got
        assert abs(m - 150.0) < 1.0 and abs(n - 148.0) < 1.0 and abs(r - 95.0) < 1.0


def test_exact_circle_about_the_start_keeps_numpys_rounding():
    # the marks' ends all on one polar row: an exact circle, rms at rounding level; two
    # such fits are told apart by that rounding, so it must be numpy's
    th = np.radians(np.arange(0, 270, 0.5))
    for c in ((150.0, 150.0), (154.0, 153.0)):
        pts = np.column_stack([c[0] + 100.0 * np.sin(th), c[1] - 100.0 * np.cos(th)])
        assert trimmed_circle(pts) == _trimmed_circle_numpy(pts)


def test_too_few_points_and_scattered_points():
    rng = np.random.default_rng(5)
    assert trimmed_circle(_ring(rng, 15, 0)) is None
    for _ in range(5):
        pts = rng.uniform(0, 300, (200, 2))
        assert trimmed_circle(pts) == _trimmed_circle_numpy(pts)


def test_collinear_points_fall_back_to_numpy():
    pts = np.column_stack([np.arange(40.0), 2.0 * np.arange(40.0)])
    assert trimmed_circle(pts) == _trimmed_circle_numpy(pts)
