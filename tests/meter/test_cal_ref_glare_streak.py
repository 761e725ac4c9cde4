"""With a reference frame, a glare streak across an end mark's patch (in the frame or in
the reference) is left out of both patches on a second look, when what is left still pins
the mark along the arc: the end marks' check no longer refuses a warp that is right."""

import math

import cv2
import numpy as np
from stored_frames import fs_off, read_cal_ref

import app.core.meter.calibrated as calibrated
import app.core.meter.glare_streak as glare_streak
import app.core.meter.register_dense as rd
from app.core.meter.glare_streak import drop_along_arc, streak_mask

# `colour` PG-201: a glare streak across the frame's minimum mark (and its maximum's)
FRAME = "cal-ref-tuning-33-0-PG-201"
# `dark` PG-102: a broad glare band over the reference's end marks, a streak in the frame
BAND = "cal-ref-tuning-24-1-PG-102"
# `colour` PG-201: a streak across the reference's maximum mark and its end dot; the arc's
# line left beside it fits a warp turned about the pivot
TURNED = "cal-ref-tuning-18-2-PG-201"


def test_a_glare_streak_across_an_end_mark_is_left_out_of_the_check(monkeypatch):
    for name, tol in ((FRAME, 0.3), (BAND, 0.5)):
        r, truth = read_cal_ref(name)
        assert r.method == "calibrated-reference"
        assert r.value is not None and fs_off(r, truth) < tol, name
    # without the second look, the end marks' check refuses, as it did before
    monkeypatch.setattr(rd, "_lines_up_past_streak", lambda *a: False)
    for name in (FRAME, BAND):
        r, _ = read_cal_ref(name)
        assert r.value is None and "does not line up" in r.error, name


def _frame_warp(monkeypatch, name):
    got = []
    check = rd.check_landmarks

    def spy(gray, cal, h, hidden=None):
        out = check(gray, cal, h, hidden)
        got.append((gray, cal, h, hidden, out[0]))
        return out
    monkeypatch.setattr(calibrated, "check_landmarks", spy)
    read_cal_ref(name)
    return got[-1]


def _turned(cal, h, deg):
    t = math.radians(deg)
    cx, cy = cal.center
    rot = np.array([[math.cos(t), -math.sin(t), 0.0], [math.sin(t), math.cos(t), 0.0],
                    [0.0, 0.0, 1.0]])
    about = np.array([[1.0, 0.0, cx], [0.0, 1.0, cy], [0.0, 0.0, 1.0]])
    return h @ about @ rot @ np.linalg.inv(about)


def test_a_warp_turned_about_the_pivot_is_not_let_through_by_a_streak(monkeypatch):
    gray, cal, h, hidden, why = _frame_warp(monkeypatch, TURNED)
    assert why is None  # the right warp passes
    for deg in (-4.0, -3.0):
        bad = _turned(cal, h, deg)
        assert rd.check_landmarks(gray, cal, bad, hidden)[0] is not None
    # with the streak left out, only the arc's line is left by the maximum mark: it would
    # pass, but for the correlation's fall along the arc (and the streak, on a white face,
    # being no lighter than the face by LIGHTER)
    monkeypatch.setattr(rd, "ALONG_DROP", -math.inf)
    monkeypatch.setattr(glare_streak, "LIGHTER", 20.0)
    assert rd.check_landmarks(gray, cal, _turned(cal, h, -4.0), hidden)[0] is None
    monkeypatch.setattr(rd, "ALONG_DROP", 0.2)
    assert rd.check_landmarks(gray, cal, _turned(cal, h, -4.0), hidden)[0] is not None


def _dots(shift=0):
    img = np.full((61, 61), 120, np.uint8)
    for k in range(5):
        cv2.circle(img, (8 + 11 * k + shift, 30), 2, 30, -1)
    return img


def test_a_streak_is_long_light_in_one_image_only():
    a = _dots()
    yy, xx = np.mgrid[0:61, 0:61].astype(np.float32)
    alpha = 0.7 * np.exp(-0.5 * ((yy - 0.4 * xx - 10.0) / 3.0) ** 2)
    b = (a * (1 - alpha) + 255 * alpha).astype(np.uint8)
    m = streak_mask(b, a)
    assert m[int(round(10 + 0.4 * 30)), 30] and not m[50, 10]
    assert np.array_equal(streak_mask(a, b), m)  # in either image
    # print that moved (a warp off by a dot) is no streak, nor is a band no lighter than
    # the face (dark print the other image lacks)
    assert not streak_mask(_dots(5), a).any()
    c = a.copy()
    c[28:33, :] = 30
    assert not streak_mask(a, c).any()


def test_the_fall_along_the_arc():
    # a ridge along x (the arc's line, the mark above the pivot): no fall along it
    res = np.tile(np.array([0.2, 0.5, 0.9, 0.5, 0.2])[:, None], (1, 9))
    assert drop_along_arc(res, (4, 2), (100.0, 0.0), (100.0, 100.0), 3) < 0.01
    # a peak: a fall either way
    peak = np.zeros((9, 9))
    peak[4, 4] = 0.9
    assert drop_along_arc(peak, (4, 4), (100.0, 0.0), (100.0, 100.0), 3) > 0.8
