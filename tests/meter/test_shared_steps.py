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
