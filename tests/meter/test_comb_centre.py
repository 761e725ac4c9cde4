"""The pivot refined from the ticks' comb (:mod:`app.core.meter.comb_centre`).

A circle fitted to the scale marks' ends slides along the gap's axis with its radius; a
centre off toward the gap turns both end marks inward and the arc looks shorter than the
profile's span.  The comb of evenly spaced ticks is bent by such an offset, and its fit
finds the pivot again."""

import math

import numpy as np
import pytest

from app.core.meter import angles, pointer, read_gauge
from app.core.meter.comb_centre import comb_centre
from app.core.meter.dial import FACE_RADIUS
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import DialStyle

PIVOT = (150.0, 150.0)


def _ring(tick_angles, r_ring=100.0, size=300) -> np.ndarray:
    dark = np.zeros((size, size), np.float32)
    for a in tick_angles:
        t = math.radians(a)
        for rr in np.arange(r_ring - 10, r_ring + 0.5, 0.5):
            for w in (-0.6, 0.0, 0.6):
                x = PIVOT[0] + rr * math.sin(t) + w * math.cos(t)
                y = PIVOT[1] - rr * math.cos(t) + w * math.sin(t)
                dark[int(round(y)), int(round(x))] = 200.0
    return dark


@pytest.mark.parametrize("off", [(0.0, 3.0), (-2.5, 1.5), (2.0, -2.0)])
def test_an_even_comb_brings_an_off_centre_back_to_the_pivot(off):
    dark = _ring(np.arange(-135.0, 135.01, 4.5))
    start = (PIVOT[0] + off[0], PIVOT[1] + off[1])
    got = comb_centre(dark, 50.0, start, FACE_RADIUS)
    assert got is not None
    (x, y), se, n = got
    assert math.dist((x, y), PIVOT) < 0.3, (x, y)
    assert se < 0.3 and n >= 40


def test_ticks_that_are_no_even_comb_give_no_centre():
    rng = np.random.default_rng(3)
    a = np.cumsum(rng.uniform(2.5, 7.5, 60)) - 135.0
    dark = _ring(a[a <= 135.0])
    assert comb_centre(dark, 50.0, (PIVOT[0], PIVOT[1] + 2.0), FACE_RADIUS) is None


def test_a_ring_centre_slid_toward_the_gap_no_longer_shortens_the_arc(monkeypatch):
    """The ring's circle fit made to land 2.5 px toward the scale's gap (as blur or ticks of
    two lengths make it on field images): about that centre both end marks lie a degree
    inward and the arc is refused as off the profile's span; the comb's centre reads it."""
    monkeypatch.setattr(pointer, "find_scale", lambda *a, **k: (None, "no tick marks found"))
    orig = angles.ring_centre

    def slid(*a, **k):
        f = orig(*a, **k)
        return None if f is None else ((f[0][0], f[0][1] + 2.5),) + tuple(f[1:])

    monkeypatch.setattr(angles, "ring_centre", slid)
    st = DialStyle(name="plant_0_10bar", min_angle_deg=-135.0, max_angle_deg=135.0,
                   min_value=0.0, max_value=10.0, major_step=1.0, minor_per_major=5)
    for value in (2.2, 7.9):
        img, _ = draw_dial(st, value, 300)
        r = read_gauge(img, st.profile())
        assert r.value is not None, r.error
        assert r.method == "profile-angles"
        assert abs(r.value - value) / 10.0 * 100 <= r.error_bound_fs
        assert math.dist(r.dial_centre_xy, PIVOT) < 0.6
