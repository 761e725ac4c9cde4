"""Each step of the paper's pipeline on constructed inputs."""

import math

import cv2
import numpy as np
import pytest

from app.core.meter.dial import find_dial, normalise_size, rectify
from app.core.meter.geometry import (
    angle_cw_from_up,
    choose_intersection,
    fit_circle,
    fit_line,
    line_circle_intersections,
)
from app.core.meter.interpolate import eq21_reading, find_interval
from app.core.meter.otsu import binarize, otsu_threshold
from app.core.meter.thinning import zhang_suen


def test_normalise_size_is_300():
    img = np.zeros((480, 517, 3), np.uint8)
    assert normalise_size(img).shape == (300, 300, 3)


def test_otsu_splits_two_levels_and_matches_brute_force():
    rng = np.random.default_rng(0)
    img = np.concatenate([rng.normal(60, 8, 5000), rng.normal(190, 10, 3000)])
    img = np.clip(img, 0, 255).astype(np.uint8).reshape(80, 100)
    t = otsu_threshold(img)
    assert 90 < t < 160
    # brute force eq. 13-17 with explicit class variances
    best, bt = -1.0, 0
    v = img.ravel().astype(float)
    for tt in range(255):
        c1, c2 = v[v <= tt], v[v > tt]
        if len(c1) == 0 or len(c2) == 0:
            continue
        w1, w2 = len(c1) / len(v), len(c2) / len(v)
        sb = w1 * w2 * (c1.mean() - c2.mean()) ** 2
        if sb > best + 1e-9:
            best, bt = sb, tt
    c1, c2 = v[v <= t], v[v > t]
    sb_t = len(c1) * len(c2) / len(v) ** 2 * (c1.mean() - c2.mean()) ** 2
    assert sb_t == pytest.approx(best, rel=1e-9)  # a maximiser of eq. 17 (bt is another)
    assert v[(v > min(t, bt)) & (v <= max(t, bt))].size == 0  # same split of the pixels
    b = binarize(img, t)
    assert set(np.unique(b)) == {0, 255}
    assert (b[img > t] == 255).all() and (b[img <= t] == 0).all()


def _neighbours(sk):
    p = np.pad(sk > 0, 1).astype(np.uint8)
    k = np.ones((3, 3), np.uint8)
    k[1, 1] = 0
    return cv2.filter2D(p, -1, k, borderType=cv2.BORDER_CONSTANT)[1:-1, 1:-1]


@pytest.mark.parametrize("shape", ["bar", "diag", "cross", "ring"])
def test_zhang_suen_gives_connected_one_pixel_skeleton(shape):
    img = np.zeros((80, 80), np.uint8)
    if shape == "bar":
        cv2.rectangle(img, (10, 35), (70, 45), 255, -1)
    elif shape == "diag":
        cv2.line(img, (10, 10), (70, 65), 255, 9)
    elif shape == "cross":
        cv2.rectangle(img, (10, 36), (70, 44), 255, -1)
        cv2.rectangle(img, (36, 10), (44, 70), 255, -1)
    else:
        cv2.circle(img, (40, 40), 25, 255, 8)
    sk = zhang_suen(img)
    on = sk > 0
    assert on.sum() > 20
    assert (on <= (img > 0)).all()  # inside the shape
    n, _ = cv2.connectedComponents(sk, connectivity=8)
    assert n - 1 == 1  # connected
    # one pixel wide: no 2x2 block fully on
    blocks = on[:-1, :-1] & on[1:, :-1] & on[:-1, 1:] & on[1:, 1:]
    assert not blocks.any()
    if shape == "ring":  # a ring stays a closed loop: every pixel has >= 2 neighbours
        assert (_neighbours(sk)[on] >= 2).all()
    if shape == "bar":  # the skeleton of a bar is its mid-line
        ys, _ = np.nonzero(on)
        assert abs(np.median(ys) - 40) <= 1


def test_zhang_suen_empty_and_vectorised_speed():
    assert zhang_suen(np.zeros((10, 10), np.uint8)).sum() == 0
    img = np.zeros((300, 300), np.uint8)
    cv2.line(img, (150, 150), (260, 60), 255, 9)
    sk = zhang_suen(img)
    assert 100 < (sk > 0).sum() < 200


