"""Steps written for speed give the values of the plain forms they stand for, to the last
bit: order statistics and the comb's floor (numpy's and scipy's), and unwraps kept for reuse."""

import math

import numpy as np
import pytest
from scipy.ndimage import minimum_filter1d

from app.core.meter import order_stats
from app.core.meter.dial import _row_medians
from app.core.meter.tick_comb import FLOOR_DEG, _floor


def _arrays(seed: int):
    rng = np.random.default_rng(seed)
    for k in range(400):
        n = int(rng.integers(1, 300)) if k % 8 else int(rng.integers(300, 4000))
        a = (rng.random(n), rng.integers(0, 5, n).astype(float), rng.normal(size=n) * 1e3,
             np.round(rng.random(n) * 255) / 7, rng.exponential(size=n))[k % 5]
        a = a.astype((np.float32, np.float64)[k % 2])
        if k % 3 == 0 and n > 3:  # 2-D, and a strided view
            a = a.reshape(2, -1)[:, ::2] if n % 2 == 0 else a.reshape(-1, 1)
        yield a


def _same(x, y) -> bool:
    return float(x) == float(y) or (math.isnan(float(x)) and math.isnan(float(y)))


@pytest.mark.parametrize("seed", range(4))
def test_quantile_percentile_and_median_are_numpys(seed):
    for a in _arrays(seed):
        for q in (0.0, 0.1, 0.25, 0.3, 0.5, 0.75, 0.9, 0.95, 1.0):
            assert _same(order_stats.quantile(a, q), np.quantile(a, q)), (a.shape, q)
        for q in (10.0, 25.0, 50.0, 75.0, 90.0, 99.0):
            assert _same(order_stats.percentile(a, q), np.percentile(a, q)), (a.shape, q)
        assert _same(order_stats.median(a), np.median(a)), a.shape


def test_a_nan_gives_nan_as_in_numpy():
    rng = np.random.default_rng(9)
    for n in (1, 2, 3, 10, 11):
        for _ in range(10):
            a = rng.random(n).astype(np.float32)
            a[rng.integers(0, n)] = np.nan
            for q in (0.0, 0.5, 0.9, 1.0):
                assert _same(order_stats.quantile(a, q), np.quantile(a, q))
            assert _same(order_stats.median(a), np.median(a))


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64, np.uint8])
def test_the_combs_floor_is_scipys_minimum_filter(dtype):
    rng = np.random.default_rng(3)
    for n in (720, 1440, 30, 7):
        for step in (0.5, 0.25, 1.0):
            e = (rng.random(n) * 40).astype(dtype)
            got = _floor(e, step)
            want = minimum_filter1d(e, 2 * int(round(FLOOR_DEG / step)) + 1, mode="wrap")
            assert got.dtype == want.dtype and np.array_equal(got, want), (n, step)


def test_row_medians_are_numpys_for_uint8_rows():
    rng = np.random.default_rng(4)
    for width in (119, 120, 1, 2):
        v = rng.integers(0, 256, (89, width)).astype(np.uint8)
        got = _row_medians(v)
        want = np.median(v.astype(np.float32), axis=1)
        assert got.dtype == want.dtype and np.array_equal(got, want)


def test_an_unchanging_image_is_unwrapped_once_per_centre_with_the_same_values():
    from app.core.meter.dial import FACE_RADIUS
    from app.core.meter.scale import polar

    rng = np.random.default_rng(5)
    img = (rng.random((300, 300)) * 255).astype(np.float32)
    frozen = img.copy()
    frozen.flags.writeable = False
    for c in ((150.0, 150.0), (147.3, 152.9)):
        for rows in (None, slice(5, 30)):
            args = (c, 0.45 * FACE_RADIUS, 0.97 * FACE_RADIUS, rows)
            a, rs_a = polar(img, *args)
            b, rs_b = polar(frozen, *args)
            assert np.array_equal(a, b) and np.array_equal(rs_a, rs_b)
            assert polar(frozen, *args)[0] is b and not b.flags.writeable  # kept, read-only
            assert polar(img, *args)[0] is not a  # a writeable image is unwrapped afresh
    # another centre is another unwrap
    assert not np.array_equal(polar(frozen, (140.0, 150.0), 60.0, 130.0)[0],
                              polar(frozen, (150.0, 150.0), 60.0, 130.0)[0])


def test_a_pass_results_float_images_are_made_once_as_made_afresh():
    from app.core.meter.geometry import Line
    from app.core.meter.ring_centre import hidden_float, needle_only, pass_images

    rng = np.random.default_rng(6)
    dark = (rng.random((300, 300)) * 255).astype(np.uint8)
    pmask = np.zeros((300, 300), np.uint8)
    pmask[148:153, 150:260] = 1
    res = {"dark": dark, "pmask": pmask, "line": Line((150.0, 150.0), (1.0, 0.0))}
    darkf, hidden = pass_images(res)
    assert np.array_equal(darkf, dark.astype(np.float32))
    assert np.array_equal(hidden, hidden_float(needle_only(pmask, res["line"])))
    assert not darkf.flags.writeable and not hidden.flags.writeable
    again = pass_images(res)
    assert again[0] is darkf and again[1] is hidden
    # another pass (another dark image) gets its own
    other = dict(res, dark=dark.copy())
    assert pass_images(other)[0] is not darkf


def _plain_focus(gray, pivot, radius, shape, shift):
    """:func:`rim_focus.focus` as first written: one remap per shift, numpy's median."""
    import cv2

    from app.core.meter import rim_focus as rf
    inv = np.linalg.inv(rf._unit(shape))
    dx, dy, k = rf._grid(radius)
    mx = (pivot[0] + inv[0, 0] * dx + inv[0, 1] * dy + shift[0] * k).astype(np.float32)
    my = (pivot[1] + inv[1, 0] * dx + inv[1, 1] * dy + shift[1] * k).astype(np.float32)
    prof = np.median(cv2.remap(gray, mx, my, cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REPLICATE), axis=1)
    step = prof[2:] - prof[:-2]
    return float(step @ step)


def test_rim_focus_batched_unwraps_are_the_plain_ones():
    from app.core.meter import rim_focus as rf
    rng = np.random.default_rng(3)
    gray = (rng.random((120, 160)) * 255).astype(np.float32)
    for _ in range(6):
        shape = np.eye(2) + rng.normal(scale=0.05, size=(2, 2))
        pivot, radius = (80.0 + rng.normal(), 60.0 + rng.normal()), float(rng.uniform(20, 40))
        shifts = [tuple(rng.normal(scale=3.0, size=2)) for _ in range(8)]
        grid = rf._grid(radius)
        many = rf._focus_many(gray, rf._view_maps(pivot, shape, grid), grid[2], shifts)
        assert many == [_plain_focus(gray, pivot, radius, shape, s) for s in shifts]
