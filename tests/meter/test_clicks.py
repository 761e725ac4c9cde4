"""The operator's clicks refined on the image (app.core.meter.clicks): a click a few pixels
off snaps to the hub and to the end tick; a click too far off, or an end mark under the
needle, is kept as clicked; the points' uncertainty reaches the reading's confidence."""

import math

import cv2
import numpy as np
import pytest
from gauge_draw import R_TICK, C, base_profile, draw_face, draw_needle, end_mark

from app.core.meter import make_calibrated_profile, read_gauge
from app.core.meter.clicks import (
    MAX_SHIFT_PX,
    Refined,
    fraction_sigma,
    matched_ends,
    refine_end_mark,
    refine_pivot,
)

A_MIN, SPAN = -135.0, 270.0
MID_R = R_TICK - 4.0  # the middle of the drawn major ticks (R_TICK - 14 .. R_TICK + 6)


def _gray(img):
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)


def _angle_about(p, q):
    return math.degrees(math.atan2(q[0] - p[0], -(q[1] - p[1])))


def _off(angle, r, along_px, across_px):
    """A point near the tick at ``angle``: moved along the arc (clockwise +) and radially."""
    x, y = end_mark(angle, r + across_px)
    t = math.radians(angle)
    return x + along_px * math.cos(t), y + along_px * math.sin(t)


@pytest.mark.parametrize("along,across", [(3, 0), (-3, 2), (2.5, -3), (-4, -2), (0, 3)])
@pytest.mark.parametrize("which", ["min", "max"])
def test_a_click_a_few_pixels_off_snaps_to_the_end_tick(along, across, which):
    img = draw_needle(draw_face(A_MIN, SPAN), A_MIN + 100.0)
    a_true = A_MIN if which == "min" else A_MIN + SPAN
    click = _off(a_true, MID_R, along, across)
    r = refine_end_mark(_gray(img), (C, C), click, -1 if which == "min" else 1)
    assert r.ok, r.why
    # the click itself was up to 2 deg off along the arc
    assert _angle_about((C, C), r.xy) == pytest.approx(a_true, abs=0.1)
    assert r.moved_px <= MAX_SHIFT_PX


def test_a_click_too_far_inside_the_scale_is_not_moved_onto_another_tick():
    img = draw_needle(draw_face(A_MIN, SPAN), A_MIN + 100.0)
    # two ticks apart = 13.5 deg; 1.5 ticks inside the minimum lies between two minor ticks,
    # 2 px from one of them: the tick beyond shows this is not the scale's end
    for along in (12.0, 16.0, 26.0):
        click = _off(A_MIN, MID_R, along, 0.0)
        r = refine_end_mark(_gray(img), (C, C), click, -1)
        assert not r.ok and r.xy == pytest.approx(click), (along, r)


def test_a_click_off_the_scale_with_no_tick_near_is_kept():
    img = draw_needle(draw_face(A_MIN, SPAN), A_MIN + 100.0)
    click = _off(A_MIN, MID_R, -(MAX_SHIFT_PX + 9.0), 0.0)  # beyond the scale's end
    r = refine_end_mark(_gray(img), (C, C), click, -1)
    assert not r.ok and r.xy == pytest.approx(click)


def test_an_end_mark_under_the_needle_is_kept_as_clicked():
    img = draw_needle(draw_face(A_MIN, SPAN), A_MIN)  # the needle lies on the minimum mark
    click = _off(A_MIN, MID_R, 2.0, 0.0)
    needle = ((A_MIN, 112.0, 2.5), (A_MIN + 180.0, 22.0, 2.5))
    r = refine_end_mark(_gray(img), (C, C), click, -1, needle)
    assert not r.ok and r.xy == pytest.approx(click)


@pytest.mark.parametrize("dx,dy", [(2.0, -3.0), (-3.0, -3.0), (0.0, 4.0)])
def test_the_pivot_snaps_to_the_hub(dx, dy):
    img = draw_needle(draw_face(A_MIN, SPAN), 40.0, hub=11)
    r = refine_pivot(_gray(img), (C + dx, C + dy), R_TICK)
    assert r.ok, r.why
    assert r.xy == pytest.approx((C, C), abs=0.35)


def test_a_pivot_click_far_from_the_hub_is_kept():
    img = draw_needle(draw_face(A_MIN, SPAN), 40.0, hub=11)
    click = (C + 8.0, C - 6.0)  # 10 px: inside the hub's disc, too far to be a click's error
    r = refine_pivot(_gray(img), click, R_TICK)
    assert not r.ok and r.xy == click


def test_no_hub_keeps_the_click():
    img = draw_face(A_MIN, SPAN, text=False)  # no needle, no hub
    r = refine_pivot(_gray(img), (C + 1.0, C), R_TICK)
    assert not r.ok and r.xy == (C + 1.0, C)


