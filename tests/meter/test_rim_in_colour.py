"""The dial's rim where the face and the background differ in colour, not in grey
(oblique.find_rectifier's colour channels)."""

import math

import cv2
import numpy as np

from app.core.meter.oblique import find_rectifier


def _tilted_dial(face_bgr, wall_bgr, seed=0):
    """A tilted dial (an ellipse, axes 200 x 150 px, turned 30 deg) with a ring of ticks
    on a plain wall, lightly noisy; its pivot and its scale ring's radius."""
    rng = np.random.default_rng(seed)
    img = np.zeros((400, 480, 3), np.uint8)
    img[:] = wall_bgr
    c, axes, turn = (240, 200), (100, 75), 30
    cv2.ellipse(img, c, axes, turn, 0, 360, face_bgr, -1, cv2.LINE_AA)
    for k in range(0, 271, 27):  # ticks on the face, at 0.8 of the rim
        t = math.radians(k - 135)
        u, v = math.sin(t), -math.cos(t)
        a = math.radians(turn)
        pts = []
        for r in (0.7, 0.8):
            x, y = r * axes[0] * u, r * axes[1] * v
            pts.append((int(round(c[0] + x * math.cos(a) - y * math.sin(a))),
                        int(round(c[1] + x * math.sin(a) + y * math.cos(a)))))
        cv2.line(img, pts[0], pts[1], (20, 20, 20), 2, cv2.LINE_AA)
    noisy = img.astype(np.float32) + rng.normal(0, 3.0, img.shape)
    return np.clip(noisy, 0, 255).astype(np.uint8), c, 0.8 * 87.0


def test_a_rim_of_like_grey_is_found_in_its_colour():
    # a blue face on a green wall: grey 78 against 71, blue 220 against 30
    img, pivot, radius = _tilted_dial((220, 60, 60), (30, 110, 10))
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    assert not find_rectifier(gray, pivot, radius).rim_seen  # grey alone: no rim
    rect = find_rectifier(gray, pivot, radius, img)
    assert rect.rim_seen and rect.ellipse is not None
    (ex, ey), (w, h), _ = rect.ellipse
    assert math.hypot(ex - pivot[0], ey - pivot[1]) < 3.0
    assert abs(min(w, h) / max(w, h) - 0.75) < 0.03
    # the rectified angles undo the tilt: the rim's ends of its axes lie 90 deg apart
    a = math.radians(30)
    ends = [(100 * math.cos(a), 100 * math.sin(a)), (-75 * math.sin(a), 75 * math.cos(a))]
    seen = [rect.angle(x, y) for x, y in ends]
    assert abs(((seen[1] - seen[0]) % 180.0) - 90.0) < 2.0


def test_a_face_that_stands_out_in_grey_is_found_as_before():
    img, pivot, radius = _tilted_dial((235, 235, 235), (40, 40, 40))
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    plain, coloured = find_rectifier(gray, pivot, radius), find_rectifier(gray, pivot, radius,
                                                                            img)
    assert plain.rim_seen and plain.ellipse == coloured.ellipse
