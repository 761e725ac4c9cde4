"""A streak of glare on a dark dial from the hub out across the rim, opposite a single
light needle: it reaches out to the scale like a second end.  A single needle has no
second end that long, so one of the two is something else; the streak is the thinner end
near the hub and over its outer half (a needle tapers from a wide root), so the widths,
which tell a needle's tip from its own tail, would take it for the tip.  It runs on past
the scale ring, where no needle reaches, and that decides (app.core.meter.needle,
``needle_ends.weigh_end_cues``, ``runs_on``)."""

import math

import cv2
import numpy as np
import pytest
from gauge_draw import C, base_profile, calibration, draw_face, draw_needle

from app.core.meter import load_profile, read_gauge

A_MIN, SPAN = -120.0, 240.0  # 0..80 kPa: the needle's opposite lies on the scale too


def _streak(img: np.ndarray, angle: float, width: float, strength: float) -> np.ndarray:
    """A band of glare from near the hub out past the rim at image angle ``angle``:
    I = I0 (1 - a) + 255 a, ``a`` falling off across the band and fading in near the hub."""
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]].astype(np.float32)
    t = math.radians(angle)
    dx, dy = math.sin(t), -math.cos(t)
    along = (xx - C) * dx + (yy - C) * dy
    across = (xx - C) * dy - (yy - C) * dx
    a = strength * np.exp(-0.5 * (across / width) ** 2) * np.clip((along - 15.0) / 15.0, 0, 1)
    out = img.astype(np.float32) * (1 - a[..., None]) + 255.0 * a[..., None]
    return np.clip(out, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("needle_deg", [82.0, -70.0, 20.0])
def test_a_glare_streak_opposite_the_needle_is_not_read_as_its_tip(needle_deg):
    img = draw_face(A_MIN, SPAN, face=(38, 46, 38), ink=(225, 228, 225))
    img = draw_needle(img, needle_deg, colour=(235, 235, 235), width=10.0, length=118,
                      tail=18.0)
    img = _streak(img, needle_deg + 180.0, 2.5, 0.75)
    img = cv2.GaussianBlur(img, (3, 3), 0)
    r = read_gauge(img, load_profile(base_profile(calibration=calibration(A_MIN,
                                                                          A_MIN + SPAN))))
    assert r.value == pytest.approx((needle_deg - A_MIN) / SPAN * 80.0, abs=0.005 * 80), \
        r.error