def test_fraction_sigma_grows_with_the_points_errors_and_shrinks_with_the_span():
    base = fraction_sigma(0.5, 270.0, 100.0, 100.0, 0.5, 0.5, 0.5, 0.1)
    assert fraction_sigma(0.5, 270.0, 100.0, 100.0, 1.8, 1.8, 0.5, 0.1) > 2 * base
    assert fraction_sigma(0.5, 90.0, 100.0, 100.0, 0.5, 0.5, 0.5, 0.1) == pytest.approx(3 * base)
    # at the minimum only the minimum mark counts
    lo = fraction_sigma(0.0, 270.0, 100.0, 100.0, 0.5, 9.0, 0.0, 0.0)
    assert lo == pytest.approx(math.degrees(0.5 / 100.0) / 270.0)


def test_an_unverifiable_click_on_a_short_scale_is_a_refusal_not_a_guess():
    # no ticks to refine the clicks on (ink as the face) and a 40 deg scale: 3 px of click
    # error is about 2 % of full scale, so the reading is refused for its uncertainty
    face = draw_face(-20.0, 40.0, ink=(236, 238, 240), text=False)
    img = draw_needle(face, 0.0)
    pts = [(C, C), end_mark(-20.0, MID_R), end_mark(20.0, MID_R)]
    r = read_gauge(img, make_calibrated_profile(base_profile(), *pts))
    assert r.value is None and "uncertain" in r.error
    assert r.raw_value == pytest.approx(40.0, abs=1.0)  # (it was found: 0 deg is mid-scale)
    # the same needle with visible ticks: the clicks are refined and the reading returned
    img = draw_needle(draw_face(-20.0, 40.0, text=False), 0.0)
    r = read_gauge(img, make_calibrated_profile(base_profile(), *pts))
    assert r.value == pytest.approx(40.0, abs=0.4), r.error


def test_noisy_clicks_on_a_small_dial_are_refined_within_half_a_percent():
    rng = np.random.default_rng(5)
    small = cv2.resize(draw_face(A_MIN, SPAN), None, fx=0.5, fy=0.5,
                       interpolation=cv2.INTER_AREA)
    errs = []
    for _ in range(10):
        v = float(rng.uniform(5, 75))
        img = cv2.resize(draw_needle(draw_face(A_MIN, SPAN), A_MIN + SPAN * v / 80), None,
                         fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
        assert img.shape == small.shape
        pts = [(np.array(p) * 0.5 + rng.uniform(-3, 3, 2)).tolist()
               for p in ((C, C), end_mark(A_MIN, MID_R), end_mark(A_MIN + SPAN, MID_R))]
        r = read_gauge(img, make_calibrated_profile(base_profile(), *pts))
        assert r.value is not None, r.error
        errs.append(abs(r.value - v) / 80 * 100)
    assert max(errs) < 0.5, errs


def test_an_end_mark_much_fainter_than_the_other_is_kept_as_clicked():
    # both end marks are major ticks of one print: a faint "tick" at one end is a label's
    # edge or glare beside a tick the needle hides
    lo = Refined((40.0, 200.0), True, 1.5, 0.5, contrast=60.0)
    hi = Refined((280.0, 200.0), True, 2.5, 0.5, contrast=12.0)
    clicked_lo, clicked_hi = (41.0, 199.0), (281.5, 203.0)
    a, b = matched_ends(lo, hi, clicked_lo, clicked_hi)
    assert a == lo and not b.ok and b.xy == clicked_hi and "fainter" in b.why
    b, a = matched_ends(hi, lo, clicked_hi, clicked_lo)
    assert a == lo and not b.ok and b.xy == clicked_hi
    # alike: both kept as refined; one not refined: nothing to compare
    hi2 = Refined((280.0, 200.0), True, 2.5, 0.5, contrast=45.0)
    assert matched_ends(lo, hi2, clicked_lo, clicked_hi) == (lo, hi2)
    kept = Refined(clicked_hi, False, why="no clear tick at the end mark")
    assert matched_ends(lo, kept, clicked_lo, clicked_hi) == (lo, kept)


def test_refined_end_marks_carry_their_ticks_contrast():
    img = draw_face(A_MIN, SPAN)
    lo = refine_end_mark(_gray(img), (C, C), _off(A_MIN, MID_R, 2.0, 1.0), -1)
    hi = refine_end_mark(_gray(img), (C, C), _off(A_MIN + SPAN, MID_R, -2.0, 1.0), 1)
    assert lo.ok and hi.ok and lo.contrast > 20 and hi.contrast > 20
    assert matched_ends(lo, hi, lo.xy, hi.xy) == (lo, hi)
