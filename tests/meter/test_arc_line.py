"""An end tick on a printed arc line is placed as surely as a lone one: the line going on
from it is not part of the mark (:mod:`app.core.meter.arc_line`), while a dot or a ring on
the line still is."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from test_end_marks import _uneven  # the same uneven scale

from app.core.meter.arc_fit import fit_profile_arc
from app.core.meter.arc_line import line_rows, mark_cols

SIZE, C, R_RING = 300, (150.0, 150.0), 100.0
TURN = 7.0  # the dial's turn in the picture (deg, clockwise)
R_LINE = R_RING - 8.0  # the printed line runs through the ticks' middle



def _p(a: float, r: float) -> tuple[int, int]:
    t = math.radians(a + TURN)
    return (int(round((C[0] + r * math.sin(t)) * 16)), int(round((C[1] - r * math.cos(t)) * 16)))


def _stroke(img: np.ndarray, a: float, width: int = 2, length: float = 16.0) -> None:
    cv2.line(img, _p(a, R_RING - length), _p(a, R_RING), 255, width, cv2.LINE_AA, 4)


def _dial(ends=(-135.0, 135.0)) -> np.ndarray:
    """Darkness image: uneven ticks over a printed line from one end mark to the other
    (upright -135 to +135 deg), turned by TURN; end ticks at ``ends``."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in _uneven():
        _stroke(img, a)
    for a in ends:
        _stroke(img, a)
    cv2.ellipse(img, (int(C[0] * 16), int(C[1] * 16)), (int(R_LINE * 16), int(R_LINE * 16)),
                0.0, -225.0 + TURN, 45.0 + TURN, 255, 2, cv2.LINE_AA, 4)
    return img


def _fit(img: np.ndarray):
    return fit_profile_arc([(img, 50)], C, 135.0, None, -135.0 % 360.0, 270.0)


def test_end_ticks_on_a_printed_line_state_no_doubt_of_the_line():
    """The end ticks cross the line, which runs on into the scale from each: the run of
    evidence an end tick is found in is the line's, tens of degrees long, and half of it
    was the doubt stated for the end mark's place (the reading refused for a bound of
    several % FS where the tick was plain)."""
    fit = _fit(_dial())
    assert fit.rho_deg == pytest.approx(TURN, abs=0.5), fit
    assert fit.ends == 2
    assert fit.ends_err_deg < 1.0, fit


def test_a_dot_on_the_line_beside_its_tick_still_states_its_doubt():
    """End marks that are dots on the line with a tick beside them, off the same way at
    both ends: the doubt of the mark's place (the dot's middle or the tick) must still
    cover the turn's error, the line taken out of the mark but not the dot's halves
    either side of it."""
    off = 3.0
    img = _dial(ends=(-135.0 + off, 135.0 + off))
    for end in (-135.0, 135.0):
        cv2.circle(img, _p(end, R_LINE), 6 * 16, 255, -1, cv2.LINE_AA, 4)
    fit = _fit(img)
    assert fit.rho_deg is not None and fit.method == "ends" and fit.ends == 2, fit
    err = abs(fit.rho_deg - TURN)
    assert err > 1.0  # the ticks, not the dots, placed the ends ...
    stated = max(abs(fit.mismatch_deg) / 2.0, fit.ends_err_deg)
    assert err <= stated + 0.5, (err, stated)


def _polar(ring_hole: bool, wander: bool = False) -> tuple[np.ndarray, list[int]]:
    """A thresholded polar strip (rows: radii, columns: angle): a line along rows 18-19
    over every column (with ``wander``, a row lower every 24 columns, as in a view not
    quite rectified), a stroke (rows 8-29) at columns 40-42 and, with ``ring_hole``, a
    ring's walls from column 40 to 53 about the line (rows 10-11 and 26-27, closed at
    column 53; 7 deg at 0.5 deg a column).  The run an end mark is found in: columns 40
    to 99."""
    b = np.zeros((40, 120), bool)
    for c0 in range(0, 120, 24):
        d = c0 // 24 if wander else 0
        b[18 + d:20 + d, c0:c0 + 24] = True
    b[8:30, 40:43] = True
    if ring_hole:
        b[10:12, 40:54] = True
        b[26:28, 40:54] = True
        b[10:28, 52:54] = True
    return b, list(range(40, 100))


@pytest.mark.parametrize("ring_hole", [False, True])
@pytest.mark.parametrize("wander", [False, True])
def test_the_mark_is_the_print_joined_to_its_stroke_off_the_line(ring_hole, wander):
    b, run = _polar(ring_hole, wander)
    line = line_rows(b, 0, 40, np.ones(b.shape[1], bool))
    if not wander:
        assert set(np.flatnonzero(line)) == {17, 18, 19, 20}  # the line and its blur
    else:
        assert not line.any()  # no row lit over most of the scale: found over the run
    assert mark_cols(b, 0, 40, line, run, 41.0, 3) == (14 if ring_hole else 3)


def test_without_a_line_the_mark_is_the_whole_run():
    """Ticks and dots along the ring, no row lit over a mark's width: as before."""
    b, run = _polar(False)
    b[18:20, :] = False
    b[18:20, 43:52] = True  # a dot's worth of print joined to the stroke
    b[8:30, 60:62] = True
    b[17:21, 64:70] = True
    line = line_rows(b, 0, 40, np.ones(b.shape[1], bool))
    assert not line.any()
    assert mark_cols(b, 0, 40, line, run, 41.0, 3) == len(run)
