"""The pivot's share of a calibrated reading's uncertainty (app.core.meter.clicks.
fraction_sigma): the pivot is moved onto the needle's fitted line, so only its error along
that line is left, and it turns both end marks' rays at once."""

import math
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from gauge_draw import R_TICK, C, base_profile, draw_face, draw_needle, end_mark  # noqa: E402

from app.core.meter import make_calibrated_profile, read_gauge  # noqa: E402
from app.core.meter.clicks import fraction_sigma  # noqa: E402

A_MIN, SPAN = -135.0, 270.0
MID_R = R_TICK - 4.0


def _frac(pivot, needle_deg, a_min_xy, a_max_xy):
    """The scale fraction of a needle at ``needle_deg`` seen about ``pivot`` (clockwise)."""
    def ang(p):
        return math.degrees(math.atan2(p[0] - pivot[0], -(p[1] - pivot[1])))
    return ((needle_deg - ang(a_min_xy)) % 360.0) / ((ang(a_max_xy) - ang(a_min_xy)) % 360.0)


@pytest.mark.parametrize("needle_deg", [-135.0, -60.0, 0.0, 40.0, 120.0])
def test_the_pivot_term_is_the_turn_of_both_marks_rays_along_the_needle(needle_deg):
    # the fraction's change when the pivot slides along the needle's line, measured on the
    # geometry, is what the pivot alone contributes to fraction_sigma
    r_min, r_max = 100.0, 80.0
    pmin = (r_min * math.sin(math.radians(A_MIN)), -r_min * math.cos(math.radians(A_MIN)))
    a_max = A_MIN + SPAN
    pmax = (r_max * math.sin(math.radians(a_max)), -r_max * math.cos(math.radians(a_max)))
    u = (math.sin(math.radians(needle_deg)), -math.cos(math.radians(needle_deg)))
    e = 1e-3
    f0 = _frac((0.0, 0.0), needle_deg, pmin, pmax)
    f1 = _frac((e * u[0], e * u[1]), needle_deg, pmin, pmax)
    measured = math.degrees(abs(f1 - f0) * math.radians(SPAN) / e) / SPAN  # per px
    sig_p = 2.0
    got = fraction_sigma(f0, SPAN, r_min, r_max, 0.0, 0.0, sig_p, 0.0,
                         A_MIN - needle_deg, a_max - needle_deg)
    assert got == pytest.approx(sig_p * measured, rel=1e-3, abs=1e-9)


def test_a_pivot_error_along_the_needle_does_not_move_the_mark_it_points_at():
    # at the minimum with the needle over the minimum mark: only that mark's own error
    lo = fraction_sigma(0.0, SPAN, 100.0, 100.0, 1.8, 9.0, 3.0, 0.0, 0.0, SPAN)
    assert lo == pytest.approx(math.degrees(1.8 / 100.0) / SPAN)
    # without the needle's direction the pivot counts in full (as before)
    assert fraction_sigma(0.0, SPAN, 100.0, 100.0, 1.8, 9.0, 3.0, 0.0) > 1.9 * lo


def test_a_small_dial_resting_at_the_minimum_reads_with_the_pivot_clicked_off():
    # a 130 px dial (end marks 52 px from the pivot), no hub to refine the pivot's click
    # on, the needle over the minimum mark (so that mark stays as clicked): the pivot's
    # click error lies along the needle and does not make the reading uncertain
    f = 0.45
    img = draw_needle(draw_face(A_MIN, SPAN, text=False), A_MIN, hub=0.0)
    img = cv2.resize(img, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
    marks = [tuple(np.array(end_mark(a, MID_R)) * f) for a in (A_MIN, A_MIN + SPAN)]
    for dx, dy in ((2.0, 1.0), (-2.0, 2.0), (1.5, -2.5), (-2.5, -1.5), (0.0, 3.0)):
        r = read_gauge(img, make_calibrated_profile(base_profile(), (C * f + dx, C * f + dy),
                                                    *marks))
        assert r.value is not None, r.error
        assert abs(r.value - 0.0) / 80.0 * 100.0 < 0.5
