"""Work the reader shares between its steps gives what each step would compute itself."""

import cv2
import numpy as np

from app.core.meter import load_profile
from app.core.meter.keypoints import _boxes
from app.core.meter.search import full_search
from sim_robot.gauge_scene import render_sample


def _frame(seed=4):
    rng = np.random.default_rng(seed)
    img, truth = render_sample("plant", "hard", rng)  # a whole camera frame, not a crop
    return img, load_profile(truth["profile"])


def test_keypoint_boxes_reuse_the_dial_search():
    img, prof = _frame()
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    assert abs(grey.shape[0] - grey.shape[1]) > 0.12 * max(grey.shape)
    found: dict = {}
    full_search(grey, False, prof, found)
    searched, min_fill, cands = found["dial_candidates"]
    assert searched is grey and len(cands) > 0
    assert _boxes(grey, found["dial_candidates"]) == _boxes(grey)


def test_keypoint_boxes_search_again_for_another_image():
    img, prof = _frame()
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    found: dict = {}
    full_search(grey, False, prof, found)
    other = np.ascontiguousarray(grey[:, ::-1])  # the same size, another picture
    assert _boxes(other, found["dial_candidates"]) == _boxes(other)
    assert _boxes(other, found["dial_candidates"]) != _boxes(grey)


def test_coarsest_comb_by_blocks_is_the_full_search():
    from app.core.meter.tick_comb import MIN_PITCH_DEG, R_MIN, _coarsest_comb

    rng = np.random.default_rng(7)
    for span in (90.0, 180.0, 240.0, 270.0, 300.0):
        for pitch in (1.5, 2.0, 2.5, 5.0, 9.0, 30.0):
            ticks = np.arange(0.0, span + 1e-9, pitch) + rng.normal(0, 0.15 * pitch / 5, 1)
            inside = np.sort(ticks[rng.random(len(ticks)) < 0.85] % 360.0)
            ns = np.arange(2, int(span / MIN_PITCH_DEG) + 1)
            z = np.exp(2j * np.pi * np.outer(ns, inside) / span).mean(axis=1)
            ok = np.flatnonzero(np.abs(z) >= R_MIN)
            want = (int(ns[ok[0]]), z[ok[0]]) if len(ok) else None
            assert _coarsest_comb(inside, span) == want