def test_fit_line_vertical_and_slope():
    pts = [(50.0, y) for y in range(10, 90)]
    ln = fit_line(pts)
    assert abs(abs(ln.direction[1]) - 1) < 1e-9
    assert ln.slope_intercept is None  # eq. 19 undefined, the line is not
    assert ln.distance((50, 0))[0] < 1e-9
    xs = np.arange(0, 50.0)
    ln = fit_line(np.column_stack([xs, 2 * xs + 3]))
    k, c = ln.slope_intercept
    assert k == pytest.approx(2.0) and c == pytest.approx(3.0)


def test_fit_circle_recovers_hub():
    t = np.linspace(0, 2 * np.pi, 50)
    m, n, r, rms = fit_circle(np.column_stack([120 + 14 * np.cos(t), 80 + 14 * np.sin(t)]))
    assert (m, n, r) == pytest.approx((120, 80, 14), abs=1e-6)
    assert rms < 1e-6


def test_fit_circle_closed_form_is_the_least_squares_circle():
    rng = np.random.default_rng(7)
    for _ in range(20):
        # a partial, noisy arc far from the origin (as a hub's boundary beside the shaft)
        t = rng.uniform(0, rng.uniform(1.0, 2 * np.pi), 40)
        p = np.column_stack([150 + 9 * np.cos(t), 140 + 9 * np.sin(t)]) + rng.normal(0, 0.3,
                                                                                   (40, 2))
        a = np.column_stack([2 * p[:, 0], 2 * p[:, 1], np.ones(len(p))])
        (m, n, c), *_ = np.linalg.lstsq(a, (p ** 2).sum(axis=1), rcond=None)
        got = fit_circle(p)
        assert got[:3] == pytest.approx((m, n, math.sqrt(c + m * m + n * n)), abs=1e-7)
    # collinear points have no circle: still an answer, not an exception
    m, n, r, rms = fit_circle([(0, 0), (1, 1), (2, 2), (3, 3)])
    assert all(math.isfinite(v) for v in (m, n, r, rms))


def test_tick_runs_wrap_around_and_spacing_fit():
    from app.core.meter.scale import _lsq_line, _run_arrays, _runs_circular

    on = np.zeros(20, bool)
    on[[0, 1, 5, 6, 7, 12, 18, 19]] = True
    assert sorted(_runs_circular(on)) == [(5, 3), (12, 1), (18, 4)]  # 18, 19, 0, 1 is one run
    starts, lens = _run_arrays(on)
    assert lens.sum() == on.sum()
    assert _runs_circular(np.ones(8, bool)) == [] and _runs_circular(np.zeros(8, bool)) == []
    k = np.arange(10.0)
    a, b = _lsq_line(k, 12.5 + 4.5 * k)
    assert (a, b) == pytest.approx((12.5, 4.5))
    assert _lsq_line(np.ones(5), np.arange(5.0)) is None


@pytest.mark.parametrize("angle", [30.0, 120.0, -150.0, -60.0, 0.0, 180.0, 90.0, -90.0])
def test_intersection_choice_in_all_quadrants(angle):
    c = (150.0, 150.0)
    dx, dy = math.sin(math.radians(angle)), -math.cos(math.radians(angle))
    ln = fit_line([(c[0] + s * dx, c[1] + s * dy) for s in np.linspace(-20, 110, 60)])
    pts = line_circle_intersections(ln, c, 100.0)
    assert len(pts) == 2
    mass = (c[0] + 60 * dx, c[1] + 60 * dy)  # pointer mass on the tip side
    p = choose_intersection(pts, c, mass)
    got = angle_cw_from_up(p[0] - c[0], p[1] - c[1])
    assert abs((got - angle + 180) % 360 - 180) < 1e-6


def test_line_missing_circle():
    ln = fit_line([(0.0, 0.0), (10.0, 0.0)])
    assert line_circle_intersections(ln, (5.0, 50.0), 10.0) == []


TABLE = [(0.0, 75.69, 215.91), (0.1, 72.29, 211.93), (0.2, 66.13, 203.46),
         (0.3, 60.12, 192.84)]


