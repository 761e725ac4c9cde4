"""Steps written out for speed give exactly what their plain definitions give.

Each reference below is the step as it was written before (numpy's roll, the general
circle fit on the points kept, one residual pass per round); the fast forms must agree to
the last bit, since the reader's decisions sit on thresholds of these numbers.
"""

import math

import numpy as np
import pytest

from app.core.meter.arc_fit import bands
from app.core.meter.geometry import fit_circle
from app.core.meter.ring_centre import _trimmed_circle
from app.core.meter.tick_band import (
    MIN_STROKES,
    STROKE_ROWS,
    long_columns,
    short_runs,
    tick_rings,
)


def _trimmed_reference(pts):
    keep = np.ones(len(pts), bool)
    for _ in range(4):
        if keep.sum() < 20:
            return None
        m, n, r, rms = fit_circle(pts[keep])
        res = np.abs(np.hypot(pts[:, 0] - m, pts[:, 1] - n) - r)
        new = res < max(1.0, 2.0 * rms)
        if (new == keep).all():
            break
        keep = new
    if keep.sum() < max(20, 0.4 * len(pts)):
        return None
    return (m, n), rms, r


def _ring(rng, n=600, outliers=0.2, noise=0.4, arc_deg=300.0):
    th = np.radians(rng.uniform(0.0, arc_deg, n))
    r = 100.0 + rng.normal(0.0, noise, n)
    bad = rng.random(n) < outliers  # numerals and major ticks: off the ring, outwards
    r[bad] += rng.uniform(3.0, 15.0, bad.sum())
    return np.column_stack([150.3 + r * np.sin(th), 149.2 - r * np.cos(th)])


@pytest.mark.parametrize("seed", range(12))
def test_trimmed_circle_is_the_plain_trimmed_fit(seed):
    rng = np.random.default_rng(seed)
    pts = _ring(rng, n=int(rng.integers(25, 700)), outliers=float(rng.uniform(0.0, 0.6)),
                noise=float(rng.uniform(0.1, 2.0)), arc_deg=float(rng.uniform(60.0, 360.0)))
    fast = _trimmed_circle(np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]))
    assert repr(fast) == repr(_trimmed_reference(pts))


def test_trimmed_circle_refuses_like_the_plain_fit():
    rng = np.random.default_rng(3)
    few = _ring(rng, n=19)
    assert _trimmed_circle(few[:, 0].copy(), few[:, 1].copy()) is None
    assert _trimmed_reference(few) is None
    scattered = rng.uniform(0.0, 300.0, (200, 2))  # no ring: most points trimmed away
    got = _trimmed_circle(scattered[:, 0].copy(), scattered[:, 1].copy())
    assert repr(got) == repr(_trimmed_reference(scattered))
    assert got is None or got[1] > 5.0


def _bands_reference(b):
    """arc_fit.bands as written with numpy's roll."""
    runs = np.count_nonzero(b[:, 1:] != b[:, :-1], axis=1) / 2.0
    runs = np.minimum(np.minimum(runs, np.roll(runs, 1)), np.roll(runs, -1))
    runs[0] = runs[-1] = 0
    out = []
    if runs.max() >= 6:
        top = int(np.argmax(runs))
        band = runs >= 0.7 * runs.max()
        lo = hi = top
        while lo > 0 and band[lo - 1]:
            lo -= 1
        while hi < len(band) - 1 and band[hi + 1]:
            hi += 1
        out.append((lo, hi))
        hi2 = lo - 1
        while hi2 > 0 and runs[hi2] < 6:
            hi2 -= 1
        lo2 = hi2
        while lo2 > 0 and runs[lo2 - 1] >= 6 and runs[lo2 - 1] >= 0.6 * runs[hi2]:
            lo2 -= 1
        if hi2 - lo2 >= 2 and lo - hi2 < 6:
            out.append((lo2, hi2))
    cover = b.mean(axis=1)
    cover[cover > 0.97] = 0
    top = int(np.argmax(cover))
    if cover[top] > 0.2:
        out.append((max(0, top - 1), min(len(cover) - 1, top + 1)))
    return out


def _stroke_counts_reference(b, step_deg=0.5):
    """tick_rings' strokes per starting row, as written with numpy's roll."""
    s = short_runs(b, long_columns(step_deg))
    k = STROKE_ROWS
    n_rows = b.shape[0]
    stroke = s[: n_rows - k + 1].copy()
    for j in range(1, k):
        stroke &= s[j: n_rows - k + 1 + j]
    return (stroke & ~np.roll(stroke, 1, axis=1)).sum(axis=1).astype(float)


