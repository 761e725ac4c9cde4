"""The end marks as a second witness of a tilted dial's rim (calibrated reading): on the
dial both end marks' ticks are equally far from the pivot, so their image distances test
the tilt the rim's ellipse gives."""

import math

import cv2
import numpy as np
import pytest
from gauge_draw import SIZE, C, base_profile, draw_face, draw_needle, end_mark

from app.core.meter import calibrated, make_calibrated_profile, read_gauge
from app.core.meter.calibrated import end_mark_tilt
from app.core.meter.clicks import FIT_SIGMA_PX, tick_ends
from app.core.meter.oblique import Rectifier, _stretch, find_rectifier

A_MIN, SPAN = -135.0, 270.0  # the drawn dial: 0..80 kPa clockwise over 270 deg
RATIO, AXIS = math.cos(math.radians(32.0)), 135.0  # foreshortened towards the max mark
PAD = 40


def _tilted(v: float):
    """A dial at ``v`` kPa seen at 32 deg of tilt (orthographically) about an axis that
    foreshortens its two end marks unequally; returns the image and its pivot and end
    marks."""
    a = A_MIN + SPAN * v / 80.0
    img = draw_needle(draw_face(A_MIN, SPAN), a)
    img = cv2.copyMakeBorder(img, PAD, PAD, PAD, PAD, cv2.BORDER_CONSTANT,
                             value=(160, 160, 160))
    t = math.radians(AXIS)
    u = np.array([math.sin(t), -math.cos(t)])
    m = np.eye(2) - (1.0 - RATIO) * np.outer(u, u)
    c = np.array([C + PAD, C + PAD])
    warp = np.hstack([m, (c - m @ c)[:, None]])
    out = cv2.warpAffine(img, warp, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR,
                         borderValue=(160, 160, 160))
    out = np.clip(out + np.random.default_rng(5).normal(0, 1.5, out.shape), 0, 255)
    pts = [(C, C), end_mark(A_MIN), end_mark(A_MIN + SPAN)]
    return out.astype(np.uint8), [tuple(m @ (np.array(p) + PAD - c) + c) for p in pts]


@pytest.mark.parametrize("v", [9.0, 22.0, 66.0])
def test_end_marks_confirm_a_rim_seen_on_few_rays(v, monkeypatch):
    # the rim's ellipse found with a step on only 60 % of the rays (as where a bracket or
    # glare hides the bezel): the rim alone leaves all of its 32 deg correction in doubt
    # (several % FS here); the end marks, foreshortened unequally, confirm it
    def few_rays(gray, pivot, radius, colour=None):
        rect = find_rectifier(gray, pivot, radius)
        rect.support = 0.6
        return rect

    monkeypatch.setattr(calibrated, "find_rectifier", few_rays)
    img, pts = _tilted(v)
    r = read_gauge(img, make_calibrated_profile(base_profile(), *pts))
    assert r.value == pytest.approx(v, abs=0.005 * 80), (r.error, r.scores)
    w, hh = r.dial_ellipse[2:4]
    assert min(w, hh) / max(w, hh) == pytest.approx(RATIO, abs=0.02)


def test_end_marks_that_disagree_with_the_rim_leave_its_doubt():
    img, pts = _tilted(30.0)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    pivot, marks = pts[0], pts[1:]
    for m in marks:  # the ticks' ends are found on both marks
        ends = tick_ends(gray, pivot, m)
        assert ends is not None and ends[0] < math.dist(pivot, m) < ends[1] + 1.0
    rect = find_rectifier(gray, pivot, 120.0)
    rect.support = 0.6  # (a rim on every ray is not in doubt: nothing to narrow)
    sig = np.array([0.5, FIT_SIGMA_PX, FIT_SIGMA_PX])
    agree, wrong = end_mark_tilt(gray, rect, pivot, marks, sig, 0.5)
    assert agree < 0.25 and wrong == 0.0  # the marks see this tilt well: little in doubt
    # the same ellipse turned a quarter turn: a tilt about the wrong axis
    (ex, ey), (w, h), ang = rect.ellipse
    wrong_ell = ((ex, ey), (w, h), ang + 90.0)
    wrong = Rectifier(_stretch(wrong_ell), wrong_ell, rect.axis_ratio, rect.support)
    s_wrong, share = end_mark_tilt(gray, wrong, pivot, marks, sig, 0.5)
    assert math.isinf(s_wrong) and share > 0.5  # ... which they say is wrong
    # no tilt found: nothing to confirm
    assert end_mark_tilt(gray, Rectifier(), pivot, marks, sig, 0.5) == (math.inf, 0.0)


