"""Helpers written for speed against the plain forms they stand for, on random inputs.

The reader's decisions sit on thresholds of these numbers, so the fast forms must give the
same values (to the last bit, except the closed-form line, which is compared with
``np.polyfit`` to rounding).
"""

import math

import numpy as np
import pytest

from app.core.meter.arc_fit import STEP, _run_around
from app.core.meter.counts import col_counts, row_counts
from app.core.meter.dial import median_u8
from app.core.meter.draws import ransac_samples
from app.core.meter.keypoints import IN, OUT, _decode
from app.core.meter.needle import _lobe, _row_percentile
from app.core.meter.needle_line import _lsq_line
from app.core.meter.ring_centre import _COS64, _SIN64
from app.core.meter.tick_band import long_columns, short_runs, tick_ring_rows, tick_rings


@pytest.mark.parametrize("seed", range(6))
def test_counts_are_numpys_counts_and_means(seed):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        m = rng.random((int(rng.integers(1, 80)), int(rng.integers(1, 760)))) < rng.random()
        assert np.array_equal(row_counts(m), np.count_nonzero(m, axis=1))
        assert np.array_equal(col_counts(m), np.count_nonzero(m, axis=0))
        # counts / n is numpy's mean of the booleans, bit for bit
        assert np.array_equal(row_counts(m) / m.shape[1], m.mean(axis=1))
        assert np.array_equal(col_counts(m) / m.shape[0], m.mean(axis=0))
        # slices (rows of a larger image; a strided view) and a comparison's result
        lo = int(rng.integers(0, m.shape[0]))
        sub = m[lo:lo + 5]
        assert np.array_equal(col_counts(sub), np.count_nonzero(sub, axis=0))
        assert np.array_equal(row_counts(m[:, ::2]), np.count_nonzero(m[:, ::2], axis=1))
        if m.shape[1] > 1:
            d = m[:, 1:] != m[:, :-1]
            assert np.array_equal(row_counts(d), np.count_nonzero(d, axis=1))
    empty = np.zeros((3, 0), bool)
    assert row_counts(empty).tolist() == [0, 0, 0]
    assert col_counts(empty).tolist() == []