def test_eq21_exactly_at_ticks_and_between():
    xy = [(x, y) for _, x, y in TABLE]
    vals = [v for v, _, _ in TABLE]
    for i, (v, x, y) in enumerate(TABLE):
        got, *_ = eq21_reading((x, y), xy, vals)
        assert got == pytest.approx(v, abs=1e-9)
        if i < len(TABLE) - 1:
            j, _ = find_interval((x, y), xy)
            assert j in (i, i - 1)
    # midway between 0.1 and 0.2
    mx, my = (72.29 + 66.13) / 2, (211.93 + 203.46) / 2
    got, l_, big_l, i = eq21_reading((mx, my), xy, vals)
    assert i == 1 and got == pytest.approx(0.15, abs=1e-9)
    assert l_ == pytest.approx(big_l / 2)


def test_eq21_reproduces_paper_table2_rows_b_c_d():
    from sim_robot.gauge_render import PAPER_TABLE1
    xy = [(x, y) for _, x, y in PAPER_TABLE1]
    vals = [v for v, _, _ in PAPER_TABLE1]
    for p, paper_val, paper_l, paper_L in [((79.54, 78.03), 1.353, 5.6, 10.5),
                                             ((210.71, 69.54), 2.563, 7.6, 12.2),
                                             ((237.39, 197.62), 3.758, 7.0, 12.2)]:
        v, l_, big_l, _ = eq21_reading(p, xy, vals)
        assert v == pytest.approx(paper_val, abs=0.0015)
        assert l_ == pytest.approx(paper_l, abs=0.15) and big_l == pytest.approx(paper_L, abs=0.1)


def test_find_dial_and_rectify_tilted_ellipse():
    img = np.full((480, 640, 3), 90, np.uint8)
    cv2.ellipse(img, ((330, 250), (300, 240), 25), (40, 40, 40), -1)
    cv2.ellipse(img, ((330, 250), (270, 216), 25), (235, 235, 235), -1)
    ell = find_dial(img)
    assert ell is not None
    assert (ell.cx, ell.cy) == pytest.approx((330, 250), abs=2)
    assert max(ell.width, ell.height) == pytest.approx(270, rel=0.04)
    out, m = rectify(img, ell)
    g = cv2.cvtColor(out, cv2.COLOR_BGR2GRAY)
    # the face becomes a circle: bright at radius 125 in all directions, dark at 142
    for a in np.linspace(0, 2 * np.pi, 12, endpoint=False):
        assert g[int(150 + 125 * np.sin(a)), int(150 + 125 * np.cos(a))] > 200
        assert g[int(150 + 142 * np.sin(a)), int(150 + 142 * np.cos(a))] < 80


def test_crop_rim_fast_path_finds_centred_face_and_declines_otherwise():
    from app.core.meter.rim import find_crop_rim, rim_edge_points

    img = np.full((300, 300), 40, np.uint8)
    cv2.circle(img, (150, 150), 135, 235, -1, lineType=cv2.LINE_AA)
    ell = find_crop_rim(img)
    assert ell is not None
    assert (ell.cx, ell.cy) == pytest.approx((150, 150), abs=0.5)
    assert ell.width == pytest.approx(270, abs=1.5) and ell.height == pytest.approx(270, abs=1.5)
    assert ell.support > 0.95
    pts, ok = rim_edge_points(img, ((150, 150), (266, 266), 0), 6.0)
    assert ok.all()
    assert np.hypot(pts[:, 0] - 150, pts[:, 1] - 150) == pytest.approx(135.3, abs=0.7)
    # a dial off the crop's centre and tilted: found by the wider first search, then refined
    off = np.full((300, 300), 40, np.uint8)
    cv2.ellipse(off, ((142, 156), (250, 236), 30), 235, -1, lineType=cv2.LINE_AA)
    e = find_crop_rim(off)
    assert e is not None
    assert (e.cx, e.cy) == pytest.approx((142, 156), abs=0.5)
    assert sorted([e.width, e.height]) == pytest.approx([237, 251], abs=1.5)
    # far off the centre, or no dial at all: no fast path (the full search runs)
    far = np.full((300, 300), 40, np.uint8)
    cv2.circle(far, (110, 180), 100, 235, -1)
    assert find_crop_rim(far) is None
    assert find_crop_rim(np.full((300, 300), 128, np.uint8)) is None