@pytest.mark.parametrize("v,axis", [(9.0, 45.0), (9.0, 135.0), (70.0, 45.0)])
def test_a_rim_on_the_wrong_edge_gives_no_confident_wrong_reading(v, axis, monkeypatch):
    # a dial seen head-on whose rim's ellipse was fitted to another edge (a bracket, a
    # shadow: 0.85 across at ``axis``), on every ray: its small correction moves the reading
    # by 1.5 % FS.  The end marks, equally far from the pivot in the image, contradict it:
    # the reading is refused, or its error stays inside what it claims
    ell = ((C, C), (290.0, 290.0 * 0.85), axis)

    def wrong_rim(gray, pivot, radius, colour=None):
        return Rectifier(_stretch(ell), ell, 0.85, 1.0)

    monkeypatch.setattr(calibrated, "find_rectifier", wrong_rim)
    img = draw_needle(draw_face(A_MIN, SPAN), A_MIN + SPAN * v / 80.0)
    img = np.clip(img + np.random.default_rng(5).normal(0, 1.5, img.shape), 0, 255)
    pts = [(C, C), end_mark(A_MIN), end_mark(A_MIN + SPAN)]
    r = read_gauge(img.astype(np.uint8), make_calibrated_profile(base_profile(), *pts))
    assert abs(r.raw_value - v) > 0.01 * 80  # the wrong rim does move the reading
    if r.value is None:
        assert "tilt" in r.error
    else:
        assert r.value == pytest.approx(v, abs=0.01 * 80), r.scores


@pytest.mark.parametrize("v", [13.0, 31.0, 58.0])
def test_a_rim_beyond_the_foreshortened_clicks_is_found(v):
    # a 180 deg scale whose face runs out to 1.5 times its end marks' radius, seen at 41 deg
    # of tilt about the vertical: the end marks, left and right, lie on the foreshortened
    # axis, so the clicks make the scale's radius 0.75 of its size on the dial, and above
    # and below the pivot the rim lies 2 of those radii out.  Both marks are foreshortened
    # alike, so the rim is the only witness of the tilt: it must be found
    a_min, span, ratio, rim = -90.0, 180.0, 0.75, 180
    img = draw_needle(draw_face(a_min, span), a_min + span * v / 80.0)
    pad = 50
    big = np.full((SIZE + 2 * pad, SIZE + 2 * pad, 3), 90, np.uint8)
    c = (SIZE + 2 * pad) // 2
    cv2.circle(big, (c, c), rim + 8, (60, 60, 60), -1, cv2.LINE_AA)
    cv2.circle(big, (c, c), rim, (236, 238, 240), -1, cv2.LINE_AA)
    inner = np.zeros(img.shape[:2], np.uint8)
    cv2.circle(inner, (int(C), int(C)), 140, 255, -1)
    region = big[pad:pad + SIZE, pad:pad + SIZE]
    region[inner > 0] = img[inner > 0]
    m = np.diag([ratio, 1.0])
    warp = np.hstack([m, (np.array([c, c]) - m @ np.array([c, c]))[:, None]])
    out = cv2.warpAffine(big, warp, (big.shape[1], big.shape[0]), flags=cv2.INTER_LINEAR,
                         borderValue=(90, 90, 90))
    out = np.clip(out + np.random.default_rng(7).normal(0, 1.5, out.shape), 0, 255)
    pts = [tuple(m @ (np.array(p) + pad - c) + c)
           for p in [(C, C), end_mark(a_min), end_mark(a_min + span)]]
    r = read_gauge(out.astype(np.uint8), make_calibrated_profile(base_profile(), *pts))
    assert r.value == pytest.approx(v, abs=0.005 * 80), (r.error, r.scores)
    w, hh = r.dial_ellipse[2:4]
    assert min(w, hh) / max(w, hh) == pytest.approx(ratio, abs=0.02)
    # read in the image, as if seen head-on, the needle would be off by more than 2 % FS
    t = math.radians(a_min + span * v / 80.0)
    naive = math.degrees(math.atan2(ratio * math.sin(t), math.cos(t))) - a_min
    assert abs(naive / span * 80.0 - v) > 0.02 * 80