def test_median_u8_is_numpys_median_under_the_mask():
    rng = np.random.default_rng(3)
    for k in range(300):
        h, w = int(rng.integers(1, 90)), int(rng.integers(1, 90))
        img = rng.integers(0, 256, (h, w)).astype(np.uint8)
        if k % 3 == 0:  # few distinct values: the middle pair often straddles a gap
            img = (img // 97 * 97).astype(np.uint8)
        mask = (rng.random((h, w)) < rng.random()).astype(np.uint8)
        if mask.any():
            assert median_u8(img, mask) == float(np.median(img[mask > 0]))
        else:
            assert math.isnan(median_u8(img, mask))
    # a view into a larger image (as the needle finder's crop about the pivot)
    big = rng.integers(0, 256, (120, 130)).astype(np.uint8)
    view = big[10:90, 20:111]
    yy, xx = np.ogrid[0:80, 0:91]
    disc = (xx - 45.3) ** 2 + (yy - 39.8) ** 2 < 37.0 ** 2
    assert median_u8(view, disc.view(np.uint8)) == float(np.median(view[disc]))


def test_lsq_line_is_polyfit():
    rng = np.random.default_rng(4)
    for _ in range(300):
        n = int(rng.integers(2, 90))
        x = np.sort(rng.uniform(10.0, 140.0, n))
        if np.ptp(x) < 1e-6:
            continue
        y = rng.uniform(-5.0, 5.0) + rng.uniform(-0.1, 0.1) * x + rng.normal(0.0, 1.0, n)
        a, b = _lsq_line(x, y)
        b_ref, a_ref = np.polyfit(x, y, 1)
        assert a == pytest.approx(a_ref, rel=1e-9, abs=1e-9)
        assert b == pytest.approx(b_ref, rel=1e-9, abs=1e-11)


def _run_around_loop(on, i):
    a = b = i
    while a > 0 and on[a - 1]:
        a -= 1
    while b < len(on) - 1 and on[b + 1]:
        b += 1
    return a, b


def test_run_around_is_the_walk_from_i():
    rng = np.random.default_rng(5)
    for _ in range(500):
        on = rng.random(int(rng.integers(1, 120))) < rng.random()
        i = int(rng.integers(0, len(on)))
        on[i] = True
        assert _run_around(on, i) == _run_around_loop(on, i)
    assert _run_around(np.ones(7, bool), 3) == (0, 6)


def _lobe_loop(s, i, thr):
    n = len(s)
    lo = i
    while lo > i - n // 4 and s[(lo - 1) % n] > thr:
        lo -= 1
    hi = i
    while hi < i + n // 4 and s[(hi + 1) % n] > thr:
        hi += 1
    return lo, hi


def test_lobe_is_the_walk_either_side():
    rng = np.random.default_rng(6)
    for _ in range(500):
        n = int(rng.choice([3, 5, 17, 720]))
        s = np.convolve(rng.random(n + 40), np.ones(21) / 21.0, "same")[20:20 + n]
        i = int(rng.integers(0, n))
        thr = float(rng.uniform(0.2, 0.7)) * float(s.max())
        assert _lobe(s, i, thr) == _lobe_loop(s, i, thr)
    s = np.ones(720)  # all above: a quarter turn either way, and no further
    assert _lobe(s, 5, 0.5) == (5 - 180, 5 + 180)


def test_column_angle_tables_are_the_angles_sin_and_cos():
    cols = np.arange(round(360.0 / STEP))
    rng = np.random.default_rng(7)
    for sub in (cols, np.sort(rng.choice(cols, 200, replace=False)), cols[:1]):
        th = np.radians(sub * STEP)
        assert np.array_equal(_SIN64[sub], np.sin(th))
        assert np.array_equal(_COS64[sub], np.cos(th))



def _samples_by_calls(rng, n, iters):
    out = []
    for _ in range(iters):
        base = int(rng.integers(0, n))
        span = int(rng.integers(n // 8, n // 2 + 1))
        out.append((base + np.sort(rng.choice(span, 5, replace=False))) % n)
    return out


@pytest.mark.parametrize("seed", range(8))
def test_ransac_samples_are_numpys_draws_and_leave_the_generator_alike(seed):
    for n in (40, 41, 47, 80, 200, 513, 1500, 4000, 100000):
        for kept_half in (False, True):
            a, b = np.random.default_rng([seed, n]), np.random.default_rng([seed, n])
            if kept_half:  # a 32-bit draw before leaves half a 64-bit word for the next
                a.integers(0, 7, dtype=np.uint32)
                b.integers(0, 7, dtype=np.uint32)
            want = _samples_by_calls(a, n, 24)
            got = ransac_samples(b, n, 24)
            assert len(got) == 24
            assert all(np.array_equal(x, y) for x, y in zip(want, got, strict=True))
            assert a.bit_generator.state == b.bit_generator.state
            # the rim search's next contour draws on from there alike
            assert _samples_by_calls(a, 300, 3)[2].tolist() == \
                ransac_samples(b, 300, 3)[2].tolist()
            assert a.random() == b.random()


def _decode_meshgrid(logits):
    k = logits.shape[0]
    flat = logits.reshape(k, -1).astype(np.float64)
    prob = np.exp(flat - flat.max(1, keepdims=True))
    prob /= prob.sum(1, keepdims=True)
    prob = prob.reshape(k, OUT, OUT)
    pts, spread, peak = np.zeros((k, 2)), np.zeros(k), np.zeros(k)
    g = np.arange(OUT)
    for j in range(k):
        y, x = np.unravel_index(int(np.argmax(prob[j])), (OUT, OUT))
        peak[j] = prob[j, max(0, y - 1):y + 2, max(0, x - 1):x + 2].sum()
        ys, xs = slice(max(0, y - 2), y + 3), slice(max(0, x - 2), x + 3)
        w = prob[j, ys, xs]
        gx, gy = np.meshgrid(g[xs], g[ys])
        s = w.sum()
        mx, my = (w * gx).sum() / s, (w * gy).sum() / s
        var = (w * ((gx - mx) ** 2 + (gy - my) ** 2)).sum() / s
        pts[j] = ((mx + 0.5) * IN / OUT, (my + 0.5) * IN / OUT)
        spread[j] = math.sqrt(var) * IN / OUT
    return pts, spread, peak


def test_keypoint_decode_is_the_meshgrid_form():
    rng = np.random.default_rng(9)
    for t in range(200):
        lg = rng.normal(0.0, 3.0, (4, OUT, OUT)).astype(np.float32)
        y, x = (int(v) for v in rng.integers(0, OUT, 2))
        if t % 2:  # a peak, at the heatmap's edge now and then
            y, x = (0 if t % 4 == 1 else y), (OUT - 1 if t % 8 == 3 else x)
            lg[1, y, x] += 20.0
        for a, b in zip(_decode(lg), _decode_meshgrid(lg), strict=True):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("seed", range(4))
def test_tick_rings_with_their_rows_given_are_the_same(seed):
    rng = np.random.default_rng(seed)
    b = rng.random((70, 720)) < 0.15
    b[30:36, ::12] = True  # a ring of ticks
    b[50:53, ::20] = True
    hidden = np.zeros_like(b)
    hidden[:, 100:120] = True
    short = short_runs(b, long_columns(STEP))
    rows = tick_ring_rows(b, STEP, short=short)
    assert rows
    want = tick_rings(b, hidden, STEP)
    got = tick_rings(b, hidden, STEP, short=short, rows=rows)
    assert len(want) == len(got)
    for (e0, k0, r0), (e1, k1, r1) in zip(want, got, strict=True):
        assert np.array_equal(e0, e1) and np.array_equal(k0, k1) and r0 == r1


def test_row_percentile_is_numpys_percentile():
    rng = np.random.default_rng(10)
    for _ in range(100):
        a = (rng.random((int(rng.integers(1, 40)), int(rng.integers(1, 70)))) * 50) \
            .astype(np.float32)
        a[:, ::3] = 0.0  # ties, as rays crossing bare face have
        for q in (0.0, 35.0, 50.0, 90.0, 100.0):
            assert np.array_equal(_row_percentile(a, q),
                                  np.percentile(a, q, axis=1).astype(np.float32))


def test_polar_frame_maps_are_the_plain_forms():
    # the rays' radii and offsets are made once per radius and reused: the maps of every
    # call are those made afresh from the pivot, bit for bit, and a reuse changes nothing
    from app.core.meter.needle import _COS, _SIN, R_IN, R_OUT, polar_frame

    rng = np.random.default_rng(5)
    img = rng.integers(0, 256, (300, 300), dtype=np.uint8)
    for _ in range(3):  # the second and third rounds reuse the offsets of the first
        for radius in (108.0, 57.3, 121.9):
            piv = (float(rng.uniform(120, 180)), float(rng.uniform(120, 180)))
            _crop, _resp, rs, mx, my = polar_frame(img, piv, radius)
            n_r = int(min(96, max(24, (R_OUT - R_IN) * radius / 1.5)))
            rs0 = np.linspace(R_IN * radius, R_OUT * radius, n_r).astype(np.float32)
            half = int(math.ceil(R_OUT * radius + 0.1 * radius + 4))
            cx, cy = piv[0] - max(0, int(piv[0]) - half), piv[1] - max(0, int(piv[1]) - half)
            mx0 = (cx + _SIN[:, None] * rs0[None, :]).astype(np.float32)
            my0 = (cy - _COS[:, None] * rs0[None, :]).astype(np.float32)
            assert rs.dtype == mx.dtype == my.dtype == np.float32
            assert np.array_equal(rs, rs0)
            assert np.array_equal(mx, mx0) and np.array_equal(my, my0)
            mx[0, 0] += 1.0  # a caller's map is its own: the next call is not moved
