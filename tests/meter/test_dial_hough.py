"""Whole frames whose dial rim no long edge contour holds (knurled bezels, glare across
the rim, brick walls whose edges are the longest): the rim is found from the circles of
the edges' gradient vote, refitted as ellipses, and the gauge is then read (or refused)
as any other."""

import cv2
import numpy as np
import pytest

from app.core.meter import dial, load_profile, read_gauge
from app.core.meter.dial import find_dial_candidates
from sim_robot.gauge_scene import render_sample

# nordic hard frames (knurled bezels on brick walls) that the contours alone miss
FRAMES = [("nordic", 6), ("nordic", 18), ("nordic", 26)]


def _frame(fam: str, k: int):
    return render_sample(fam, "hard", np.random.default_rng([11, k]))


@pytest.mark.parametrize("fam,k", FRAMES)
def test_a_rim_no_contour_holds_is_found_by_the_circles_vote(fam, k, monkeypatch):
    img, truth = _frame(fam, k)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    cands = find_dial_candidates(gray, min_fill=0.22)
    assert cands, "no dial found"
    px, py = truth["pivot_xy"]
    best = cands[0]
    # the rim's centre near the pivot (perspective moves it a little), its size a dial's
    assert np.hypot(best.cx - px, best.cy - py) < 0.06 * best.width
    assert 0.3 * img.shape[0] < best.width < 1.1 * img.shape[0]
    monkeypatch.setattr(dial, "_hough_rims", lambda *a: iter(()))
    assert find_dial_candidates(gray, min_fill=0.22) == []  # the contours alone: none


def test_the_vote_runs_only_where_the_contours_found_nothing(monkeypatch):
    img, _ = render_sample("plant", "hard", np.random.default_rng([11, 1]))
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    calls = []
    hough = dial._hough_rims
    monkeypatch.setattr(dial, "_hough_rims", lambda *a: calls.append(1) or hough(*a))
    assert find_dial_candidates(gray, min_fill=0.22)
    assert calls == []


def test_a_frame_found_so_is_read_within_its_stated_bound():
    img, truth = _frame("nordic", 6)
    r = read_gauge(img, load_profile(truth["profile"]))
    assert r.value is not None, r.error
    err = abs(r.value - truth["value"]) / truth["full_scale"] * 100
    assert err < 2.0 and (r.error_bound_fs is None or err <= r.error_bound_fs)