def _polar_marks(rng, rows=60, cols=720):
    """A thresholded polar image with two rings of ticks, a printed arc and noise."""
    b = rng.random((rows, cols)) < 0.03
    b[30:42, ::12] = True  # ticks every 6 deg
    b[30:42, 1::12] = True
    b[10:16, 3::24] = True  # an inner ring of major ticks
    b[45:47, :] = True  # a printed arc
    b[:, 600:] &= rng.random((rows, 120)) < 0.5  # the gap, part noise
    b[:, 0] |= rng.random(rows) < 0.5  # strokes across the columns' wrap
    return b


@pytest.mark.parametrize("seed", range(8))
def test_bands_match_their_rolled_form(seed):
    b = _polar_marks(np.random.default_rng(seed))
    assert bands(b) == _bands_reference(b)
    assert bands(b[:2]) == _bands_reference(b[:2])  # rows too few for neighbours


@pytest.mark.parametrize("seed", range(8))
def test_tick_rings_count_strokes_as_the_rolled_form(seed):
    rng = np.random.default_rng(seed)
    b = _polar_marks(rng)
    hidden = np.zeros_like(b)
    hidden[:, 100:110] = True
    rings = tick_rings(b, hidden, 0.5, most=5)
    assert rings  # the ring of ticks is found at all
    count = _stroke_counts_reference(b)
    # the rings come in the order of the reference counts, each about its top row
    tops = []
    for _e, _known, (lo, hi) in rings:
        top = int(np.argmax(count))
        assert lo <= top <= hi
        tops.append(top)
        count[max(0, lo - STROKE_ROWS + 1): hi - STROKE_ROWS + 1 + STROKE_ROWS] = 0
    assert len(set(tops)) == len(tops)
    assert count.max() < MIN_STROKES or len(rings) == 5


@pytest.mark.parametrize("seed", range(4))
def test_ransac_inliers_counted_at_once_as_one_by_one(seed):
    import cv2

    from app.core.meter.dial import _ellipse_residual, _inlier_counts

    rng = np.random.default_rng(seed)
    for _ in range(40):
        n = int(rng.integers(40, 900))
        th = np.sort(rng.uniform(0.0, 2 * np.pi, n))
        a, b = rng.uniform(30.0, 120.0, 2)
        pts = np.column_stack([160 + a * np.cos(th), 120 + b * np.sin(th)])
        pts += rng.normal(0.0, 1.0, pts.shape)
        off = rng.random(n) < 0.3  # clutter edges merged with the rim
        pts[off] += rng.normal(0.0, 15.0, (off.sum(), 2))
        pts = pts.astype(np.float32)  # as the dial finder's contours
        ells = [cv2.fitEllipse(pts[np.sort(rng.choice(n, 5, replace=False))])
                for _ in range(24)]
        one_by_one = [int((_ellipse_residual(pts, e) < 1.5).sum()) for e in ells]
        assert _inlier_counts(pts, ells).tolist() == one_by_one


def test_a_stroke_across_the_wrap_counts_once():
    # two rings of 8 strokes each; the outer one has a stroke across the last and first
    # columns.  Counted once, the rings tie and the inner (first) one leads; counted
    # twice, the outer one would
    b = np.zeros((50, 720), bool)
    for c in range(20, 720, 90):
        b[10:14, c:c + 2] = True  # inner ring: 8 strokes
    for c in range(60, 650, 90):
        b[30:34, c:c + 2] = True  # outer ring: 7 strokes ...
    b[30:34, 719] = b[30:34, 0] = True  # ... and one across the wrap
    rings = tick_rings(b, np.zeros_like(b), 0.5, most=2)
    assert [lohi for _, _, lohi in rings] == [(10, 13), (30, 33)]


@pytest.mark.parametrize("seed", range(8))
def test_tick_ring_rows_are_tick_rings_rows(seed):
    # the rows alone (ring_centre's and comb_centre's use) are where tick_rings puts them,
    # whatever the needle hides: the evidence is not made for them
    from app.core.meter.tick_band import tick_ring_rows

    rng = np.random.default_rng(seed)
    b = _polar_marks(rng, rows=int(rng.integers(3, 90)))
    hidden = rng.random(b.shape) < 0.2
    for most in (1, 3, 5):
        full = [lohi for _, _, lohi in tick_rings(b, hidden, 0.5, most=most)]
        assert tick_ring_rows(b, 0.5, most=most) == full
        assert tick_ring_rows(b, 0.5, most=most, short=short_runs(b, long_columns(0.5))) \
            == full


