"""A reference frame's rim on few of its rays that mixes two edges is weighed against no
correction and the other edges by how sharp the dial's circles are through each view
(:mod:`app.core.meter.rim_focus`)."""

import numpy as np
from stored_frames import fs_off, read_cal_ref

import app.core.meter.calibrated as calibrated
from app.core.meter.oblique import Rectifier, _stretch
from app.core.meter.rim_focus import focus, sharpest_rim

# `process` CG-301 seen head-on (0.02 deg of view): the reference's rim (78 of 96 rays)
# mixes two edges at an axis ratio of 0.958, 1.25 deg of view put in by its correction
FRAME = "cal-ref-tuning-27-4-CG-301"


def test_a_rim_that_blurs_the_dials_circles_gives_way(monkeypatch):
    r, truth = read_cal_ref(FRAME)
    assert r.value is not None and fs_off(r, truth) < 0.3
    # the mixed rim kept: its correction puts the view in the reading
    monkeypatch.setattr(calibrated, "sharpest_rim", lambda gray, piv, clicked, radius, rect: rect)
    r, truth = read_cal_ref(FRAME)
    assert r.value is not None and fs_off(r, truth) > 0.8


def _rings(ratio: float) -> np.ndarray:
    """Concentric dark rings on a light face, seen with an axis ratio ``ratio`` about 30 deg."""
    yy, xx = np.mgrid[0:240, 0:240].astype(float)
    m = _stretch(((120.0, 120.0), (200.0, 200.0 * ratio), 30.0))  # image -> dial
    dx, dy = xx - 120.0, yy - 120.0
    r = np.hypot(m[0, 0] * dx + m[0, 1] * dy, m[1, 0] * dx + m[1, 1] * dy)
    img = np.full(r.shape, 200.0)
    for ring in (60.0, 75.0, 90.0, 105.0):
        img[np.abs(r - ring) < 1.5] = 40.0
    return img.astype(np.uint8)


def test_circles_are_sharpest_through_the_right_view():
    img = _rings(0.95).astype(np.float32)
    right = _stretch(((120.0, 120.0), (200.0, 190.0), 30.0))
    wrong = _stretch(((120.0, 120.0), (200.0, 190.0), 120.0))
    s_right = focus(img, (120.0, 120.0), 80.0, right, (0.0, 0.0))
    assert s_right > focus(img, (120.0, 120.0), 80.0, np.eye(2), (0.0, 0.0))
    assert s_right > focus(img, (120.0, 120.0), 80.0, wrong, (0.0, 0.0))


def test_a_rim_on_most_of_its_rays_is_kept():
    ell = ((120.0, 120.0), (200.0, 190.0), 120.0)
    rect = Rectifier(_stretch(ell), ell, 0.95, 0.95)
    assert sharpest_rim(_rings(1.0), (120.0, 120.0), (120.0, 120.0), 80.0, rect) is rect


def test_a_rim_on_few_rays_that_blurs_round_circles_gives_way():
    ell = ((120.0, 120.0), (200.0, 190.0), 120.0)
    rect = Rectifier(_stretch(ell), ell, 0.95, 0.6)
    got = sharpest_rim(_rings(1.0), (120.0, 120.0), (120.0, 120.0), 80.0, rect)
    s = np.linalg.svd(got.a, compute_uv=False)
    assert got is not rect and s[1] / s[0] > 0.99
