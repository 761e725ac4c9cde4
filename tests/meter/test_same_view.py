"""A crop the fast path read and refused is not read again where the full search finds
the same rim: the search's crop would sample the image within half a pixel of the fast
path's (:data:`app.core.meter.search.SAME_VIEW_PX`), the same view resampled.  The
refusal stands and the learned fallback reads it, as it read it after the second pass."""

import numpy as np
import pytest

import app.core.meter.learned as learned
import app.core.meter.reader as reader
import app.core.meter.search as search
from app.core.meter import load_profile, read_gauge
from app.core.meter.dial import DialEllipse, rectify
from app.core.meter.search import SAME_VIEW_PX, view_shift_px
from sim_robot.gauge_scene import render_sample


def test_view_shift_is_the_crops_shift_in_pixels():
    base = np.zeros((300, 300), np.uint8)
    ell = DialEllipse(150.0, 150.0, 260.0, 260.0, 0.0, 0.9)
    _, m = rectify(base, ell)
    assert view_shift_px(m, m) == pytest.approx(0.0, abs=1e-9)
    _, moved = rectify(base, DialEllipse(150.3, 150.0, 260.0, 260.0, 0.0, 0.9))
    assert view_shift_px(m, moved) == pytest.approx(0.3 * 270.0 / 260.0, rel=0.02)
    _, wider = rectify(base, DialEllipse(150.0, 150.0, 262.6, 262.6, 0.0, 0.9))
    # 1 % larger: the corners, 150 px from the crop's centre, move by 1.5 px
    assert view_shift_px(m, wider) == pytest.approx(1.5, rel=0.02)
    assert view_shift_px(m, wider) > SAME_VIEW_PX


def _read_counting(monkeypatch, img, prof, same_view_px: float):
    finishes = []
    orig = reader._finish

    def counting(*a, **k):
        finishes.append(1)
        return orig(*a, **k)

    monkeypatch.setattr(reader, "_finish", counting)
    monkeypatch.setattr(search, "SAME_VIEW_PX", same_view_px)
    # (the dial search after the keypoints, as the rule was made: see
    # test_learned_before_retries.py for the keypoints read first)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)
    r = read_gauge(img, prof)
    monkeypatch.undo()
    return r, len(finishes)


def test_the_same_view_is_not_read_twice(monkeypatch):
    img, truth = render_sample("marine", "field", np.random.default_rng(3))
    prof = load_profile(truth["profile"])
    r, n = _read_counting(monkeypatch, img, prof, SAME_VIEW_PX)
    # every view read again, as before the rule
    r_again, n_again = _read_counting(monkeypatch, img, prof, -1.0)
    assert n_again == 2  # the fast path's crop, then the search's of the same rim
    assert n == 1
    assert r.value is not None and r.method == "keypoints"
    assert (r.value, r.confidence, r.method, r.error_bound_fs) == \
        (r_again.value, r_again.confidence, r_again.method, r_again.error_bound_fs)
    assert abs(r.value - truth["value"]) / truth["full_scale"] < 0.02
