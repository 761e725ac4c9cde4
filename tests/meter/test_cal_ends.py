"""Telling a calibrated needle's tip from its tail when both ends reach nearly as far
(app.core.meter.needle, ``weigh_ends``): a long counterweight whose weight and the tick
marks beyond it reach past a thin tip that fades before its end, on a scale of 320 deg
where both ends lie on the scale.  The widths of the ends near the hub and over their outer
halves tell them apart; the scale cannot."""

import math

import cv2
import pytest
from gauge_draw import base_profile, calibration, draw_face, draw_needle, end_mark

from app.core.meter import load_profile, read_gauge

A_MIN, SPAN = -160.0, 320.0  # 0..80 kPa clockwise: a needle's opposite is on the scale too


def _angle(v):
    return A_MIN + SPAN * v / 80.0


def _profile():
    return load_profile(base_profile(needle="two-ended",
                                     calibration=calibration(A_MIN, A_MIN + SPAN)))


@pytest.mark.parametrize("v", [25.0, 55.0])
def test_a_long_counterweight_with_its_weight_is_not_the_tip(v):
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v), style="two-ended", tail=104,
                      tail_width=6)
    x, y = end_mark(_angle(v) + 180.0, 80.0)  # the weight, two thirds of the way out
    cv2.circle(img, (int(round(x * 16)), int(round(y * 16))), 9 * 16, (25, 25, 25), -1,
               cv2.LINE_AA, 4)
    r = read_gauge(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


@pytest.mark.parametrize("v", [25.0, 55.0])
@pytest.mark.parametrize("tail, tail_width", [(100, 20), (104, 26)])
def test_a_long_arrow_tail_is_not_the_tip(v, tail, tail_width):
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v), style="arrow-tail", tail=tail,
                      tail_width=tail_width)
    r = read_gauge(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


def test_ends_alike_in_every_cue_are_refused():
    """A bar of one width both ways, with no weight, on a scale that holds both of its ends:
    nothing tells the tip."""
    v = 25.0
    img = draw_face(A_MIN, SPAN)
    a = math.radians(_angle(v))
    dx, dy = math.sin(a), -math.cos(a)
    c = 160.0
    p0 = (int(round((c - 108 * dx) * 16)), int(round((c - 108 * dy) * 16)))
    p1 = (int(round((c + 108 * dx) * 16)), int(round((c + 108 * dy) * 16)))
    cv2.line(img, p0, p1, (25, 25, 25), 4, cv2.LINE_AA, 4)
    cv2.circle(img, (int(c * 16), int(c * 16)), 11 * 16, (25, 25, 25), -1, cv2.LINE_AA, 4)
    r = read_gauge(img, _profile())
    assert r.value is None and "tip from its tail" in r.error
