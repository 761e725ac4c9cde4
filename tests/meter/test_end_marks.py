"""The scale's end marks are found by their shape: a tick is a thin radial stroke; a
numeral printed beside an end tick is no end mark, and a thick end tick is placed by its
centre line, not its outer edge (:func:`app.core.meter.end_marks.mark_shape`)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from app.core.meter.arc_fit import fit_profile_arc

SIZE, C, R_RING = 300, (150.0, 150.0), 100.0
TURN = 7.0  # the dial's turn in the picture (deg, clockwise)


def _uneven(n: int = 34, seed: int = 0) -> list[float]:
    """Tick angles strewn over the inside of the arc at least 3 deg apart: an uneven
    scale (no comb of evenly spaced ticks), so that only its end marks place it."""
    rng = np.random.default_rng(seed)
    out: list[float] = []
    while len(out) < n:
        a = float(rng.uniform(-129.0, 129.0))
        if all(abs(a - b) >= 3.0 for b in out):
            out.append(a)
    return sorted(out)


INNER = _uneven()


def _p(a: float, r: float) -> tuple[int, int]:
    t = math.radians(a + TURN)
    return (int(round((C[0] + r * math.sin(t)) * 16)), int(round((C[1] - r * math.cos(t)) * 16)))


def _stroke(img: np.ndarray, a: float, width: int, length: float = 16.0) -> None:
    cv2.line(img, _p(a, R_RING - length), _p(a, R_RING), 255, width, cv2.LINE_AA, 4)


def _dial(end_width: int = 2) -> np.ndarray:
    """Darkness image: uneven ticks from -135 to +135 deg (upright), turned by TURN."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in INNER:
        _stroke(img, a, 2)
    for a in (-135.0, 135.0):
        _stroke(img, a, end_width)
    return img


def _fit(img: np.ndarray):
    return fit_profile_arc([(img, 50)], C, 135.0, None, -135.0 % 360.0, 270.0)


def test_the_plain_uneven_scale_is_placed_by_its_end_marks():
    fit = _fit(_dial())
    assert fit.method == "ends" and fit.ends == 2
    assert fit.rho_deg == pytest.approx(TURN, abs=0.5)


@pytest.mark.parametrize("text", ["0", "10"])
def test_a_numeral_beside_the_end_tick_is_not_taken_for_the_end_mark(text):
    """The numeral sits in the gap just outside the minimum's tick, on the ticks' radii
    (where the old reader took it for the end mark and refused the span)."""
    img = _dial()
    t = math.radians(-135.0 - 7.0 + TURN)
    x, y = C[0] + (R_RING - 8) * math.sin(t), C[1] - (R_RING - 8) * math.cos(t)
    (w, h), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 2)
    cv2.putText(img, text, (int(x - w / 2), int(y + h / 2)), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                255, 2, cv2.LINE_AA)
    fit = _fit(img)
    assert fit.rho_deg == pytest.approx(TURN, abs=0.5), fit
    assert fit.ends == 2


@pytest.mark.parametrize("width", [9, 11])
def test_a_thick_end_tick_is_placed_by_its_centre_line(width):
    """End ticks 9-11 px wide (5-6 deg at the ring, longer than a thin tick's run): their
    middle, not their outer edge, is the end of the scale."""
    fit = _fit(_dial(end_width=width))
    assert fit.rho_deg == pytest.approx(TURN, abs=0.5), fit
    assert fit.ends == 2 and abs(fit.mismatch_deg) < 1.0


def test_a_printed_arc_still_ends_at_its_outer_edge():
    """A printed arc (thin along the radius, long along the ring) is no stroke: the scale
    ends where it ends, half a stroke beyond its last tick, as before."""
    img = _dial()
    cv2.ellipse(img, (int(C[0] * 16), int(C[1] * 16)), (int(R_RING * 16), int(R_RING * 16)),
                0.0, -225.0 + TURN, 45.0 + TURN, 255, 3, cv2.LINE_AA, 4)
    fit = _fit(img)
    assert fit.rho_deg == pytest.approx(TURN, abs=1.0), fit


def test_end_marks_off_the_same_way_state_the_doubt_their_mismatch_cannot_show():
    """End marks that are dots with a tick beside them (the tick inside the arc at the
    minimum, outside it at the maximum): placed by the ticks, both ends are off the same
    way, which turns the scale without changing its span, so their mismatch stays near
    zero.  The fit must state that doubt (:attr:`ArcFit.ends_err_deg`), enough to cover
    the turn's error."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in INNER:
        if -127.0 < a < 127.0:
            _stroke(img, a, 2)
    off = 3.0
    for end, tick in ((-135.0, -135.0 + off), (135.0, 135.0 + off)):
        cv2.circle(img, _p(end, R_RING - 7.0), 6 * 16, 255, -1, cv2.LINE_AA, 4)
        _stroke(img, tick, 2)
    fit = _fit(img)
    assert fit.rho_deg is not None and fit.method == "ends" and fit.ends == 2
    err = abs(fit.rho_deg - TURN)
    assert err > 1.0  # the ticks, not the dots, placed the ends ...
    assert abs(fit.mismatch_deg) / 2.0 < err  # ... unseen by their mismatch
    stated = max(abs(fit.mismatch_deg) / 2.0, getattr(fit, "ends_err_deg", 0.0))
    assert err <= stated + 0.5, (err, stated)


def test_a_refused_span_keeps_the_turn_it_came_nearest_to():
    """The maximum's end tick drawn 5 deg beyond the profile's span: the fit is refused
    (the end marks disagree), and says the turn it would have taken, the two end marks'
    mean (half the 5 deg beyond the true turn), so a bench can tell what the refusal
    would have read."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in INNER:
        _stroke(img, a, 2)
    for a in (-135.0, 140.0):
        _stroke(img, a, 2)
    fit = _fit(img)
    assert fit.rho_deg is None and "off the profile's span" in (fit.error or ""), fit
    assert fit.mismatch_deg == pytest.approx(5.0, abs=0.6)
    assert fit.candidate_rho == pytest.approx(TURN + 2.5, abs=0.6)


def test_a_fit_refused_for_a_missing_end_mark_keeps_the_other_ends_turn():
    """No maximum end tick (the ticks stop 6 deg short of it, beyond the end mark search's
    gap): the refusal's candidate turn is the one the minimum's end mark gives."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in INNER:
        if a < 100.0:
            _stroke(img, a, 2)
    _stroke(img, -135.0, 2)
    fit = _fit(img)
    assert fit.rho_deg is None and "not found" in (fit.error or ""), fit
    assert fit.candidate_rho == pytest.approx(TURN, abs=0.6), fit