def _ring_centre_reference(dark, thr, centre, face_r, hidden_mask, clamp_band=False):
    """angles.ring_centre as written before: the tick rings with their evidence, the rows
    picked by index arrays."""
    from app.core.meter.ring_centre import (
        CLAMPED_SHARE,
        MAX_CENTRE_SHIFT_PX,
        MIN_RING_ARC_DEG,
        STEP,
        _arc_cover_deg,
        hidden_float,
    )
    from app.core.meter.scale import polar

    c = (float(centre[0]), float(centre[1]))
    darkf = dark.astype(np.float32)
    hidden = None if hidden_mask is None else hidden_float(hidden_mask)
    for _ in range(2):
        pol, rs = polar(darkf, c, 0.45 * face_r, 0.97 * face_r)
        b = pol > thr
        rings = bands(b)
        if not rings:
            return None
        cands = [(b, max(0, rings[0][0] - 3), min(len(rs) - 1, rings[0][1] + 3))]
        short = short_runs(b, long_columns(STEP))
        cands += [(short, lo, hi) for _, _, (lo, hi) in
                  tick_rings(b, np.zeros_like(b), STEP, short=short)]
        hid = None
        if hidden is not None:
            r0, r1 = min(lo for _, lo, _ in cands), max(hi for _, _, hi in cands)
            pm, _ = polar(hidden, c, 0.45 * face_r, 0.97 * face_r, rows=slice(r0, r1 + 1))
            hid = pm > 0.05
        best = None
        for img, lo, hi in cands:
            rows = np.arange(lo, hi + 1)
            sub = img[rows]
            if hid is not None:
                sub = sub & ~hid[rows - r0].any(axis=0)[None, :]
            cols = np.flatnonzero(sub.any(axis=0))
            if len(cols) < 20:
                continue
            if img is not b and _arc_cover_deg(cols) < MIN_RING_ARC_DEG:
                continue
            th = np.radians(cols * STEP)
            sin_t, cos_t = np.sin(th), np.cos(th)
            sc = sub[:, cols]
            for edge in (len(rows) - 1 - np.argmax(sc[::-1], axis=0), np.argmax(sc, axis=0)):
                if (img is not b or clamp_band) and \
                        np.mean((edge == 0) | (edge == len(rows) - 1)) > CLAMPED_SHARE:
                    continue
                r_e = rs[rows[edge]]
                fit = _trimmed_circle(c[0] + r_e * sin_t, c[1] - r_e * cos_t)
                if fit is not None and (best is None or fit[1] < best[1]):
                    best = fit
        if best is None:
            return None
        (m, nn), _, _ = best
        if math.hypot(m - centre[0], nn - centre[1]) > MAX_CENTRE_SHIFT_PX:
            return None
        c = (float(m), float(nn))
    return c, best[1], best[2]


@pytest.mark.parametrize("seed", range(10))
def test_ring_centre_is_its_plain_form(seed):
    import cv2

    from app.core.meter.ring_centre import ring_centre

    rng = np.random.default_rng(seed)
    dark = (rng.random((300, 300)) < 0.01).astype(np.uint8) * 200
    cx, cy = 150 + rng.normal(0, 3, 2)
    start, span = rng.uniform(0, 360), rng.uniform(180, 300)
    r_out = rng.uniform(110, 120)
    for k in range(int(rng.integers(20, 60)) + 1):  # ticks, some long
        a = math.radians(start + span * k / 40.0)
        r_in = r_out - (14 if k % 5 == 0 else rng.uniform(5, 9))
        cv2.line(dark, (int(cx + r_in * math.sin(a)), int(cy - r_in * math.cos(a))),
                 (int(cx + r_out * math.sin(a)), int(cy - r_out * math.cos(a))), 220, 2)
    hidden = np.zeros((300, 300), np.uint8)
    a = rng.uniform(0, 2 * math.pi)
    cv2.line(hidden, (150, 150), (int(150 + 125 * math.sin(a)), int(150 - 125 * math.cos(a))),
             1, 5)
    for mask in (hidden, None):
        for clamp in (False, True):
            ref = _ring_centre_reference(dark, 60, (150.0, 150.0), 135.0, mask, clamp)
            got = ring_centre(dark, 60, (150.0, 150.0), 135.0, mask, with_radius=True,
                              clamp_band=clamp)
            assert repr(got) == repr(ref)


@pytest.mark.parametrize("seed", range(6))
def test_percentile_is_numpys(seed):
    from app.core.meter.arc_fit import percentile

    rng = np.random.default_rng(seed)
    for _ in range(300):
        n = int(rng.integers(1, 80))
        a = rng.normal(0.0, rng.uniform(0.1, 50.0), n)
        if rng.random() < 0.3:  # ties: evidence shares and run lengths repeat
            a = np.round(a)
        for q in (90, 35, 50, 75, float(rng.uniform(0, 100))):
            got = percentile(a.copy(), q)
            assert repr(got) == repr(float(np.percentile(a, q)))
