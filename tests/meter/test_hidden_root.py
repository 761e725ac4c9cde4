"""A needle whose root is hidden at the hub (:mod:`app.core.meter.hidden_root`): the pointer
step found no hub (a light hexagonal cap over the pivot, or a set-point pointer's ring hub
in the colour the profile ignores, erased to the face's grey, cutting the needle off), so
the pivot comes from the scale ring and the needle from its rays about it, and the
profile's angles read the dial.  Two `atlas` field crops of bench/meter_why.py's draw were
refused so before ("pointer line not found", "pointer hub not found"), and the learned
fallback refused them too."""

import math

import numpy as np

from app.core.meter import load_profile, read_gauge
from app.core.meter.hidden_root import pointer_about_ring
from tests.meter.stored_frames import fs_off, spy_angles, stored


def _read(name: str, monkeypatch):
    seen = spy_angles(monkeypatch)
    img, truth = stored(name)
    r = read_gauge(img, load_profile(truth["profile"]))
    return r, seen, truth


def test_a_needle_cut_off_at_a_ring_hub_of_the_ignored_colour_is_read(monkeypatch):
    # a red set-point pointer with a red ring hub over a black needle; red is ignored
    r, seen, truth = _read("atlas-field-2-6", monkeypatch)
    assert truth["profile"]["ignore_colour"] == "red"
    assert r.value is not None and r.method == "profile-angles"
    assert seen and "error" not in seen[-1]
    assert fs_off(r, truth) <= r.error_bound_fs < 0.625


def test_a_needle_under_a_light_hub_cap_is_read(monkeypatch):
    # a pale hexagonal cap over the pivot; the needle rests at the scale's minimum
    r, seen, truth = _read("atlas-field-3-35", monkeypatch)
    assert r.value is not None and r.method == "profile-angles"
    assert seen and "error" not in seen[-1]
    assert fs_off(r, truth) <= r.error_bound_fs < 0.625


def test_the_pivot_is_the_rings_centre_and_needs_the_learned_pivot():
    # a plain light face with a ring of ticks and a needle whose root a light disc hides
    img = np.full((300, 300), 225, np.uint8)
    c, r_ring = (150.0, 150.0), 110.0
    import cv2

    for k in range(31):  # a 240 deg scale, ticks every 8 deg
        a = math.radians(-120.0 + 8.0 * k)
        p0 = (c[0] + (r_ring - 12) * math.sin(a), c[1] - (r_ring - 12) * math.cos(a))
        p1 = (c[0] + r_ring * math.sin(a), c[1] - r_ring * math.cos(a))
        cv2.line(img, (round(p0[0]), round(p0[1])), (round(p1[0]), round(p1[1])), 20, 2)
    tip = (c[0] + 95 * math.sin(math.radians(40)), c[1] - 95 * math.cos(math.radians(40)))
    cv2.line(img, (150, 150), (round(tip[0]), round(tip[1])), 15, 3)
    cv2.circle(img, (150, 150), 14, 240, -1)  # the light cap over the needle's root
    cv2.circle(img, (150, 150), 14, 120, 1)
    prof = load_profile({"name": "t", "unit": "bar", "min_value": 0, "max_value": 10,
                         "min_angle_deg": -120, "max_angle_deg": 120, "needle": "single"})
    failed = {"error": "pointer hub not found"}
    # without the learned keypoints (the one estimate of the pivot along the needle) the
    # refusal stands
    assert pointer_about_ring(img, prof, failed) is failed

    class Kp:  # the learned pivot, near the ring's centre
        spread = np.array([8.0, 8.0, 8.0, 8.0])

        def __getitem__(self, name):
            return (151.0, 149.0)

    got = pointer_about_ring(img, prof, failed, lambda: Kp())
    assert math.dist(got["centre"], c) < 1.0 and got["hub_from"] == "ring"
    assert abs(((got["theta"] - 40.0 + 180.0) % 360.0) - 180.0) < 1.5

    class Far(Kp):  # a learned pivot far off the ring's centre: refused
        def __getitem__(self, name):
            return (175.0, 150.0)

    assert pointer_about_ring(img, prof, failed, lambda: Far()) is failed
