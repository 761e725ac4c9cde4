"""An end mark hidden under the needle's tip (app.core.meter.hidden_mark): the needle's
band in the image bounds the mark better than the operator's click, so a needle resting on
an end mark reads where the click's error alone refused it; where the band says less than
the click, or a tick beyond the needle may be the end mark, nothing is claimed."""

import math

import cv2
import numpy as np
import pytest
from gauge_draw import C, base_profile, draw_face, end_mark

from app.core.meter import make_calibrated_profile, read_gauge
from app.core.meter.clicks import CLICK_SIGMA_PX
from app.core.meter.hidden_mark import mark_under_needle

A_MIN, SPAN = -45.0, 90.0  # a short scale: a click's +-3 px is about 1 % FS


def _bar_dial(needle_deg: float, width: int, reach: float = 128.0) -> np.ndarray:
    """A 90 deg scale with a straight bar needle ``width`` px wide reaching ``reach`` px,
    across the ticks (106-126 px from the pivot, the majors 3 px wide)."""
    img = draw_face(A_MIN, SPAN, n_ticks=21)  # a major tick at both ends
    r = math.radians(needle_deg)
    tip = (C + reach * math.sin(r), C - reach * math.cos(r))
    cv2.line(img, (int(round(C * 16)), int(round(C * 16))),
             (int(round(tip[0] * 16)), int(round(tip[1] * 16))), (25, 25, 25), width,
             cv2.LINE_AA, 4)
    cv2.circle(img, (int(round(C * 16)), int(round(C * 16))), 11 * 16, (25, 25, 25), -1,
               cv2.LINE_AA, 4)
    return np.clip(img + np.random.default_rng(3).normal(0, 1.5, img.shape), 0,
                   255).astype(np.uint8)


def _clicks(seed: int):
    rng = np.random.default_rng(seed)
    return [(x + rng.uniform(-3, 3), y + rng.uniform(-3, 3)) for x, y in
            ((C, C), end_mark(A_MIN), end_mark(A_MIN + SPAN))]


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
@pytest.mark.parametrize("v", [0.0, 0.4])
def test_a_needle_lying_on_the_minimum_mark_reads_it(seed, v):
    # the needle over the minimum's tick (at the minimum, or 0.5 % FS above it): the tick
    # is hidden, so the click (+-3 px, about 1 % FS here) was the mark's only witness and
    # the reading was refused; the needle's own band bounds the mark far better
    img = _bar_dial(A_MIN + SPAN * v / 80.0, 6)
    r = read_gauge(img, make_calibrated_profile(base_profile(), *_clicks(seed)))
    assert r.value is not None, (r.error, r.scores)
    assert r.value == pytest.approx(v, abs=0.01 * 80)


def test_the_needles_band_places_the_hidden_mark():
    img = cv2.cvtColor(_bar_dial(A_MIN + 0.3, 6), cv2.COLOR_BGR2GRAY)
    click = end_mark(A_MIN - 1.2)  # 2.5 px off along the arc
    got = mark_under_needle(img, (C, C), click, -1, A_MIN + 0.3, 128.0, 3.0, 60.0, 3.0)
    assert got is not None and got.under_needle
    a = math.degrees(math.atan2(got.xy[0] - C, -(got.xy[1] - C)))
    assert a == pytest.approx(A_MIN, abs=0.6)  # within the band's half-width of the tick
    assert got.sigma_px < CLICK_SIGMA_PX


def test_a_tick_beyond_the_needle_is_not_taken_for_hidden():
    # a tick as strong as the other end's shows just off the scale beyond the needle: the
    # end mark may be that one, so nothing is claimed
    img = _bar_dial(A_MIN + 0.3, 6)
    r = math.radians(A_MIN - 3.5)
    p0 = (C + 106 * math.sin(r), C - 106 * math.cos(r))
    p1 = (C + 126 * math.sin(r), C - 126 * math.cos(r))
    cv2.line(img, (int(p0[0] * 16), int(p0[1] * 16)), (int(p1[0] * 16), int(p1[1] * 16)),
             (30, 30, 30), 3, cv2.LINE_AA, 4)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    assert mark_under_needle(gray, (C, C), end_mark(A_MIN), -1, A_MIN + 0.3, 128.0, 3.0,
                             60.0, 3.0) is None


@pytest.mark.parametrize("seed", [1, 2])
def test_a_paddle_wider_than_the_clicks_error_leaves_the_reading_refused(seed):
    # a needle 16 px wide over the minimum mark: its band says less than the click, and the
    # reading (about 1 % FS of doubt on this short scale) stays refused
    img = _bar_dial(A_MIN + SPAN * 0.4 / 80.0, 16)
    r = read_gauge(img, make_calibrated_profile(base_profile(), *_clicks(seed)))
    assert r.value is None and "points" in r.error, (r.value, r.scores)


def test_a_lance_head_beside_its_line_is_not_a_hidden_end_mark():
    # a two-ended grey lance (bench/meter_cal_stress.py, case two-ended, seed 1, #4) 3 % FS
    # short of the maximum, its head over the tick ring: the strongest band near its line is
    # beside the line (a tick and the head's shade), not on it; placed there, the mark made
    # the needle read the maximum with confidence 1.  Such a band claims nothing
    from bench.meter_cal_stress import CASES, sample

    rng = np.random.default_rng([1, 31, CASES.index("two-ended")])
    for i in range(5):
        img, truth, prof = sample("two-ended", i, rng)
    r = read_gauge(img, prof)
    if r.value is not None:
        assert abs(r.value - truth["value"]) <= 0.02 * truth["full_scale"], r.scores