def test_crop_rim_fast_path_takes_a_dark_face_and_a_bezel_cut_by_lugs():
    """A dark face in a lighter bezel is found in the negative; a rim whose edge is cut by
    lugs on a quarter of its rays is kept when the rest fit it tightly all round, but not
    when the rays that see it lie on one side only."""
    from app.core.meter.rim import find_crop_rim

    dark = np.full((300, 300), 170, np.uint8)
    cv2.circle(dark, (150, 150), 141, 25, -1, lineType=cv2.LINE_AA)
    e = find_crop_rim(dark)
    assert e is not None
    assert (e.cx, e.cy) == pytest.approx((150, 150), abs=0.5)
    assert e.width == pytest.approx(282, abs=1.5)
    lugs = np.full((300, 300), 40, np.uint8)
    cv2.circle(lugs, (150, 150), 132, 235, -1, lineType=cv2.LINE_AA)
    for a in range(0, 360, 45):  # eight bright lugs over the edge, about 11 deg wide each
        cv2.ellipse(lugs, (150, 150), (139, 139), 0, a, a + 10, 235, 16)
    e = find_crop_rim(lugs)
    assert e is not None
    assert (e.cx, e.cy) == pytest.approx((150, 150), abs=0.5)
    assert e.width == pytest.approx(264.5, abs=1.5)
    one_side = np.full((300, 300), 40, np.uint8)
    cv2.circle(one_side, (150, 150), 132, 235, -1, lineType=cv2.LINE_AA)
    cv2.ellipse(one_side, (150, 150), (139, 139), 0, 0, 120, 235, 16)  # a third, in one piece
    assert find_crop_rim(one_side) is None


def test_principal_axis_matches_eigh():
    from app.core.meter.geometry import principal_axis

    rng = np.random.default_rng(5)
    for _ in range(50):
        p = rng.normal(size=(30, 2)) @ rng.normal(size=(2, 2))
        s = p.T @ p
        w, v = np.linalg.eigh(s)
        ux, uy, lam = principal_axis(s[0, 0], s[0, 1], s[1, 1])
        assert abs(ux * v[0, 1] + uy * v[1, 1]) == pytest.approx(1.0, abs=1e-9)
        assert lam == pytest.approx(max(w[0], 0.0), abs=1e-9 * w[1])
    assert principal_axis(2.0, 0.0, 2.0)[2] == pytest.approx(2.0)


def test_head_on_crop_is_decided_from_the_rim_and_read_without_a_warp(monkeypatch):
    from app.core.meter import dial, reader
    from app.core.meter.dial import DialEllipse
    from app.core.meter.rim import find_crop_rim, is_head_on_crop
    from sim_robot.gauge_render import STOCK_SPECS, render_dial

    # the normalised circle: centred, round, radius 135 (within 1 %)
    assert is_head_on_crop(DialEllipse(150.2, 149.8, 271.0, 270.6, 10.0, 1.0), (300, 300))
    assert is_head_on_crop(DialEllipse(150.0, 150.0, 272.0, 272.0, 0.0, 1.0), (300, 300, 3))
    # off centre, oval (an oblique view), another size, or another crop size: not head-on
    assert not is_head_on_crop(DialEllipse(151.0, 150.0, 270.0, 270.0, 0.0, 1.0), (300, 300))
    assert not is_head_on_crop(DialEllipse(150.0, 150.0, 270.0, 268.0, 0.0, 1.0), (300, 300))
    assert not is_head_on_crop(DialEllipse(150.0, 150.0, 276.0, 276.0, 0.0, 1.0), (300, 300))
    assert not is_head_on_crop(DialEllipse(160.0, 160.0, 290.0, 290.0, 0.0, 1.0), (320, 320))

    spec = STOCK_SPECS[1]
    img = render_dial(spec, 1.0, 300)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    ell = find_crop_rim(gray)
    assert ell is not None and is_head_on_crop(ell, gray.shape)
    # a tilted view of the same dial is not head-on
    tilted = cv2.resize(img, (300, 294))
    tilted = cv2.copyMakeBorder(tilted, 3, 3, 0, 0, cv2.BORDER_CONSTANT, value=(255, 255, 255))
    e2 = find_crop_rim(cv2.cvtColor(tilted, cv2.COLOR_BGR2GRAY))
    assert e2 is not None and not is_head_on_crop(e2, tilted.shape)

    warps = []
    real = dial.cv2.warpAffine

    def counting(*a, **k):
        warps.append(a[0].shape)
        return real(*a, **k)

    monkeypatch.setattr(dial.cv2, "warpAffine", counting)
    r = reader.read_gauge(img, spec.profile())
    assert r.value == pytest.approx(1.0, abs=0.002 * 1.6)
    assert warps == []  # the head-on crop is read as it is
    r2 = reader.read_gauge(tilted, spec.profile())
    assert r2.value == pytest.approx(1.0, abs=0.01 * 1.6)
    assert warps  # the oblique crop is rectified


