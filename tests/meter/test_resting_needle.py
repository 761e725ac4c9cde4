"""A needle resting on its stop pin just below the minimum mark: the tick behind the needle
(``end_marks.end_mark``'s ``"behind"``) and the reading's error bound clamped to the scale
(``angles._clamped_bound``)."""

import numpy as np
import pytest

from app.core.meter import load_profile, read_gauge
from app.core.meter.angles import _clamped_bound
from app.core.meter.arc_fit import SPAN_TOL_DEG, STEP, _ends_fit
from tests.meter.stored_frames import stored

N = int(round(360.0 / STEP))


def _ticks(start: float, span: float, n_int: int, rho: float) -> np.ndarray:
    """Evidence (one value per polar column): ``n_int + 1`` ticks 1 deg wide over the arc
    turned by ``rho``."""
    a = np.arange(N) * STEP
    e = np.zeros(N)
    for t in (start + rho + j * span / n_int for j in range(n_int + 1)):
        e = np.maximum(e, np.clip(1.0 - np.abs((a - t + 180) % 360 - 180), 0, 1))
    return e


def _needle(known: np.ndarray, at_deg: float, half_cols: int = 3) -> None:
    c = int(round((at_deg % 360.0) / STEP))
    for k in range(c - half_cols, c + half_cols + 1):
        known[k % N] = False


def test_the_bound_counts_only_the_doubt_that_reaches_inside_the_scale():
    span = 270.0
    # on the scale: the bound as it is
    assert _clamped_bound(0.5, 2.7, span) == pytest.approx(1.0)
    # 8.1 deg below the minimum, 2.7 deg of doubt: the minimum for sure (the least bound)
    assert _clamped_bound(-0.03, 2.7, span) == pytest.approx(100 * STEP / 2 / span)
    # 1.35 deg below the minimum, 2.7 deg of doubt: half of it reaches inside
    assert _clamped_bound(-0.005, 2.7, span) == pytest.approx(0.5)
    # beyond the maximum alike
    assert _clamped_bound(1.005, 2.7, span) == pytest.approx(0.5)


def test_a_tick_just_inside_the_needle_stands_for_its_end_when_the_other_end_agrees():
    start, span, rho = 225.0, 270.0, 3.0
    e = _ticks(start, span, 27, rho)
    known = np.ones(N, bool)
    _needle(known, start + rho - 4.0)  # on the stop pin, 4 deg below the minimum mark
    fit = _ends_fit(e, known, start, span, 25.0, rho + 1.0, 1.0)
    assert fit.rho_deg == pytest.approx(rho, abs=0.3)
    assert fit.ends == 2


def test_a_tick_inside_a_hidden_end_mark_is_not_taken_for_it():
    """The needle over the minimum mark itself: the first tick inside is 10 deg (a pitch)
    further on, which the other end mark does not confirm; that end is hidden."""
    start, span, rho = 225.0, 270.0, 3.0
    e = _ticks(start, span, 27, rho)
    known = np.ones(N, bool)
    _needle(known, start + rho + 7.0, half_cols=15)  # covers the minimum mark
    fit = _ends_fit(e, known, start, span, 25.0, rho + 1.0, 1.0)
    assert fit.ends == 1
    assert fit.rho_deg == pytest.approx(rho, abs=0.3)  # from the maximum mark alone
    # a finer scale: a tick 1 deg inside passes for the end mark, within the span's
    # tolerance, and turns the arc by no more than half of it
    e = _ticks(start, span, 270, rho)
    known = np.ones(N, bool)
    _needle(known, start + rho - 0.5, half_cols=2)
    fit = _ends_fit(e, known, start, span, 25.0, rho + 0.5, 1.0)
    assert fit.rho_deg is not None and abs(fit.rho_deg - rho) <= SPAN_TOL_DEG / 2 + STEP


def test_needles_at_rest_read_the_minimum_by_the_profiles_angles():
    """Field frames of the former held-out family atlas (as ``bench/meter_ab.py --families
    atlas --seed 3`` draws them, #73 and #102), the needle resting on its stop pin a few
    degrees below the minimum: the scale's ends left the exact angle in doubt, but not the
    reading; each is read by the profile's angles (the learned keypoints
    only confirming the needle's tip) as the minimum."""
    for i in (73, 102):
        img, truth = stored(f"atlas-field-3-{i}")
        prof = load_profile(truth["profile"])
        assert truth["value"] == prof.min_value
        r = read_gauge(img, prof)
        assert r.value is not None, (i, r.error)
        assert abs(r.value - truth["value"]) <= 0.005 * truth["full_scale"]
        assert r.method == "profile-angles"


def test_the_learned_keypoints_read_a_needle_on_its_stop_pin_as_the_minimum():
    """A hard atlas frame (``bench/meter_ab.py --families atlas --seed 3``, #152) read by
    the learned keypoints: the needle just below the minimum, its angle's doubt not
    reaching inside the scale."""
    img, truth = stored("atlas-hard-3-152")
    prof = load_profile(truth["profile"])
    assert truth["value"] == prof.min_value
    r = read_gauge(img, prof)
    assert r.value is not None, r.error
    assert abs(r.value - truth["value"]) <= 0.005 * truth["full_scale"]
    assert r.method == "keypoints"