def test_rim_refinement_stops_when_the_narrower_band_would_see_the_same_edges(monkeypatch):
    from app.core.meter import rim
    from app.core.meter.rim import _settled, refine_rim

    ok = np.ones(180, bool)
    guess = ((150.0, 150.0), (270.0, 270.0), 0.0)
    assert _settled(guess, ((150.2, 149.9), (270.6, 270.4), 30.0), ok, 180, 6.0, 4.0)
    # moved more than a pixel, or a fifth of the rays without a clear edge: not settled
    assert not _settled(guess, ((151.0, 150.0), (271.0, 271.0), 0.0), ok, 180, 6.0, 4.0)
    few = ok.copy()
    few[:36] = False
    assert not _settled(guess, ((150.0, 150.0), (270.0, 270.0), 0.0), few, 144, 6.0, 4.0)
    # an oval turned by 90 degrees moves its rim by the difference of its axes
    assert not _settled(((150.0, 150.0), (270.0, 250.0), 0.0),
                        ((150.0, 150.0), (270.0, 250.0), 90.0), ok, 180, 6.0, 4.0)

    # the refinement from a guess off by 3 px takes both bands; from a close guess, one;
    # both end on the same rim
    img = np.full((300, 300), 40, np.uint8)
    cv2.circle(img, (150, 150), 135, 235, -1, lineType=cv2.LINE_AA)
    bands = []
    real = rim.rim_edge_points

    def counting(gray, ell, band, *a, **k):
        bands.append(band)
        return real(gray, ell, band, *a, **k)

    monkeypatch.setattr(rim, "rim_edge_points", counting)
    near = refine_rim(img, ((150.0, 150.0), (271.0, 271.0), 0.0))
    assert bands == [6.0]
    far = refine_rim(img, ((150.0, 150.0), (265.0, 265.0), 0.0))
    assert bands == [6.0, 6.0, 4.0]
    assert near is not None and far is not None
    assert (near.cx, near.cy, near.width) == pytest.approx((far.cx, far.cy, far.width), abs=0.1)


def test_crop_at_the_normalised_size_is_refined_from_the_normalised_circle(monkeypatch):
    from app.core.meter import rim

    calls = []
    real = rim.face_radius
    monkeypatch.setattr(rim, "face_radius", lambda *a, **k: calls.append(1) or real(*a, **k))
    img = np.full((300, 300), 40, np.uint8)
    cv2.circle(img, (150, 150), 134, 235, -1, lineType=cv2.LINE_AA)
    e = rim.find_crop_rim(img)
    assert e is not None and (e.cx, e.cy) == pytest.approx((150, 150), abs=0.3)
    assert calls == []  # no face-radius scan was needed
    # a smaller face in the same crop size: the normalised circle misses it, the scan finds it
    small = np.full((300, 300), 40, np.uint8)
    cv2.circle(small, (150, 150), 110, 235, -1, lineType=cv2.LINE_AA)
    e2 = rim.find_crop_rim(small)
    assert calls == [1]
    assert e2 is not None and (e2.width + e2.height) / 4 == pytest.approx(110.5, abs=1.0)
